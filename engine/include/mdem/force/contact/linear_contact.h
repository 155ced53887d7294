#pragma once
// Linear frictionless contact between grains (thesis Eq. 36, model.md §6):
//   F_n = k_n·u_n along the centre line, u_n = R1 + R2 − r > 0, k_n = π·min(R1,R2)²·E/(R1+R2),
//   1/E = 1/E1 + 1/E2 (one material: E/2), no force at all when u_n ≤ 0 (never tension).
// Energy ½·k_n·u_n² (EnergyTerm::Contact). Pairs owned by a GrainBond model (bonded, or broken
// and then in the bond model's own post-break contact) are excluded.
#include "mdem/force/pair_driver.h"

namespace mdem {

class GrainBond;

// The Grain–Grain pair kernel (pair_driver.h).
class LinearContactKernel {
 public:
  static constexpr bool kDissipative = false;
  static constexpr bool kTorques = false;
  static constexpr EnergyTerm kTerm = EnergyTerm::Contact;

  // youngs: E of the grains' material (eV/nm³); max_radius: largest grain radius (the cutoff is
  // twice it). bonds (may be null) owns the pairs it names. Throws std::invalid_argument for a
  // non-finite or non-positive youngs or max_radius.
  LinearContactKernel(double youngs, double max_radius, const GrainBond* bonds = nullptr);
  std::string_view name() const { return "linear_contact"; }
  double cutoff() const { return 2.0 * max_radius_; }
  KindPairs kinds() const { return KindPairs::of(ElementKind::Grain, ElementKind::Grain); }
  bool excludes(const Elements& el, std::size_t i, std::size_t j) const;
  bool pair(const Elements& el, std::size_t i, std::size_t j, const Vec3& d, PairForces& out) const;
  void stiffness(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                 StiffnessSums& s) const;

  // k_n of a pair of radii (eV/nm²), and the magnitude of the contact force (eV/nm, repulsive)
  // for centre distance r: k_n·(ri + rj − r) when positive, 0 otherwise.
  double stiffness(double ri, double rj) const;
  double force(double ri, double rj, double r) const;
  void set_bonds(const GrainBond* bonds) { bonds_ = bonds; }

 private:
  double youngs_, max_radius_;
  const GrainBond* bonds_;
};

extern template class PairModel<LinearContactKernel>;

class LinearContact final : public PairModel<LinearContactKernel> {
 public:
  LinearContact(double youngs, double max_radius, const GrainBond* bonds = nullptr)
      : PairModel<LinearContactKernel>(youngs, max_radius, bonds) {}
  double stiffness(double ri, double rj) const { return k_.stiffness(ri, rj); }
  double force(double ri, double rj, double r) const { return k_.force(ri, rj, r); }
  void set_bonds(const GrainBond* bonds) { k_.set_bonds(bonds); }
};

}  // namespace mdem
