#include "mdem/force/damping/viscous_contact_damping.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "force/damping/dashpot_simd.h"
#include "mdem/core/limits.h"

namespace mdem {

ContactDampingKernel::ContactDampingKernel(ContactDampingParams p, DashpotEvaluation e)
    : p_(p), eval_(e) {
  if (!std::isfinite(p.ratio) || p.ratio < 0 || p.ratio > limits::kMaxDashpotRatio)
    throw std::invalid_argument("contact damping ratio must be finite and in [0, " +
                                std::to_string(static_cast<int>(limits::kMaxDashpotRatio)) +
                                "] (critical damping), got " + std::to_string(p.ratio));
  if (!std::isfinite(p.stiffness) || p.stiffness <= 0)
    throw std::invalid_argument("contact damping stiffness must be finite and > 0");
  if (!std::isfinite(p.cutoff) || p.cutoff <= 0)
    throw std::invalid_argument("contact damping cutoff must be finite and > 0");
  if (p.intra_tube_exclusion < 0)
    throw std::invalid_argument("contact damping intra-tube exclusion must be >= 0");
}

double ContactDampingKernel::coefficient(const Elements& el, std::size_t i, std::size_t j) const {
  return dashpot_coefficient(p_.ratio, el.mass[i], el.mass[j], p_.stiffness);
}

bool ContactDampingKernel::pair(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                                PairForces& out) const {
  const double r2 = d.squaredNorm();
  if (r2 >= p_.cutoff * p_.cutoff || r2 == 0) return false;
  // Along the centre line only: a rigid motion of the pair (translation or rotation) has no
  // relative velocity along it, so it is not damped. With shear, the whole relative velocity.
  const Vec3 u = el.v[j] - el.v[i];
  if (p_.shear) {
    out.f2 = -coefficient(el, i, j) * u;
  } else {
    const Vec3 n = d / std::sqrt(r2);
    out.f2 = -coefficient(el, i, j) * n.dot(u) * n;
  }
  out.f1 = -out.f2;
  return true;
}

// The batch's pairs gathered into SoA lanes (relative velocities and masses beside the driver's
// displacements), padded with r = 0 lanes (zero force) to a whole number of vectors.
void ContactDampingKernel::batch(const Elements& el, PairBatch& b) const {
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
  dashpot_simd::evaluate(p_.ratio, p_.stiffness, p_.shear, l, static_cast<std::size_t>(lanes));
}

const char* contact_damping_simd_target() { return dashpot_simd::target_name(); }

void ContactDampingKernel::stiffness(const Elements& el, std::size_t i, std::size_t j,
                                     const Vec3& d, StiffnessSums& s) const {
  if (d.squaredNorm() >= p_.cutoff * p_.cutoff) return;
  const double c = coefficient(el, i, j);
  s.c[i] += c;
  s.c[j] += c;
}

template class PairModel<ContactDampingKernel>;

}  // namespace mdem
