#pragma once
// Viscous dashpots in CNT–CNT vdW contacts (thesis Eq. 33–34, model.md §4): on every pair within
// the vdW cutoff, a force −c·(n·v_rel)·n along the centre line n, c = 2ψ√(m_eff k), m_eff the
// pair's reduced mass.
//
// Only the normal dashpot: the thesis's shear dashpot on the relative centre velocity damps a
// rigid rotation (a rope turning as a whole meets a drag growing with the pair distance), and on
// the relative velocity at a contact point the vdW reach of 5.4 nm makes lever arms that over-damp
// every spin (unstable at the default step). A force along the centre line, as DPD's dissipative
// force, leaves every rigid motion undamped and conserves linear and angular momentum; sliding
// is still damped through the many pairs at oblique angles.
#include "mdem/force/force_model.h"

namespace mdem {

struct ContactDampingParams {
  double ratio = 0.03;            // ψ (thesis: 0.03)
  double stiffness = 100.0;       // k (eV/nm²)
  double cutoff = 4 * 1.356;      // acts on pairs closer than this (nm): the vdW cutoff 4T
  int intra_tube_exclusion = 20;  // same meaning as VdwParams::intra_tube_exclusion
};

class ViscousContactDamping final : public ForceModel {
 public:
  explicit ViscousContactDamping(ContactDampingParams p);
  std::string_view name() const override { return "viscous_contact_damping"; }
  double cutoff() const override { return p_.cutoff; }
  bool dissipative() const override { return true; }
  bool excludes(const Elements& el, std::size_t i, std::size_t j) const override;
  void compute(const Elements& el, const NeighborList* pairs, ForceSink& sink) const override;
  void add_stiffness(const Elements& el, const NeighborList* pairs,
                     StiffnessSums& s) const override;
  const ContactDampingParams& params() const { return p_; }

 private:
  double coefficient(const Elements& el, std::size_t i, std::size_t j) const;
  ContactDampingParams p_;
};

}  // namespace mdem
