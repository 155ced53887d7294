#pragma once
// Linear frictionless contact between grains (thesis Eq. 36, model.md §6):
//   F_n = k_n·u_n along the centre line, u_n = R1 + R2 − r > 0, k_n = π·min(R1,R2)²·E/(R1+R2),
//   1/E = 1/E1 + 1/E2 (one material: E/2), no force at all when u_n ≤ 0 (never tension).
// Energy ½·k_n·u_n² (EnergyTerm::Contact). Pairs owned by a GrainBond model (bonded, or broken
// and then in the bond model's own post-break contact) are skipped.
#include "mdem/force/force_model.h"

namespace mdem {

class GrainBond;

class LinearContact final : public ForceModel {
 public:
  // youngs: E of the grains' material (eV/nm³); max_radius: largest grain radius (the cutoff is
  // twice it). bonds (may be null) owns the pairs it names.
  LinearContact(double youngs, double max_radius, const GrainBond* bonds = nullptr);
  std::string_view name() const override { return "linear_contact"; }
  double cutoff() const override { return 2.0 * max_radius_; }
  bool excludes(const Elements& el, std::size_t i, std::size_t j) const override;
  void compute(const Elements& el, const NeighborList* pairs, ForceSink& sink) const override;
  void add_stiffness(const Elements& el, const NeighborList* pairs,
                     StiffnessSums& s) const override;

  // k_n of a pair of radii (eV/nm²), and the magnitude of the contact force (eV/nm, repulsive)
  // for centre distance r: k_n·(ri + rj − r) when positive, 0 otherwise.
  double stiffness(double ri, double rj) const;
  double force(double ri, double rj, double r) const;
  void set_bonds(const GrainBond* bonds) { bonds_ = bonds; }

 private:
  double youngs_, max_radius_;
  const GrainBond* bonds_;
};

}  // namespace mdem
