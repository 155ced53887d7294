// The neighbour-list build's candidate test over vectors (cell_scan_simd.h). Compiled once per
// instruction set by Highway's foreach_target and without contraction of multiplies and adds
// (CMakeLists.txt), so every target computes d and |d|² with the same roundings as the scalar
// loop it replaced, and lists the same pairs.
#include "neighbor/cell_scan_simd.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "neighbor/cell_scan_simd.cpp"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"

HWY_BEFORE_NAMESPACE();
namespace mdem::cell_scan {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<double>;
using V = hn::Vec<D>;

// d − L·nearbyint(d/L), as Domain::delta; d itself along an open axis (L = 0: d − 0·0 = d).
HWY_INLINE V minimum_image(V d, V length, V inv_length) {
  return hn::Sub(d, hn::Mul(length, hn::Round(hn::Mul(d, inv_length))));
}

template <bool kPeriodic, bool kAnyJ>
HWY_INLINE std::uint32_t* scan_runs(const Cells& c, const Probe& p, const std::uint32_t* begin,
                                    const std::uint32_t* end, int runs, std::uint32_t* out) {
  const D d;
  const std::size_t N = hn::Lanes(d);
  const V xi = hn::Set(d, p.x), yi = hn::Set(d, p.y), zi = hn::Set(d, p.z);
  const V r2 = hn::Set(d, p.range2);
  const V lx = hn::Set(d, p.length[0]), ly = hn::Set(d, p.length[1]), lz = hn::Set(d, p.length[2]);
  const V ilx = hn::Set(d, p.inv_length[0]), ily = hn::Set(d, p.inv_length[1]),
          ilz = hn::Set(d, p.inv_length[2]);
  const hn::Rebind<std::uint32_t, D> du;
  const auto iv = hn::Set(du, p.i);
  for (int r = 0; r < runs; ++r) {
    const std::uint32_t kb = begin[r], ke = end[r];
    for (std::uint32_t k = kb; k < ke; k += static_cast<std::uint32_t>(N)) {
      V dx = hn::Sub(hn::LoadU(d, c.x + k), xi);
      V dy = hn::Sub(hn::LoadU(d, c.y + k), yi);
      V dz = hn::Sub(hn::LoadU(d, c.z + k), zi);
      if constexpr (kPeriodic) {
        dx = minimum_image(dx, lx, ilx);
        dy = minimum_image(dy, ly, ily);
        dz = minimum_image(dz, lz, ilz);
      }
      const V s = hn::Add(hn::Add(hn::Mul(dx, dx), hn::Mul(dy, dy)), hn::Mul(dz, dz));
      const auto near = hn::And(hn::Lt(s, r2), hn::FirstN(d, ke - k));
      // The lanes kept, as indices: j > i (any j with kAnyJ) among those within range, packed
      // to the front of a vector that is stored whole (the caller's room covers a vector past
      // the last kept).
      std::uint8_t bits[8] = {};
      hn::StoreMaskBits(d, near, bits);
      const auto j = hn::LoadU(du, c.elem + k);
      auto keep = hn::LoadMaskBits(du, bits);
      if constexpr (!kAnyJ) keep = hn::And(keep, hn::Gt(j, iv));
      hn::StoreU(hn::Compress(j, keep), du, out);
      out += hn::CountTrue(du, keep);
    }
  }
  return out;
}

std::uint32_t* Scan(const Cells& c, const Probe& p, const std::uint32_t* begin,
                    const std::uint32_t* end, int runs, std::uint32_t* out) {
  const bool periodic = p.length[0] != 0.0 || p.length[1] != 0.0 || p.length[2] != 0.0;
  if (p.any_j)
    return periodic ? scan_runs<true, true>(c, p, begin, end, runs, out)
                    : scan_runs<false, true>(c, p, begin, end, runs, out);
  return periodic ? scan_runs<true, false>(c, p, begin, end, runs, out)
                  : scan_runs<false, false>(c, p, begin, end, runs, out);
}

const char* TargetName() { return hwy::TargetName(HWY_TARGET); }

}  // namespace HWY_NAMESPACE
}  // namespace mdem::cell_scan
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mdem::cell_scan {

HWY_EXPORT(Scan);
HWY_EXPORT(TargetName);

std::uint32_t* scan(const Cells& c, const Probe& p, const std::uint32_t* begin,
                    const std::uint32_t* end, int runs, std::uint32_t* out) {
  static_assert(HWY_MAX_BYTES / sizeof(double) <= kPad);
  return HWY_DYNAMIC_DISPATCH(Scan)(c, p, begin, end, runs, out);
}

const char* target_name() { return HWY_DYNAMIC_DISPATCH(TargetName)(); }

}  // namespace mdem::cell_scan
#endif
