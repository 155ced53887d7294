// Linear frictionless grain–grain contact (thesis Eq. 36, model.md §6).
#include "mdem/force/contact/linear_contact.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "mdem/force/bond/grain_bond.h"
#include "mdem/neighbor/neighbor_list.h"
#include "mdem/scene/grain.h"

namespace mdem {

LinearContact::LinearContact(double youngs, double max_radius, const GrainBond* bonds)
    : youngs_(youngs), max_radius_(max_radius), bonds_(bonds) {
  if (!std::isfinite(youngs) || youngs <= 0)
    throw std::invalid_argument("linear contact: youngs must be finite and > 0, got " +
                                std::to_string(youngs));
  if (!std::isfinite(max_radius) || max_radius <= 0)
    throw std::invalid_argument("linear contact: max_radius must be finite and > 0 nm, got " +
                                std::to_string(max_radius));
}

bool LinearContact::excludes(const Elements& el, std::size_t i, std::size_t j) const {
  if (el.kind[i] != ElementKind::Grain || el.kind[j] != ElementKind::Grain) return true;
  return bonds_ && bonds_->owns(i, j);
}

double LinearContact::stiffness(double ri, double rj) const {
  return grain_contact_stiffness(youngs_, ri, rj);
}

double LinearContact::force(double ri, double rj, double r) const {
  const double u = ri + rj - r;
  return u > 0 ? stiffness(ri, rj) * u : 0.0;
}

void LinearContact::compute(const Elements& el, const NeighborList* pairs, ForceSink& sink) const {
  if (!pairs) throw std::logic_error("linear_contact: compute() needs a neighbour list");
  const long n = static_cast<long>(el.size());
  if (n == 0) return;
  const auto& off = pairs->offsets();
  const auto& nb = pairs->neighbors();
  if (off.size() != el.size() + 1)
    throw std::logic_error("linear_contact: neighbour list was not built for these elements");
  const bool threaded = static_cast<long>(pairs->pair_count()) >= 2 * kParallelMinItems;
#pragma omp parallel num_threads(sink.threads()) if (threaded)
  {
    const int tid = omp_get_thread_num();
    Vec3* f = sink.force(tid);
    double energy = 0;
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i) {
      const std::uint32_t begin = off[i], end = off[i + 1];
      if (begin == end || el.kind[i] != ElementKind::Grain) continue;
      const Vec3 xi = el.x[i];
      const double ri = el.radius[i];
      Vec3 fi = Vec3::Zero();
      for (std::uint32_t m = begin; m < end; ++m) {
        const std::uint32_t j = nb[m];
        const Vec3 d = el.x[j] - xi;
        const double reach = ri + el.radius[j];
        const double r2 = d.squaredNorm();
        // Apart or touching: nothing at all (never tension). Coincident centres have no
        // direction to push along; the packing never produces them (it grows radii from small).
        if (r2 >= reach * reach || r2 == 0) continue;
        if (el.kind[j] != ElementKind::Grain) continue;
        if (bonds_ && bonds_->owns(i, j)) continue;
        const double r = std::sqrt(r2);
        const double u = reach - r;
        const double k = stiffness(ri, el.radius[j]);
        const Vec3 fj = (k * u / r) * d;  // pushes j away from i
        f[j] += fj;
        fi -= fj;
        energy += 0.5 * k * u * u;
      }
      f[i] += fi;
    }
    sink.energy(tid).add(EnergyTerm::Contact, energy);
  }
}

void LinearContact::add_stiffness(const Elements& el, const NeighborList* pairs,
                                  StiffnessSums& s) const {
  if (!pairs) return;
  const auto& off = pairs->offsets();
  const auto& nb = pairs->neighbors();
  if (off.size() != el.size() + 1) return;
  // Unbonded grain pairs touching or about to (a gap below half the smaller radius): the step is
  // fixed when a run starts, and these are the contacts it meets first. (Counting every listed
  // pair, out to 2·max_radius + skin, would count three times the contacts a dense packing has
  // and halve the step for nothing.)
  for (std::size_t i = 0; i < el.size(); ++i) {
    if (el.kind[i] != ElementKind::Grain) continue;
    for (std::uint32_t m = off[i]; m < off[i + 1]; ++m) {
      const std::size_t j = nb[m];
      const double ri = el.radius[i], rj = el.radius[j];
      const double reach = ri + rj + 0.5 * std::min(ri, rj);
      if ((el.x[j] - el.x[i]).squaredNorm() >= reach * reach || excludes(el, i, j)) continue;
      // Frictionless and central: no moment, no rotational stiffness.
      s.add_pair(i, j, stiffness(ri, rj), 0.0, 0.0);
    }
  }
}

}  // namespace mdem
