#include "mdem/force/damping/dashpot_law.h"

#include "force/damping/dashpot_simd.h"

namespace mdem {

// The batch's pairs gathered into SoA lanes (relative velocities and masses beside the driver's
// displacements), padded with r = 0 lanes (zero force) to a whole number of vectors.
void dashpot_batch(const Elements& el, PairBatch& b, double ratio, double stiffness, bool shear) {
  constexpr int kCap = PairBatch::kCapacity;
  constexpr int kVec = static_cast<int>(dashpot_simd::kMaxLanes);
  static_assert(kCap % kVec == 0);
  alignas(64) double ux[kCap], uy[kCap], uz[kCap], m1[kCap], m2[kCap];
  for (int p = 0; p < b.n; ++p) {
    const Vec3 u = el.v[b.j[p]] - el.v[b.i[p]];
    ux[p] = u.x();
    uy[p] = u.y();
    uz[p] = u.z();
    m1[p] = el.mass[b.i[p]];
    m2[p] = el.mass[b.j[p]];
  }
  const int lanes = (b.n + kVec - 1) / kVec * kVec;
  for (int p = b.n; p < lanes; ++p) {
    b.dx[p] = b.dy[p] = b.dz[p] = 0.0;
    ux[p] = uy[p] = uz[p] = 0.0;
    m1[p] = m2[p] = 1.0;
  }
  const dashpot_simd::Lanes l{b.dx, b.dy, b.dz, ux, uy, uz, m1, m2, b.fx, b.fy, b.fz};
  dashpot_simd::evaluate(ratio, stiffness, shear, l, static_cast<std::size_t>(lanes));
}

const char* contact_damping_simd_target() { return dashpot_simd::target_name(); }

}  // namespace mdem
