// Linear frictionless grain–grain contact (thesis Eq. 36, model.md §6).
#include "mdem/force/contact/linear_contact.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "mdem/force/bond/grain_bond.h"
#include "mdem/scene/grain.h"

namespace mdem {

LinearContactKernel::LinearContactKernel(double youngs, double max_radius, const GrainBond* bonds)
    : youngs_(youngs), max_radius_(max_radius), bonds_(bonds) {
  if (!std::isfinite(youngs) || youngs <= 0)
    throw std::invalid_argument("linear contact: youngs must be finite and > 0, got " +
                                std::to_string(youngs));
  if (!std::isfinite(max_radius) || max_radius <= 0)
    throw std::invalid_argument("linear contact: max_radius must be finite and > 0 nm, got " +
                                std::to_string(max_radius));
}

bool LinearContactKernel::excludes(const Elements& el, std::size_t i, std::size_t j) const {
  return grain_contact_excluded(el, i, j, bonds_);
}

double LinearContactKernel::stiffness(double ri, double rj) const {
  return grain_contact_stiffness(youngs_, ri, rj);
}

double LinearContactKernel::force(double ri, double rj, double r) const {
  const double u = ri + rj - r;
  return u > 0 ? stiffness(ri, rj) * u : 0.0;
}

bool LinearContactKernel::pair(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                               PairForces& out) const {
  const double ri = el.radius[i], rj = el.radius[j];
  const double reach = ri + rj;
  const double r2 = d.squaredNorm();
  // Apart or touching: nothing at all (never tension). Coincident centres have no direction to
  // push along; the packing never produces them (it grows radii from small).
  if (r2 >= reach * reach || r2 == 0) return false;
  const double r = std::sqrt(r2);
  const double u = reach - r;
  const double k = stiffness(ri, rj);
  out.f2 = (k * u / r) * d;  // pushes j away from i
  out.f1 = -out.f2;
  out.energy = 0.5 * k * u * u;
  return true;
}

void LinearContactKernel::stiffness(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                                    StiffnessSums& s) const {
  // Unbonded grain pairs touching or about to (a gap below half the smaller radius): the step is
  // fixed when a run starts, and these are the contacts it meets first. (Counting every listed
  // pair, out to 2·max_radius + skin, would count three times the contacts a dense packing has
  // and halve the step for nothing.)
  const double ri = el.radius[i], rj = el.radius[j];
  const double reach = ri + rj + 0.5 * std::min(ri, rj);
  if (d.squaredNorm() >= reach * reach) return;
  // Frictionless and central: no moment, no rotational stiffness.
  s.add_pair(i, j, stiffness(ri, rj), 0.0, 0.0);
}

template class PairModel<LinearContactKernel>;

}  // namespace mdem
