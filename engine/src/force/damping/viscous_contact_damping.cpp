#include "mdem/force/damping/viscous_contact_damping.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "mdem/core/limits.h"

namespace mdem {

ContactDampingKernel::ContactDampingKernel(ContactDampingParams p) : p_(p) {
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
  // relative velocity along it, so it is not damped.
  const Vec3 n = d / std::sqrt(r2);
  out.f2 = -coefficient(el, i, j) * n.dot(el.v[j] - el.v[i]) * n;
  out.f1 = -out.f2;
  return true;
}

void ContactDampingKernel::stiffness(const Elements& el, std::size_t i, std::size_t j,
                                     const Vec3& d, StiffnessSums& s) const {
  if (d.squaredNorm() >= p_.cutoff * p_.cutoff) return;
  const double c = coefficient(el, i, j);
  s.c[i] += c;
  s.c[j] += c;
}

template class PairModel<ContactDampingKernel>;

}  // namespace mdem
