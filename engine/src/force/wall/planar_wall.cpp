// Grain–platen contact: linear, frictionless, rigid-platen limit of Eq. 36 (planar_wall.h).
#include "mdem/force/wall/planar_wall.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "per_grain.h"

namespace mdem {

PlanarWallContact::PlanarWallContact(double youngs) : youngs_(youngs) {
  if (!std::isfinite(youngs) || youngs <= 0)
    throw std::invalid_argument("planar wall contact: youngs must be finite and > 0, got " +
                                std::to_string(youngs));
}

double PlanarWallContact::stiffness(double radius) const {
  return wall_contact_stiffness(youngs_, radius);
}

void PlanarWallContact::compute(const Elements& el, const NeighborList*, ForceSink& sink) const {
  platens_.update(el);
  if (platens_.size() == 0) return;
  const std::size_t nw = platens_.size();
  for_each_grain(el, sink, EnergyTerm::Contact, [&](long i, Vec3* f, double& energy) {
    const double R = el.radius[i];
    for (std::size_t w = 0; w < nw; ++w) {
      const double u = R - platens_.height(w, el.x[i]);
      if (u <= 0) continue;
      const double k = stiffness(R);
      const Vec3 F = (k * u) * platens_.normal(w);
      f[i] += F;
      // The reaction on the platen: a force only (its rotation is never free), so the system
      // books the work of its prescribed motion and a protocol reads the platen force.
      f[platens_.index(w)] -= F;
      energy += 0.5 * k * u * u;
    }
  });
}

void PlanarWallContact::add_stiffness(const Elements& el, const NeighborList*,
                                      StiffnessSums& s) const {
  platens_.update(el);
  // A platen moves as prescribed: its spring adds k/m to the grain's ω² with no coupling block,
  // and the system doubles kt for the coupling of free pairs, hence k/2.
  platens_.for_each_grain_near(el,
                               [&](std::size_t i) { s.kt[i] += 0.5 * stiffness(el.radius[i]); });
}

}  // namespace mdem
