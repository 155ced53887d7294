// The vectorised parallel bond: parallel_bond.cpp's kinematics() and loads() (whose comments
// derive the formulas) over vectors of bonds. Compiled once per instruction set by Highway's
// foreach_target; HWY_DYNAMIC_DISPATCH picks the widest the CPU has at run time.
//
// What differs from the scalar form, all exact up to round-off:
// - the two bodies' positions and quaternions are gathered per lane (GatherIndex), the rest
//   state is loaded from structure-of-arrays;
// - no branches: the rotation log always takes its small-angle series; lanes beyond the series'
//   range (s² ≥ 0.0025 w², |θ| ≳ 0.1 rad), with no bond axis (|m|² ≤ 1e-24) or with a NaN are
//   flagged and left to the scalar code;
// - one square root and one divide per lane: d = 1/(w |m|) gives both 1/w = |m| d and
//   1/|m| = w d.
#include "force/bond/bond_simd.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "force/bond/bond_simd.cpp"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"

HWY_BEFORE_NAMESPACE();
namespace mdem::bond_simd {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<double>;
using V = hn::Vec<D>;
using DI = hn::RebindToSigned<D>;
using VI = hn::Vec<DI>;

#include "force/bond/triple-inl.h"  // NOLINT: per target, inside HWY_NAMESPACE
using V3 = Triple<V>;
// Fields f, f + 1, f + 2 of a vector of bonds (f at base + f·kMaxLanes).
HWY_INLINE V3 load3(D d, const double* base, int f) {
  return {hn::LoadU(d, base + f * kMaxLanes), hn::LoadU(d, base + (f + 1) * kMaxLanes),
          hn::LoadU(d, base + (f + 2) * kMaxLanes)};
}

// The rotation matrix of a unit quaternion (the scalar Rot's formula).
struct M3 {
  V m00, m01, m02, m10, m11, m12, m20, m21, m22;
  HWY_INLINE M3(D d, V w, V x, V y, V z) {
    const V one = hn::Set(d, 1.0);
    const V tx = x + x, ty = y + y, tz = z + z;
    const V twx = tx * w, twy = ty * w, twz = tz * w, txx = tx * x, txy = ty * x, txz = tz * x,
            tyy = ty * y, tyz = tz * y, tzz = tz * z;
    m00 = one - (tyy + tzz);
    m01 = txy - twz;
    m02 = txz + twy;
    m10 = txy + twz;
    m11 = one - (txx + tzz);
    m12 = tyz - twx;
    m20 = txz - twy;
    m21 = tyz + twx;
    m22 = one - (txx + tyy);
  }
  HWY_INLINE V3 operator*(const V3& v) const {
    return {m00 * v.x + m01 * v.y + m02 * v.z, m10 * v.x + m11 * v.y + m12 * v.z,
            m20 * v.x + m21 * v.y + m22 * v.z};
  }
};

struct Q {
  V w;
  V3 v;
};
// Hamilton product a b.
HWY_INLINE Q mul(const Q& a, const Q& b) {
  return {a.w * b.w - dot(a.v, b.v), a.w * b.v + b.w * a.v + cross(a.v, b.v)};
}

// A quaternion gathered from Eigen's layout (x, y, z, w) at element offsets i4 = 4·index.
HWY_INLINE Q gather_q(D d, const double* q, VI i4) {
  return {
      hn::GatherIndex(d, q + 3, i4),
      {hn::GatherIndex(d, q, i4), hn::GatherIndex(d, q + 1, i4), hn::GatherIndex(d, q + 2, i4)}};
}
HWY_INLINE V3 gather_x(D d, const double* x, VI i3) {
  return {hn::GatherIndex(d, x, i3), hn::GatherIndex(d, x + 1, i3), hn::GatherIndex(d, x + 2, i3)};
}

HWY_INLINE void store3(D d, const V3& a, double* x, double* y, double* z, std::size_t o) {
  hn::StoreU(a.x, d, x + o);
  hn::StoreU(a.y, d, y + o);
  hn::StoreU(a.z, d, z + o);
}

// Per-lane running sums of the four energies.
struct Energies {
  V tension, shear, bending, torsion;
};

// One vector of bonds at k = begin + o; returns the mask of lanes for the scalar code, and adds
// the other lanes' energies to e.
HWY_INLINE std::uint64_t lanes(const Rest& r, const Bodies& b, std::size_t k, std::size_t o,
                               Out& out, Energies& e) {
  const D d;
  const DI di;
  const V zero = hn::Zero(d), one = hn::Set(d, 1.0), half = hn::Set(d, 0.5);

  const std::size_t block = k / kMaxLanes, lane = k % kMaxLanes;
  const double* rest = r.field + block * kFields * kMaxLanes + lane;
  auto field = [&](int f) { return hn::LoadU(d, rest + f * kMaxLanes); };
  const std::int64_t* index = r.index + 2 * block * kMaxLanes + lane;
  const VI ii = hn::LoadU(di, index), jj = hn::LoadU(di, index + kMaxLanes);
  V3 xi, xj;
  Q qi, qj;
  // A vector of one tube's consecutive bonds (i, i + 1), (i + 1, i + 2), ...: its bodies lie
  // side by side in memory, loaded as such (the same doubles) rather than by 14 gathers.
  const std::int64_t i0 = hn::GetLane(ii);
  const VI run = hn::Iota(di, i0);
  if (hn::AllTrue(di, hn::And(hn::Eq(ii, run), hn::Eq(jj, run + hn::Set(di, 1))))) {
    hn::LoadInterleaved3(d, b.x + 3 * i0, xi.x, xi.y, xi.z);
    hn::LoadInterleaved3(d, b.x + 3 * (i0 + 1), xj.x, xj.y, xj.z);
    hn::LoadInterleaved4(d, b.q + 4 * i0, qi.v.x, qi.v.y, qi.v.z, qi.w);
    hn::LoadInterleaved4(d, b.q + 4 * (i0 + 1), qj.v.x, qj.v.y, qj.v.z, qj.w);
  } else {
    xi = gather_x(d, b.x, ii + hn::ShiftLeft<1>(ii));
    xj = gather_x(d, b.x, jj + hn::ShiftLeft<1>(jj));
    qi = gather_q(d, b.q, hn::ShiftLeft<2>(ii));
    qj = gather_q(d, b.q, hn::ShiftLeft<2>(jj));
  }
  if (b.periodic) {  // Domain::image: x_j less whole box lengths (0 on open axes)
    xj.x = xj.x - hn::Set(d, b.length[0]) * hn::Round((xj.x - xi.x) * hn::Set(d, b.inv_length[0]));
    xj.y = xj.y - hn::Set(d, b.length[1]) * hn::Round((xj.y - xi.y) * hn::Set(d, b.inv_length[1]));
    xj.z = xj.z - hn::Set(d, b.length[2]) * hn::Round((xj.z - xi.z) * hn::Set(d, b.inv_length[2]));
  }

  // Kinematics.
  const M3 Ri(d, qi.w, qi.v.x, qi.v.y, qi.v.z), Rj(d, qj.w, qj.v.x, qj.v.y, qj.v.z);
  const V3 ai = Ri * load3(d, rest, kCix);
  const V3 aj = Rj * load3(d, rest, kCjx);
  const V3 ui = Ri * load3(d, rest, kNix);
  const V3 uj = Rj * load3(d, rest, kNjx);
  const V3 m = ui + uj;
  const V m2 = dot(m, m);
  const V3 g = (xj + aj) - (xi + ai);

  // Relative rotation q_j q_rel0⁻¹ q_i⁻¹, the shortest one (w ≥ 0).
  const Q p = {field(kPw), load3(d, rest, kPx)};
  Q rq = mul(mul(qj, p), Q{qi.w, {hn::Neg(qi.v.x), hn::Neg(qi.v.y), hn::Neg(qi.v.z)}});
  const auto flip = hn::Lt(rq.w, zero);
  const V w = hn::IfThenElse(flip, hn::Neg(rq.w), rq.w);
  const V3 v = {hn::IfThenElse(flip, hn::Neg(rq.v.x), rq.v.x),
                hn::IfThenElse(flip, hn::Neg(rq.v.y), rq.v.y),
                hn::IfThenElse(flip, hn::Neg(rq.v.z), rq.v.z)};
  const V s2 = dot(v, v);
  // Both comparisons are false for a NaN, so such a lane goes to the scalar code too.
  const auto ok = hn::And(hn::Lt(s2, hn::Set(d, 0.0025) * w * w), hn::Gt(m2, hn::Set(d, 1e-24)));

  const V sm = hn::Sqrt(m2);
  const V dv = one / (w * sm);
  const V iw = sm * dv, inv_m = w * dv;
  const V3 n = inv_m * m;

  // The rotation log's series (rotation_log in parallel_bond.cpp).
  const V u = s2 * iw * iw;
  V poly = hn::Set(d, 1.0 / 13);
  poly = hn::MulAdd(u, poly, hn::Set(d, -1.0 / 11));
  poly = hn::MulAdd(u, poly, hn::Set(d, 1.0 / 9));
  poly = hn::MulAdd(u, poly, hn::Set(d, -1.0 / 7));
  poly = hn::MulAdd(u, poly, hn::Set(d, 1.0 / 5));
  poly = hn::MulAdd(u, poly, hn::Set(d, -1.0 / 3));
  poly = hn::MulAdd(u, poly, one);
  const V3 th = (hn::Set(d, 2.0) * poly * iw) * v;
  const V a2 = hn::Set(d, 4.0) * u * poly * poly;
  V c = hn::Set(d, 1.0 / 47900160);
  c = hn::MulAdd(a2, c, hn::Set(d, 1.0 / 1209600));
  c = hn::MulAdd(a2, c, hn::Set(d, 1.0 / 30240));
  c = hn::MulAdd(a2, c, hn::Set(d, 1.0 / 720));
  c = hn::MulAdd(a2, c, hn::Set(d, 1.0 / 12));

  // Loads (loads() in parallel_bond.cpp).
  const V kn_a = field(kKnArea), ks_a = field(kKsArea);
  const V kn_i = field(kKnInertia), ks_j = field(kKsPolar);
  const V gn = dot(g, n);
  const V3 gs = g - gn * n;
  const V tn = dot(th, n);
  const V3 tb = th - tn * n;
  e.tension = e.tension + hn::IfThenElseZero(ok, half * kn_a * gn * gn);
  e.shear = e.shear + hn::IfThenElseZero(ok, half * ks_a * dot(gs, gs));
  e.bending = e.bending + hn::IfThenElseZero(ok, half * kn_i * dot(tb, tb));
  e.torsion = e.torsion + hn::IfThenElseZero(ok, half * ks_j * tn * tn);

  const V kg = (kn_a - ks_a) * gn;
  const V kt = (ks_j - kn_i) * tn;
  const V3 dU_dg = ks_a * g + kg * n;
  const V3 dU_dth = kn_i * th + kt * n;
  const V3 dU_dn = kg * g + kt * th;
  const V3 dU_dm = inv_m * (dU_dn - dot(n, dU_dn) * n);
  const V3 pr = cross(th, dU_dth);
  const V3 sym = dU_dth + c * cross(th, pr);
  const V3 ti = (cross(ai, dU_dg) - cross(ui, dU_dm)) + (sym - half * pr);
  const V3 tj = (cross(dU_dg, aj) - cross(uj, dU_dm)) - (sym + half * pr);
  store3(d, dU_dg, out.fx, out.fy, out.fz, o);
  store3(d, ti, out.tix, out.tiy, out.tiz, o);
  store3(d, tj, out.tjx, out.tjy, out.tjz, o);

  std::uint8_t bits[8] = {0};
  hn::StoreMaskBits(d, hn::Not(ok), bits);
  return std::uint64_t{bits[0]} << o;
}

std::uint64_t Evaluate(const Rest& r, const Bodies& b, std::size_t begin, std::size_t n, Out& out) {
  const D d;
  std::uint64_t scalar = 0;
  Energies e{hn::Zero(d), hn::Zero(d), hn::Zero(d), hn::Zero(d)};
  for (std::size_t o = 0; o < n; o += hn::Lanes(d)) scalar |= lanes(r, b, begin + o, o, out, e);
  out.e_tension = hn::GetLane(hn::SumOfLanes(d, e.tension));
  out.e_shear = hn::GetLane(hn::SumOfLanes(d, e.shear));
  out.e_bending = hn::GetLane(hn::SumOfLanes(d, e.bending));
  out.e_torsion = hn::GetLane(hn::SumOfLanes(d, e.torsion));
  return scalar;
}

const char* TargetName() { return hwy::TargetName(HWY_TARGET); }

}  // namespace HWY_NAMESPACE
}  // namespace mdem::bond_simd
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mdem::bond_simd {

HWY_EXPORT(Evaluate);
HWY_EXPORT(TargetName);

std::uint64_t evaluate(const Rest& r, const Bodies& b, std::size_t begin, std::size_t n, Out& out) {
  static_assert(HWY_MAX_BYTES / sizeof(double) <= kMaxLanes);
  static_assert(kChunk % kMaxLanes == 0 && kChunk <= 64);
  return HWY_DYNAMIC_DISPATCH(Evaluate)(r, b, begin, n, out);
}

const char* target_name() { return HWY_DYNAMIC_DISPATCH(TargetName)(); }

}  // namespace mdem::bond_simd
#endif
