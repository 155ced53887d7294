// Nanoparticle–nanoparticle contact (model.md §5): a central force from U(R) = f_c(R) V(R/r − 2).
#include "mdem/force/contact/np_np_contact.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "force/contact/np_cnt_simd.h"

namespace mdem {

namespace {

constexpr double kCoincident2 = 1e-24;  // R² below which the centres count as coincident (nm²)

void require_positive(double v, const char* field) {
  if (!std::isfinite(v) || !(v > 0))
    throw std::invalid_argument(std::string("NP-NP contact ") + field +
                                " must be finite and > 0 (nm), got " + std::to_string(v));
}

}  // namespace

NpNpKernel::NpNpKernel(NpNpParams p, NpNpEvaluation e)
    : p_(p),
      eval_(e),
      fc_{p.taper_start, p.taper_width},
      v_("NP-NP contact", p.epsilon, p.A, p.B, p.alpha, p.beta, p.d_min) {
  require_positive(p.radius, "radius");
  require_positive(p.taper_start, "taper_start");
  require_positive(p.taper_width, "taper_width");
  v_(p.d_min, v_min_, dv_min_);
}

void NpNpKernel::batch(const Elements&, PairBatch& b) const {
  constexpr int kCap = PairBatch::kCapacity;
  constexpr int kWidth = static_cast<int>(np_cnt_simd::kMaxLanes);
  static_assert(kCap % kWidth == 0);
  // The NP–CNT law's d = x_NP − x_seg is the batch's d = x_j − x_i: its "NP" is j, its force
  // −(force on i). Any unit axis serves (δ does not depend on it); padding lanes lie beyond the
  // cutoff and give zeros.
  alignas(64) double dx[kCap], dy[kCap], dz[kCap], bx[kCap], by[kCap], bz[kCap];
  alignas(64) double e[kCap], fx[kCap], fy[kCap], fz[kCap], tx[kCap], ty[kCap], tz[kCap];
  const int lanes = (b.n + kWidth - 1) / kWidth * kWidth;
  for (int p = 0; p < lanes; ++p) {
    const bool pair = p < b.n;
    dx[p] = pair ? b.dx[p] : 2.0 * p_.cutoff();
    dy[p] = pair ? b.dy[p] : 0.0;
    dz[p] = pair ? b.dz[p] : 0.0;
    bx[p] = 1.0;
    by[p] = bz[p] = 0.0;
  }
  const np_cnt_simd::Constants k = np_cnt_simd::constants_of(
      p_, fc_.start, fc_.width, 1.0 / p_.radius, {1.0, 0.0, 0.0, 0.0, 0.0, 0.0},  // δ ≡ 1
      v_min_, dv_min_);
  const np_cnt_simd::Lanes l{dx, dy, dz, bx, by, bz, e, fx, fy, fz, tx, ty, tz};
  const bool coincident = np_cnt_simd::evaluate(k, l, static_cast<std::size_t>(lanes));
  for (int p = 0; p < b.n; ++p) {
    if (coincident && dx[p] * dx[p] + dy[p] * dy[p] + dz[p] * dz[p] < kCoincident2) {
      PairForces r;
      evaluate(Vec3(dx[p], dy[p], dz[p]), r);
      b.store(p, r);
      continue;
    }
    b.energy[p] = e[p];
    b.fx[p] = -fx[p];
    b.fy[p] = -fy[p];
    b.fz[p] = -fz[p];
    b.t1x[p] = b.t1y[p] = b.t1z[p] = 0.0;
    b.t2x[p] = b.t2y[p] = b.t2z[p] = 0.0;
  }
}

bool NpNpKernel::evaluate(const Vec3& d, PairForces& out) const {
  const double R2 = d.squaredNorm();
  const double cut = p_.cutoff();
  if (!(R2 < cut * cut)) return false;  // (a NaN fails this test and propagates below)
  if (R2 < kCoincident2) {
    out.energy = v_(-2.0);
    return true;
  }
  const double R = std::sqrt(R2);
  const double a = 1.0 / p_.radius;  // ∂D/∂R
  double v, dv, fc, dfc;
  v_(R * a - 2.0, v, dv);
  fc_(R, fc, dfc);
  out.energy = fc * v;
  const double dU = dfc * v + fc * dv * a;
  out.f2 = (-dU / R) * d;
  out.f1 = -out.f2;
  return true;
}

double NpNpKernel::energy(double R) const {
  PairForces r;
  evaluate(Vec3(R, 0, 0), r);
  return r.energy;
}

void NpNpKernel::stiffness(const Elements&, std::size_t i, std::size_t j, const Vec3& d,
                           StiffnessSums& s) const {
  const double R = d.norm();
  if (!(R < p_.cutoff())) return;
  const double a = 1.0 / p_.radius;
  s.add_pair(i, j, vdw_shape::radial_stiffness_bound(fc_, v_, R, R * a - 2.0, a), 0.0, 0.0);
}

double NpNpKernel::equilibrium_stiffness() const {
  return v_.second(v_.minimum()) / (p_.radius * p_.radius);
}

double NpNpKernel::equilibrium_distance() const { return p_.radius * (v_.minimum() + 2.0); }

template class PairModel<NpNpKernel>;

}  // namespace mdem
