#pragma once
// Fixed spherical walls that hold grains while they are packed (thesis §6.2): an outer wall of
// radius R_out (grains pushed inwards when r + R > R_out) and, for a shell, an inner wall of
// radius R_in (grains pushed outwards when r − R < R_in); r the grain's distance from the centre.
// Linear frictionless, k_n = π·R·E as for a flat platen, energy EnergyTerm::Contact. The walls do
// not move during a run, so they do no work: the reaction is not recorded on any element. (A
// packing may move them between runs, set_radii, to confine grains that do not jam; it books no
// energy.)
#include "mdem/force/force_model.h"

namespace mdem {

class SphericalWallContact final : public ForceModel {
 public:
  // r_inner = 0: no inner wall (a full sphere).
  SphericalWallContact(const Vec3& centre, double r_outer, double r_inner, double youngs);
  std::string_view name() const override { return "spherical_wall_contact"; }
  // Holds no element indices (parameters only).
  bool follows_reorder() const override { return true; }
  void compute(const Elements& el, const NeighborList* pairs, ForceSink& sink) const override;
  void add_stiffness(const Elements& el, const NeighborList* pairs,
                     StiffnessSums& s) const override;
  // Moves the walls (same checks as the constructor).
  void set_radii(double r_outer, double r_inner);
  double r_outer() const { return r_outer_; }
  double r_inner() const { return r_inner_; }

 private:
  Vec3 centre_;
  double r_outer_, r_inner_, youngs_;
};

}  // namespace mdem
