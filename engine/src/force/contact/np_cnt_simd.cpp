// The vectorised NP–CNT law: NpCntKernel::law (np_cnt_contact.cpp) over vectors of pairs, compiled
// once per instruction set by Highway's foreach_target and dispatched at run time.
//
// What differs from the scalar form, all exact up to round-off:
// - no branches: the power law and its linear continuation below d_min are both computed (the
//   power law at max(D, d_min), so no lane takes the log of D ≤ 0) and selected per lane, and
//   lanes beyond the cutoff are zeroed by a mask;
// - D^−α and D^−β from one Log and two Exp rather than two pow() calls;
// - the smoothstep is evaluated at t clamped to [0, 1], which gives exactly f_c = 1, 0 and f_c' = 0
//   outside the ramp, as the scalar branches do.
#include "force/contact/np_cnt_simd.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "force/contact/np_cnt_simd.cpp"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"
// After highway.h, per target (its include guard toggles with the target).
#include "hwy/contrib/math/math-inl.h"

HWY_BEFORE_NAMESPACE();
namespace mdem::np_cnt_simd {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<double>;
using V = hn::Vec<D>;

HWY_INLINE bool lanes(const Constants& k, const Lanes& l, std::size_t o) {
  const D d;
  const V one = hn::Set(d, 1.0), two = hn::Set(d, 2.0), zero = hn::Zero(d);

  const V rx = hn::LoadU(d, l.dx + o), ry = hn::LoadU(d, l.dy + o), rz = hn::LoadU(d, l.dz + o);
  const V bx = hn::LoadU(d, l.bx + o), by = hn::LoadU(d, l.by + o), bz = hn::LoadU(d, l.bz + o);

  const V R2 = hn::MulAdd(rx, rx, hn::MulAdd(ry, ry, rz * rz));
  const auto beyond = hn::Ge(R2, hn::Set(d, k.cutoff2));  // a NaN is not beyond: it propagates
  const bool coincident = !hn::AllFalse(d, hn::Lt(R2, hn::Set(d, 1e-24)));

  const V R = hn::Sqrt(R2);
  const V inv_R = one / R;
  const V nx = rx * inv_R, ny = ry * inv_R, nz = rz * inv_R;
  const V c = hn::MulAdd(bx, nx, hn::MulAdd(by, ny, bz * nz));

  // δ and dδ/du at u = c² (vdw_shape::DeltaPolynomial, y = 2u − 1).
  const auto& a = k.delta;
  const V y = hn::MulSub(two, c * c, one);
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
  const V delta_u = two * dy;

  const V inv_delta = one / delta;
  const V ar = hn::Set(d, k.inv_rho) * inv_delta;  // ∂D/∂R = 1/(ρ δ)
  const V Dv = hn::MulSub(R, ar, two);

  // V(D), V'(D): the power law at max(D, d_min), the linear branch below d_min.
  const V dmin = hn::Set(d, k.d_min);
  const V Dc = hn::Max(Dv, dmin);
  const V L = hn::Log(d, Dc);
  const V pa = hn::Exp(d, hn::Set(d, -k.alpha) * L);
  const V pb = hn::Exp(d, hn::Set(d, -k.beta) * L);
  const V four_eps = hn::Set(d, k.four_eps);
  const V vA = hn::Set(d, k.A) * pa, vB = hn::Set(d, k.B) * pb;
  const V v_pow = four_eps * (vA - vB);
  const V dv_pow = four_eps * hn::MulAdd(hn::Set(d, -k.alpha), vA, hn::Set(d, k.beta) * vB) / Dc;
  const auto on_power = hn::Ge(Dv, dmin);
  const V v = hn::IfThenElse(on_power, v_pow,
                             hn::MulAdd(hn::Set(d, k.dv_min), Dv - dmin, hn::Set(d, k.v_min)));
  const V dv = hn::IfThenElse(on_power, dv_pow, hn::Set(d, k.dv_min));

  // f_c(R) = 1 − t²(3 − 2t), f_c' = 6t(t − 1)/width, t = (R − start)/width in [0, 1].
  const V width = hn::Set(d, k.fc_width);
  const V t = hn::Min(hn::Max((R - hn::Set(d, k.fc_start)) / width, zero), one);
  const V fc = hn::NegMulAdd(t * t, hn::NegMulAdd(two, t, hn::Set(d, 3.0)), one);
  const V dfc = hn::Set(d, 6.0) * t * (t - one) / width;

  const V energy = fc * v;
  const V U_R = hn::MulAdd(dfc, v, fc * dv * ar);
  const V U_u = hn::Neg(fc * dv * (Dv + two) * delta_u * inv_delta);
  const V two_c_Uu = two * c * U_u;
  // g = U_R n + 2c U_u (b − c n)/R; the NP's force −g, the segment's torque −2c U_u (b × n).
  const V s = two_c_Uu * inv_R;
  const V gn = hn::NegMulAdd(s, c, U_R);  // coefficient of n
  const V fx = hn::Neg(hn::MulAdd(gn, nx, s * bx));
  const V fy = hn::Neg(hn::MulAdd(gn, ny, s * by));
  const V fz = hn::Neg(hn::MulAdd(gn, nz, s * bz));
  const V tx = hn::Neg(two_c_Uu * hn::MulSub(by, nz, bz * ny));
  const V ty = hn::Neg(two_c_Uu * hn::MulSub(bz, nx, bx * nz));
  const V tz = hn::Neg(two_c_Uu * hn::MulSub(bx, ny, by * nx));

  hn::StoreU(hn::IfThenZeroElse(beyond, energy), d, l.e + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, fx), d, l.fx + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, fy), d, l.fy + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, fz), d, l.fz + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, tx), d, l.tx + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, ty), d, l.ty + o);
  hn::StoreU(hn::IfThenZeroElse(beyond, tz), d, l.tz + o);
  return coincident;
}

bool Evaluate(const Constants& k, const Lanes& l, std::size_t n) {
  const std::size_t step = hn::Lanes(D());
  bool coincident = false;
  for (std::size_t o = 0; o < n; o += step) coincident |= lanes(k, l, o);
  return coincident;
}

const char* TargetName() { return hwy::TargetName(HWY_TARGET); }

}  // namespace HWY_NAMESPACE
}  // namespace mdem::np_cnt_simd
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mdem::np_cnt_simd {

HWY_EXPORT(Evaluate);
HWY_EXPORT(TargetName);

bool evaluate(const Constants& k, const Lanes& l, std::size_t n) {
  static_assert(HWY_MAX_BYTES / sizeof(double) <= kMaxLanes);
  return HWY_DYNAMIC_DISPATCH(Evaluate)(k, l, n);
}

const char* target_name() { return HWY_DYNAMIC_DISPATCH(TargetName)(); }

}  // namespace mdem::np_cnt_simd
#endif
