// Nanoparticle–CNT segment contact (model.md §5).
//
// Gradient (tensile.md §2.3). With c = b·n, u = c², δ = δ(u), δ_u = dδ/du, D = R/(ρ δ) − 2:
//   U_R = f_c' V + f_c V' / (ρ δ)              (∂U/∂R at fixed u)
//   U_u = −f_c V' (D + 2) δ_u / δ              (∂U/∂u at fixed R; ∂D/∂δ = −(D + 2)/δ)
//   g   = ∂U/∂x_NP = U_R n + 2c U_u (b − c n)/R
//   F_NP = −g,  F_seg = +g,  τ_seg = −b × ∂U/∂b = −2c U_u (b × n),  τ_NP = 0
// (a rotation δφ of the segment moves b by δφ × b, so δU = δφ · (b × ∂U/∂b), ∂U/∂b = 2c U_u n).
// Linear and angular momentum balance: F_NP + F_seg = 0 and d × F_NP + τ_seg = 0, since
// d × g = 2c U_u n × b. U depends on b only through c², so it is even in b (no axis flip needed).
#include "mdem/force/contact/np_cnt_contact.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "force/contact/np_cnt_simd.h"

namespace mdem {

namespace {

constexpr double kCoincident2 = 1e-24;  // R² below which the centres count as coincident (nm²)

}  // namespace

NpCntKernel::NpCntKernel(NpCntParams p, NpCntEvaluation e)
    : p_(p),
      eval_(e),
      delta_(p.C),
      fc_{3.0 * p.segment_length, p.segment_length},
      v_("NP-CNT contact", p.epsilon, p.A, p.B, p.alpha, p.beta, p.d_min) {
  if (!std::isfinite(p.rho) || !(p.rho > 0))
    throw std::invalid_argument("NP-CNT contact rho must be finite and > 0 (nm), got " +
                                std::to_string(p.rho));
  if (!std::isfinite(p.segment_length) || !(p.segment_length > 0))
    throw std::invalid_argument("NP-CNT contact segment_length must be finite and > 0 (nm), got " +
                                std::to_string(p.segment_length));
  v_(p.d_min, v_min_, dv_min_);
}

bool NpCntKernel::law(const Vec3& d, const Vec3& b, double& energy, Vec3& f_np, Vec3& t_seg) const {
  const double R2 = d.squaredNorm();
  const double cut = p_.cutoff();
  if (!(R2 < cut * cut)) return false;  // (a NaN fails this test and propagates below)
  if (R2 < kCoincident2) {
    energy = v_(-2.0);  // f_c(0) = 1, D = −2 whatever θ
    f_np = Vec3::Zero();
    t_seg = Vec3::Zero();
    return true;
  }
  const double R = std::sqrt(R2);
  const double inv_R = 1.0 / R;
  const Vec3 n = d * inv_R;
  const double c = b.dot(n);
  double delta, delta_u;
  delta_(c * c, delta, delta_u);
  const double a = 1.0 / (p_.rho * delta);  // ∂D/∂R
  const double D = R * a - 2.0;
  double v, dv, fc, dfc;
  v_(D, v, dv);
  fc_(R, fc, dfc);
  energy = fc * v;
  const double U_R = dfc * v + fc * dv * a;
  const double U_u = -fc * dv * (D + 2.0) * delta_u / delta;
  const double two_c_Uu = 2.0 * c * U_u;
  const Vec3 g = U_R * n + two_c_Uu * inv_R * (b - c * n);
  f_np = -g;
  t_seg = -two_c_Uu * b.cross(n);
  return true;
}

double NpCntKernel::separation(const Vec3& x_np, const Vec3& x_seg, const Vec3& b) const {
  const Vec3 d = x_np - x_seg;
  const double R2 = d.squaredNorm();
  if (R2 < kCoincident2) return -2.0;
  const double R = std::sqrt(R2);
  const double c = b.dot(d) / R;
  return R / (p_.rho * delta_(c * c)) - 2.0;
}

PairForces NpCntKernel::evaluate(const Vec3& x_np, const Vec3& x_seg, const Vec3& b) const {
  PairForces r;
  if (law(x_np - x_seg, b, r.energy, r.f1, r.t2)) r.f2 = -r.f1;
  return r;
}

bool NpCntKernel::pair(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                       PairForces& out) const {
  // d = x_j − x_i; the law wants x_NP − x_seg.
  if (el.kind[i] == ElementKind::Nanoparticle) {
    if (!law(-d, el.axis(j), out.energy, out.f1, out.t2)) return false;
    out.f2 = -out.f1;
  } else {
    if (!law(d, el.axis(i), out.energy, out.f2, out.t1)) return false;
    out.f1 = -out.f2;
  }
  return true;
}

void NpCntKernel::batch(const Elements& el, PairBatch& b) const {
  constexpr int kCap = PairBatch::kCapacity;
  constexpr int kWidth = static_cast<int>(np_cnt_simd::kMaxLanes);
  static_assert(kCap % kWidth == 0);
  // The law's d = x_NP − x_seg and the segment's axis per lane; the batch's d is x_j − x_i.
  alignas(64) double dx[kCap], dy[kCap], dz[kCap], bx[kCap], by[kCap], bz[kCap];
  alignas(64) double e[kCap], fx[kCap], fy[kCap], fz[kCap], tx[kCap], ty[kCap], tz[kCap];
  bool np_is_i[kCap];
  for (int p = 0; p < b.n; ++p) {
    const bool np_i = el.kind[b.i[p]] == ElementKind::Nanoparticle;
    np_is_i[p] = np_i;
    const double s = np_i ? -1.0 : 1.0;
    dx[p] = s * b.dx[p];
    dy[p] = s * b.dy[p];
    dz[p] = s * b.dz[p];
    const Vec3 axis = el.axis(np_i ? b.j[p] : b.i[p]);
    bx[p] = axis.x();
    by[p] = axis.y();
    bz[p] = axis.z();
  }
  const int lanes = (b.n + kWidth - 1) / kWidth * kWidth;
  for (int p = b.n; p < lanes; ++p) {  // padding: beyond the cutoff, zero outputs
    dx[p] = 2.0 * p_.cutoff();
    dy[p] = dz[p] = 0.0;
    bx[p] = 1.0;
    by[p] = bz[p] = 0.0;
  }
  const auto& a = delta_.coefficients();
  const np_cnt_simd::Constants k =
      np_cnt_simd::constants_of(p_, fc_.start, fc_.width, 1.0 / p_.rho, a, v_min_, dv_min_);
  const np_cnt_simd::Lanes l{dx, dy, dz, bx, by, bz, e, fx, fy, fz, tx, ty, tz};
  const bool coincident = np_cnt_simd::evaluate(k, l, static_cast<std::size_t>(lanes));
  for (int p = 0; p < b.n; ++p) {
    if (coincident && dx[p] * dx[p] + dy[p] * dy[p] + dz[p] * dz[p] < kCoincident2) {
      PairForces r;
      pair(el, b.i[p], b.j[p], Vec3(b.dx[p], b.dy[p], b.dz[p]), r);
      b.store(p, r);
      continue;
    }
    // Force on i: the NP's when i is the NP, the segment's (−) otherwise; the torque is the
    // segment's, on whichever of i, j it is.
    const double s = np_is_i[p] ? 1.0 : -1.0;
    b.energy[p] = e[p];
    b.fx[p] = s * fx[p];
    b.fy[p] = s * fy[p];
    b.fz[p] = s * fz[p];
    double* const seg[3] = {np_is_i[p] ? b.t2x : b.t1x, np_is_i[p] ? b.t2y : b.t1y,
                            np_is_i[p] ? b.t2z : b.t1z};
    double* const np[3] = {np_is_i[p] ? b.t1x : b.t2x, np_is_i[p] ? b.t1y : b.t2y,
                           np_is_i[p] ? b.t1z : b.t2z};
    seg[0][p] = tx[p];
    seg[1][p] = ty[p];
    seg[2][p] = tz[p];
    np[0][p] = np[1][p] = np[2][p] = 0.0;
  }
}

const char* np_cnt_simd_target() { return np_cnt_simd::target_name(); }

void NpCntKernel::stiffness(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                            StiffnessSums& s) const {
  const double R = d.norm();
  if (!(R < p_.cutoff())) return;
  const std::size_t seg = el.kind[i] == ElementKind::CntSegment ? i : j;
  const double c = R > 0 ? std::abs(el.axis(seg).dot(d)) / R : 0.0;
  const double delta = delta_(c * c), delta_lo = delta_.min_delta();
  const double a = 1.0 / (p_.rho * delta), a_lo = 1.0 / (p_.rho * delta_lo);
  const double kt = std::max(vdw_shape::radial_stiffness_bound(fc_, v_, R, R * a - 2.0, a),
                             vdw_shape::radial_stiffness_bound(fc_, v_, R, R * a_lo - 2.0, a_lo));
  s.kt[i] += kt;
  s.kt[j] += kt;
  // Turning the segment by φ changes D by at most (D + 2)·g·2|c|·φ ≤ 2g·R a·φ (g = max |δ_u|/δ):
  // the angle acts like a radial displacement of lever arm 2gR. Rotational bound kt·(2gR)², its
  // coupling kt·2gR, plus the first-order term 2|U_u| of ∂²U/∂c².
  const double arm = 2.0 * delta_.max_log_slope() * R;
  double v, dv, fc, dfc;
  v_(R * a - 2.0, v, dv);
  fc_(R, fc, dfc);
  s.kr[seg] += kt * arm * arm + 2.0 * std::abs(fc * dv) * R * a * delta_.max_log_slope();
  s.ktr[seg] += kt * arm;
}

double NpCntKernel::equilibrium_stiffness() const {
  return v_.second(v_.minimum()) / (p_.rho * p_.rho);
}

template class PairModel<NpCntKernel>;

}  // namespace mdem
