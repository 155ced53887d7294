// Fixed spherical packing walls (spherical_wall.h).
#include "mdem/force/wall/spherical_wall.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "mdem/scene/grain.h"
#include "per_grain.h"

namespace mdem {

SphericalWallContact::SphericalWallContact(const Vec3& centre, double r_outer, double r_inner,
                                           double youngs)
    : centre_(centre), youngs_(youngs) {
  if (!centre.allFinite()) throw std::invalid_argument("spherical wall: centre must be finite");
  if (!std::isfinite(youngs) || youngs <= 0)
    throw std::invalid_argument("spherical wall: youngs must be finite and > 0, got " +
                                std::to_string(youngs));
  set_radii(r_outer, r_inner);
}

void SphericalWallContact::set_radii(double r_outer, double r_inner) {
  if (!std::isfinite(r_outer) || r_outer <= 0)
    throw std::invalid_argument("spherical wall: r_outer must be finite and > 0 nm, got " +
                                std::to_string(r_outer));
  if (!std::isfinite(r_inner) || r_inner < 0 || r_inner >= r_outer)
    throw std::invalid_argument("spherical wall: r_inner must be in [0, r_outer), got " +
                                std::to_string(r_inner));
  r_outer_ = r_outer;
  r_inner_ = r_inner;
}

void SphericalWallContact::compute(const Elements& el, const NeighborList*, ForceSink& sink) const {
  for_each_grain(el, sink, EnergyTerm::Contact, [&](long i, Vec3* f, double& energy) {
    const double R = el.radius[i];
    const double k = wall_contact_stiffness(youngs_, R);
    const Vec3 d = el.x[i] - centre_;
    const double r = d.norm();
    // Outward unit vector (any direction at the centre itself, where only the inner wall acts).
    const Vec3 out = r > 0 ? Vec3(d / r) : Vec3(Vec3::UnitZ());
    const double u_out = r + R - r_outer_;
    if (u_out > 0) {
      f[i] -= (k * u_out) * out;
      energy += 0.5 * k * u_out * u_out;
    }
    const double u_in = r_inner_ - (r - R);
    if (r_inner_ > 0 && u_in > 0) {
      f[i] += (k * u_in) * out;
      energy += 0.5 * k * u_in * u_in;
    }
  });
}

void SphericalWallContact::add_stiffness(const Elements& el, const NeighborList*,
                                         StiffnessSums& s) const {
  for (std::size_t i = 0; i < el.size(); ++i) {
    if (el.kind[i] != ElementKind::Grain) continue;
    const double R = el.radius[i];
    const double r = (el.x[i] - centre_).norm();
    // Fixed walls: k/2 per wall within a diameter of touching (see PlanarWallContact).
    const double k = wall_contact_stiffness(youngs_, R);
    if (r_outer_ - (r + R) < 2.0 * R) s.kt[i] += 0.5 * k;
    if (r_inner_ > 0 && (r - R) - r_inner_ < 2.0 * R) s.kt[i] += 0.5 * k;
  }
}

}  // namespace mdem
