#pragma once
// The law the contact dashpots share (the CNT contact's, viscous_contact_damping.h, and the NP
// contacts', np_contact_damping.h): on a pair within the cutoff, the force −c·(n·v_rel)·n along
// the centre line n (or −c·v_rel with shear), c = 2ψ√(m_eff k), m_eff the pair's reduced mass.
// One scalar law (the reference), one batch path and one vectorised kernel (dashpot_simd) serve
// every dashpot kernel.
#include <cmath>
#include <cstdint>

#include "mdem/core/elements.h"
#include "mdem/force/pair_driver.h"

namespace mdem {

// How a dashpot kernel evaluates its pairs. Batched (the default): in batches of pairs in
// structure-of-arrays form with SIMD on the widest instruction set of the CPU chosen at run time
// (contact_damping_simd_target()); equal to the scalar kernel to round-off, not bit for bit.
// Scalar: one pair at a time (pair()), the reference.
enum class DashpotEvaluation { Batched, Scalar };

// The scalar law on pair (i, j) with d = x_j − x_i: fills out.f1, out.f2 and returns true, or
// returns false beyond the cutoff or at coincident centres.
inline bool dashpot_pair(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                         double ratio, double stiffness, double cutoff, bool shear,
                         PairForces& out) {
  const double r2 = d.squaredNorm();
  if (r2 >= cutoff * cutoff || r2 == 0) return false;
  // Along the centre line only: a rigid motion of the pair (translation or rotation) has no
  // relative velocity along it, so it is not damped. With shear, the whole relative velocity.
  const double c = dashpot_coefficient(ratio, el.mass[i], el.mass[j], stiffness);
  const Vec3 u = el.v[j] - el.v[i];
  if (shear) {
    out.f2 = -c * u;
  } else {
    const Vec3 n = d / std::sqrt(r2);
    out.f2 = -c * n.dot(u) * n;
  }
  out.f1 = -out.f2;
  return true;
}

// The dashpot's coefficient on pair (i, j) within the cutoff added to both elements' c (the
// critical step's damping bound).
inline void dashpot_stiffness(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                              double ratio, double stiffness, double cutoff, StiffnessSums& s) {
  if (d.squaredNorm() >= cutoff * cutoff) return;
  const double c = dashpot_coefficient(ratio, el.mass[i], el.mass[j], stiffness);
  s.c[i] += c;
  s.c[j] += c;
}

// Fills the force outputs of the batch's pairs (PairBatch: the force on i, −f on j; no torques,
// no energy) for a dashpot of damping ratio ψ = ratio and stiffness k, from the elements'
// velocities and masses: the relative velocities and masses gathered beside the driver's
// displacements and evaluated over SIMD lanes. A pair with coincident centres gets zero force
// (no centre line), a NaN propagates.
void dashpot_batch(const Elements& el, PairBatch& b, double ratio, double stiffness, bool shear);

// What dashpot_batch() reads of element j (v_j, m_j): fetched while the driver fills the batch.
inline void dashpot_touch(const Elements& el, std::uint32_t j) {
  pair_driver_detail::prefetch_vec3_end<0>(el.v.data() + j);
  __builtin_prefetch(el.mass.data() + j, 0, 3);
}

// The instruction set of the batched path on this CPU (Highway's name: "AVX3", "AVX2", ...).
const char* contact_damping_simd_target();

}  // namespace mdem
