// The vectorised CNT contact dashpot: the scalar kernel's force (viscous_contact_damping.cpp)
// over lanes of pairs, normal-only or with the shear part. One divide per lane serves 1/|r|² and
// 1/(m1 + m2): q = 1/(|r|² (m1 + m2)), so
// (r·u)/|r|² · √(k m1 m2/(m1 + m2)) = (r·u) q √(k m1 m2 (m1 + m2)).
#include "force/damping/dashpot_simd.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "force/damping/dashpot_simd.cpp"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"

HWY_BEFORE_NAMESPACE();
namespace mdem::dashpot_simd {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<double>;
using V = hn::Vec<D>;

template <bool kShear>
HWY_INLINE void EvaluateLanes(double ratio, double stiffness, const Lanes& l, std::size_t n) {
  const D d;
  const V two_ratio = hn::Set(d, 2.0 * ratio), k = hn::Set(d, stiffness), zero = hn::Zero(d);
  for (std::size_t o = 0; o < n; o += hn::Lanes(d)) {
    const V rx = hn::LoadU(d, l.rx + o), ry = hn::LoadU(d, l.ry + o), rz = hn::LoadU(d, l.rz + o);
    const V ux = hn::LoadU(d, l.ux + o), uy = hn::LoadU(d, l.uy + o), uz = hn::LoadU(d, l.uz + o);
    const V m1 = hn::LoadU(d, l.m1 + o), m2 = hn::LoadU(d, l.m2 + o);
    const V r2 = hn::MulAdd(rx, rx, hn::MulAdd(ry, ry, rz * rz));
    const V ru = hn::MulAdd(rx, ux, hn::MulAdd(ry, uy, rz * uz));
    const V msum = m1 + m2;
    const V q = hn::Set(d, 1.0) / (r2 * msum);
    const V c = two_ratio * hn::Sqrt(k * m1 * m2 * msum);  // 2ψ√(k m_eff) · (m1 + m2)
    // r = 0: no centre line, no force (q is infinite there).
    if constexpr (kShear) {  // c q r² = 2ψ√(k m_eff)
      const V s = hn::IfThenZeroElse(hn::Eq(r2, zero), c * q * r2);
      hn::StoreU(s * ux, d, l.fx + o);
      hn::StoreU(s * uy, d, l.fy + o);
      hn::StoreU(s * uz, d, l.fz + o);
    } else {
      const V s = hn::IfThenZeroElse(hn::Eq(r2, zero), c * ru * q);
      hn::StoreU(s * rx, d, l.fx + o);
      hn::StoreU(s * ry, d, l.fy + o);
      hn::StoreU(s * rz, d, l.fz + o);
    }
  }
}

void Evaluate(double ratio, double stiffness, bool shear, const Lanes& l, std::size_t n) {
  if (shear)
    EvaluateLanes<true>(ratio, stiffness, l, n);
  else
    EvaluateLanes<false>(ratio, stiffness, l, n);
}

const char* TargetName() { return hwy::TargetName(HWY_TARGET); }

}  // namespace HWY_NAMESPACE
}  // namespace mdem::dashpot_simd
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mdem::dashpot_simd {

HWY_EXPORT(Evaluate);
HWY_EXPORT(TargetName);

void evaluate(double ratio, double stiffness, bool shear, const Lanes& l, std::size_t n) {
  static_assert(HWY_MAX_BYTES / sizeof(double) <= kMaxLanes);
  HWY_DYNAMIC_DISPATCH(Evaluate)(ratio, stiffness, shear, l, n);
}

const char* target_name() { return HWY_DYNAMIC_DISPATCH(TargetName)(); }

}  // namespace mdem::dashpot_simd
#endif
