#pragma once
// Linear frictionless contact between grains and flat platens (ElementKind::Wall elements):
// u_n = R − d, d the distance from the grain centre to the platen plane (along its normal),
// F = k_n·u_n along the normal when u_n > 0, nothing otherwise. The thesis's Eq. 36 with a wall
// of infinite radius gives L = ∞; this engine takes the rigid-platen limit of the same neck
// model: k_n = π·R²·E_grain/R = π·R·E_grain (L = R, the wall adds no compliance). Energy
// EnergyTerm::Contact. The reaction on the platen goes to the platen element, so a protocol reads
// the platen force from System's forces and the system books the work of its prescribed motion.
#include <vector>

#include "mdem/force/force_model.h"
#include "mdem/scene/grain.h"

namespace mdem {

class PlanarWallContact final : public ForceModel {
 public:
  explicit PlanarWallContact(double youngs);
  std::string_view name() const override { return "planar_wall_contact"; }
  // Holds no element indices (platens found afresh at every evaluation).
  bool follows_reorder() const override { return true; }
  void compute(const Elements& el, const NeighborList* pairs, ForceSink& sink) const override;
  void add_stiffness(const Elements& el, const NeighborList* pairs,
                     StiffnessSums& s) const override;
  double stiffness(double radius) const;

 private:
  double youngs_;
  mutable PlatenPlanes platens_;  // refreshed at every evaluation
};

}  // namespace mdem
