// The vectorised anisotropic vdW pair kernel: the scalar kernel's eval_pair (anisotropic_vdw.cpp,
// whose file comment derives the formulas) over vectors of pairs. Compiled once per instruction
// set by Highway's foreach_target; HWY_DYNAMIC_DISPATCH picks the widest the CPU has at run time,
// so the portable build uses AVX-512 or AVX2 where present.
//
// What differs from the scalar form, all exact up to round-off:
// - no branches: both sides of every case (linear overlap branch / Lennard-Jones branch, inside /
//   outside the cutoff ramp, above / below W's knee, inside / outside the flip-blend window) are
//   computed and selected per lane; lanes beyond the cutoff are zeroed by a mask;
// - the divides and square roots run side by side rather than one after another (the kernel was
//   waiting on their latency): g0 = 1/(R² (1 + |c|)) next to R = √R² gives 1/R and
//   1/(2(1 + |c|)); g = 1/(δ m), m = δ max(D, d_min), next to √(δ m) gives 1/δ, 1/max(D, d_min)
//   and max(D, d_min)^-1.5; the flip-blend window's 1/(1 ± c) share one divide;
// - D + 2 in ∂U/∂u is taken as X/δ (as in the scalar kernel), not as D + 2, which cancels;
// - the cutoff smoothstep is evaluated at t clamped to [0, 1], which gives exactly f_c = 1, 0 and
//   f_c' = 0 outside the ramp;
// - the second signed cos²θ and the blend are computed only for vectors with a lane in the
//   flip-blend window.
#include "force/contact/vdw_simd.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "force/contact/vdw_simd.cpp"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"

HWY_BEFORE_NAMESPACE();
namespace mdem::vdw_simd {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<double>;
using V = hn::Vec<D>;

// u = cos²θ and its partials in (p1, p2, c) for one flip sign s = ±1, given inv_h = 1/(2(1 + s c)).
struct CosTheta2 {
  V u, u_p1, u_p2, u_c;
};
HWY_INLINE CosTheta2 signed_u(D d, V s, V p1, V p2, V inv_h) {
  const V q = hn::MulAdd(s, p2, p1);
  const V u = q * q * inv_h;
  const V u_p1 = hn::Set(d, 2.0) * q * inv_h;
  return {u, u_p1, s * u_p1, hn::Set(d, -2.0) * s * u * inv_h};
}

template <bool kPfc>
HWY_INLINE bool lanes(const VdwConstants& k, const Lanes& l, std::size_t o) {
  const D d;
  const VdwParams& p = k.p;
  const V one = hn::Set(d, 1.0), two = hn::Set(d, 2.0), zero = hn::Zero(d);

  const V rx = hn::LoadU(d, l.rx + o), ry = hn::LoadU(d, l.ry + o), rz = hn::LoadU(d, l.rz + o);
  const V ax = hn::LoadU(d, l.ax + o), ay = hn::LoadU(d, l.ay + o), az = hn::LoadU(d, l.az + o);
  const V bx = hn::LoadU(d, l.bx + o), by = hn::LoadU(d, l.by + o), bz = hn::LoadU(d, l.bz + o);

  const V R2 = hn::MulAdd(rx, rx, hn::MulAdd(ry, ry, rz * rz));
  // Beyond the cutoff: zeroed at the end (a NaN is not "beyond", so it propagates).
  const auto beyond = hn::Ge(R2, hn::Set(d, k.cutoff2));
  const bool coincident = !hn::AllFalse(d, hn::Lt(R2, hn::Set(d, 1e-24)));
  const V c = hn::MulAdd(ax, bx, hn::MulAdd(ay, by, az * bz));
  const V one_minus_c2 = hn::NegMulAdd(c, c, one);

  // 1/R and 1/(2(1 + |c|)), the signed cos²θ's denominator, from one divide g0 = 1/(R² h) that
  // runs alongside the square root R = √R² (not after it): 1/R = R h g0, 1/(2h) = R² g0 / 2.
  const V R = hn::Sqrt(R2);
  const V h = one + hn::Abs(c);
  const V g0 = one / (R2 * h);
  const V inv_R = R * h * g0;
  const V inv_h = hn::Set(d, 0.5) * R2 * g0;
  const V nx = rx * inv_R, ny = ry * inv_R, nz = rz * inv_R;
  const V p1 = hn::MulAdd(ax, nx, hn::MulAdd(ay, ny, az * nz));
  const V p2 = hn::MulAdd(bx, nx, hn::MulAdd(by, ny, bz * nz));

  // cos²θ with the model's flip s = sign(c) (+1 for c = 0), blended near c = 0 (flip_blend).
  const V s = hn::IfThenElse(hn::Lt(c, zero), hn::Neg(one), one);
  CosTheta2 ct = signed_u(d, s, p1, p2, inv_h);
  const double blend = p.flip_blend;
  if (blend > 0.0) {
    const auto window = hn::AndNot(beyond, hn::Lt(hn::Abs(c), hn::Set(d, blend)));
    if (!hn::AllFalse(d, window)) {
      const V half = hn::Set(d, 0.5);
      // 1/(2(1 ± c)) from one divide (|c| < blend ≤ 0.5 here, so (1 + c)(1 − c) loses nothing).
      const V g = half / ((one + c) * (one - c));
      const CosTheta2 a = signed_u(d, one, p1, p2, (one - c) * g);
      const CosTheta2 b = signed_u(d, hn::Neg(one), p1, p2, (one + c) * g);
      const V t = (c + hn::Set(d, blend)) * hn::Set(d, 0.5 / blend);
      const V w = t * t * hn::NegMulAdd(two, t, hn::Set(d, 3.0));
      const V dw = hn::Set(d, 3.0) * t * (one - t) * hn::Set(d, 1.0 / blend);
      const V du = a.u - b.u;
      ct.u = hn::IfThenElse(window, hn::MulAdd(w, du, b.u), ct.u);
      ct.u_p1 = hn::IfThenElse(window, hn::MulAdd(w, a.u_p1 - b.u_p1, b.u_p1), ct.u_p1);
      ct.u_p2 = hn::IfThenElse(window, hn::MulAdd(w, a.u_p2 - b.u_p2, b.u_p2), ct.u_p2);
      ct.u_c =
          hn::IfThenElse(window, hn::MulAdd(w, a.u_c - b.u_c, hn::MulAdd(dw, du, b.u_c)), ct.u_c);
    }
  }

  // δ(θ) and dδ/du: the degree-5 polynomial in y = cos 2θ = 2u − 1.
  const auto& a = k.delta_poly;
  const V y = hn::MulSub(two, ct.u, one);
  const V delta = hn::MulAdd(
      y,
      hn::MulAdd(
          y,
          hn::MulAdd(
              y, hn::MulAdd(y, hn::MulAdd(y, hn::Set(d, a[5]), hn::Set(d, a[4])), hn::Set(d, a[3])),
              hn::Set(d, a[2])),
          hn::Set(d, a[1])),
      hn::Set(d, a[0]));
  const V dy =
      hn::MulAdd(y,
                 hn::MulAdd(y,
                            hn::MulAdd(y, hn::MulAdd(y, hn::Set(d, 5 * a[5]), hn::Set(d, 4 * a[4])),
                                       hn::Set(d, 3 * a[3])),
                            hn::Set(d, 2 * a[2])),
                 hn::Set(d, a[1]));
  const V ddelta_du = two * dy;
  const V inv_r = hn::Set(d, k.inv_r);
  // D = X/δ − 2 with X = R/r, and 1/δ, 1/max(D, d_min), max(D, d_min)^-1.5 from one divide and
  // one square root of p = δ m, m = max(X − 2δ, d_min δ) = δ max(D, d_min) (δ > 0), side by
  // side: g = 1/p, 1/δ = g m, 1/max(D, d_min) = g δ², max(D, d_min)^-1.5 = δ³ g² √p.
  const V d_min = hn::Set(d, p.d_min);
  const V m_raw = hn::NegMulAdd(two, delta, R * inv_r);  // X − 2δ = δ D
  const V m = hn::Max(m_raw, d_min * delta);
  const V pm = delta * m;
  const V g = one / pm;
  const V sq = hn::Sqrt(pm);
  const V inv_delta = g * m;
  const V dd = m_raw * inv_delta;  // D

  // V(D), V'(D): Lennard-Jones branch at max(D, d_min) (D^-9.5 = D^-8 · D^-1.5, D^-4), the
  // linear continuation below d_min.
  const V delta2 = delta * delta;
  const V inv = g * delta2;
  const V inv2 = inv * inv;
  const V inv4 = inv2 * inv2;
  const V da = inv4 * inv4 * ((delta2 * delta) * (g * g) * sq);
  const V four_eps = hn::Set(d, k.four_eps);
  const V v_lj = four_eps * (hn::Set(d, p.A) * da - hn::Set(d, p.B) * inv4);
  const V dv_lj =
      four_eps * (hn::Set(d, p.beta * p.B) * inv4 - hn::Set(d, p.alpha * p.A) * da) * inv;
  const auto lj_branch = hn::Ge(dd, d_min);
  const V v = hn::IfThenElse(lj_branch, v_lj,
                             hn::MulAdd(hn::Set(d, k.dv_dmin), dd - d_min, hn::Set(d, k.v_dmin)));
  const V dv = hn::IfThenElse(lj_branch, dv_lj, hn::Set(d, k.dv_dmin));

  // Smoothstep cutoff from 3T to 4T.
  const V inv_T = hn::Set(d, k.inv_T);
  const V tc = hn::Min(hn::Max(hn::MulSub(R, inv_T, hn::Set(d, 3.0)), zero), one);
  const V fc = hn::NegMulAdd(tc * tc, hn::NegMulAdd(two, tc, hn::Set(d, 3.0)), one);
  const V dfc = hn::Set(d, 6.0) * tc * (tc - one) * inv_T;

  // W(R) = w_prefactor ρ^-7.5 above the knee, constant below.
  const V rinv = hn::Set(d, p.radius) * inv_R;  // 1/ρ
  const V rinv2 = rinv * rinv;
  const V w_far = hn::Set(d, p.w_prefactor) * (rinv2 * rinv2) * rinv2 * hn::Sqrt(rinv2 * rinv);
  const auto above_knee = hn::Gt(R * inv_r, hn::Set(d, p.w_knee));
  const V w = hn::IfThenElse(above_knee, w_far, hn::Set(d, k.w_knee_value));
  const V dw = hn::IfThenElseZero(above_knee, hn::Set(d, -p.w_exponent) * w_far * inv_R);

  const V M = hn::MulAdd(two * w, one_minus_c2, one);
  const V mfc = M * fc;
  const V energy = mfc * v;
  const V dM_dR = two * dw * one_minus_c2;
  const V dM_dc = hn::Set(d, -4.0) * w * c;
  const V U_R = hn::MulAdd(dM_dR * fc + M * dfc, v, mfc * dv * inv_r * inv_delta);
  // D + 2 = X/δ taken as such: D + 2 cancels to a few digits where R → 0 (D → −2).
  const V U_u = hn::Neg(mfc * dv * (R * inv_r * inv_delta) * inv_delta * ddelta_du);
  const V U_p1 = U_u * ct.u_p1, U_p2 = U_u * ct.u_p2;
  const V U_cM = dM_dc * fc * v;
  const V U_c = hn::MulAdd(U_u, ct.u_c, U_cM);

  // dU/dr = U_R n + ((U_p1 b1 + U_p2 b2) − (U_p1 p1 + U_p2 p2) n) / R; f on segment 1 = +dU/dr.
  const V pn = hn::MulAdd(U_p1, p1, U_p2 * p2);
  const V gn = hn::NegMulAdd(pn, inv_R, U_R);  // coefficient of n
  const V fx = hn::MulAdd(gn, nx, hn::MulAdd(U_p1, ax, U_p2 * bx) * inv_R);
  const V fy = hn::MulAdd(gn, ny, hn::MulAdd(U_p1, ay, U_p2 * by) * inv_R);
  const V fz = hn::MulAdd(gn, nz, hn::MulAdd(U_p1, az, U_p2 * bz) * inv_R);

  // b1 × b2, and (Exact) b1 × n, b2 × n.
  const V cx = hn::MulSub(ay, bz, az * by), cy = hn::MulSub(az, bx, ax * bz),
          cz = hn::MulSub(ax, by, ay * bx);
  V t1x, t1y, t1z, t2x, t2y, t2z;
  if constexpr (kPfc) {
    t1x = hn::Neg(U_cM * cx);
    t1y = hn::Neg(U_cM * cy);
    t1z = hn::Neg(U_cM * cz);
    t2x = U_cM * cx;
    t2y = U_cM * cy;
    t2z = U_cM * cz;
  } else {
    const V an_x = hn::MulSub(ay, nz, az * ny), an_y = hn::MulSub(az, nx, ax * nz),
            an_z = hn::MulSub(ax, ny, ay * nx);
    const V bn_x = hn::MulSub(by, nz, bz * ny), bn_y = hn::MulSub(bz, nx, bx * nz),
            bn_z = hn::MulSub(bx, ny, by * nx);
    t1x = hn::Neg(hn::MulAdd(U_c, cx, U_p1 * an_x));
    t1y = hn::Neg(hn::MulAdd(U_c, cy, U_p1 * an_y));
    t1z = hn::Neg(hn::MulAdd(U_c, cz, U_p1 * an_z));
    t2x = hn::NegMulAdd(U_p2, bn_x, U_c * cx);
    t2y = hn::NegMulAdd(U_p2, bn_y, U_c * cy);
    t2z = hn::NegMulAdd(U_p2, bn_z, U_c * cz);
  }

  hn::StoreU(hn::IfThenZeroElse(beyond, energy), d, l.e + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, fx), d, l.fx + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, fy), d, l.fy + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, fz), d, l.fz + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, t1x), d, l.t1x + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, t1y), d, l.t1y + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, t1z), d, l.t1z + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, t2x), d, l.t2x + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, t2y), d, l.t2y + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, t2z), d, l.t2z + o);
  return coincident;
}

bool Evaluate(const VdwConstants& k, const Lanes& l, std::size_t n) {
  const std::size_t step = hn::Lanes(D());
  bool coincident = false;
  if (k.p.torque == VdwTorque::Pfc) {
    for (std::size_t o = 0; o < n; o += step) coincident |= lanes<true>(k, l, o);
  } else {
    for (std::size_t o = 0; o < n; o += step) coincident |= lanes<false>(k, l, o);
  }
  return coincident;
}

const char* TargetName() { return hwy::TargetName(HWY_TARGET); }

}  // namespace HWY_NAMESPACE
}  // namespace mdem::vdw_simd
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mdem::vdw_simd {

HWY_EXPORT(Evaluate);
HWY_EXPORT(TargetName);

bool evaluate(const VdwConstants& k, const Lanes& l, std::size_t n) {
  static_assert(HWY_MAX_BYTES / sizeof(double) <= kMaxLanes);
  return HWY_DYNAMIC_DISPATCH(Evaluate)(k, l, n);
}

const char* target_name() { return HWY_DYNAMIC_DISPATCH(TargetName)(); }

}  // namespace mdem::vdw_simd
#endif
