#pragma once
// Viscous dashpots in CNT–CNT vdW contacts (thesis Eq. 33–34, model.md §4): on every pair of the
// vdW contact within the cutoff, a force −c·(n·v_rel)·n along the centre line n,
// c = 2ψ√(m_eff k), m_eff the pair's reduced mass; with `shear`, also the thesis's shear dashpot
// (c_s = c_n: both stiffnesses are 100 eV/nm², Eq. 34), so the force is −c·v_rel, v_rel the
// relative centre velocity.
//
// The dashpot belongs to the vdW contact (pair_owner() "anisotropic_vdw"): it acts on exactly
// that contact's CntSegment–CntSegment pairs, never on pairs of other kinds (a nanoparticle next
// to a tube gets no CNT dashpot). Without a vdW contact in the system it lists those pairs itself.
//
// Only the normal dashpot: the thesis's shear dashpot on the relative centre velocity damps a
// rigid rotation (a rope turning as a whole meets a drag growing with the pair distance), and on
// the relative velocity at a contact point the vdW reach of 5.4 nm makes lever arms that over-damp
// every spin (unstable at the default step). A force along the centre line, as DPD's dissipative
// force, leaves every rigid motion undamped and conserves linear and angular momentum; sliding
// is still damped through the many pairs at oblique angles. The shear option is for comparisons
// with the thesis on gripped films (the tensile job), where no body turns as a whole: it damps
// sliding at a crossing directly, and conserves linear momentum but not angular momentum.
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/damping/dashpot_law.h"
#include "mdem/force/pair_driver.h"

namespace mdem {

struct ContactDampingParams {
  double ratio = 0.03;            // ψ (thesis: 0.03)
  double stiffness = 100.0;       // k (eV/nm²)
  double cutoff = 4 * 1.356;      // acts on pairs closer than this (nm): the vdW cutoff 4T
  int intra_tube_exclusion = 20;  // same meaning as VdwParams::intra_tube_exclusion
  // Also damp the relative centre velocity across the centre line (the thesis's shear dashpot,
  // c_s = c): the force is then −c·v_rel. Off by default (see above).
  bool shear = false;
};

// The dashpot pair kernel (pair_driver.h).
class ContactDampingKernel {
 public:
  static constexpr bool kDissipative = true;
  static constexpr Timescale kTimescale = Timescale::Slow;  // r-RESPA outer step
  static constexpr bool kTorques = false;
  static constexpr EnergyTerm kTerm = EnergyTerm::Vdw;  // unused: dissipative

  // Throws std::invalid_argument for a ratio outside [0, 10], a non-positive stiffness or cutoff,
  // or a negative exclusion.
  explicit ContactDampingKernel(ContactDampingParams p,
                                DashpotEvaluation e = DashpotEvaluation::Batched);
  std::string_view name() const { return "viscous_contact_damping"; }
  std::string_view owner() const { return "anisotropic_vdw"; }
  // Its pairs are the vdW contact's: the system evaluates both in one pass (compute_with).
  using Owners = std::tuple<VdwKernel>;
  bool active() const { return p_.ratio != 0; }
  double cutoff() const { return p_.cutoff; }
  KindPairs kinds() const {
    return KindPairs::of(ElementKind::CntSegment, ElementKind::CntSegment);
  }
  bool excludes(const Elements& el, std::size_t i, std::size_t j) const {
    return el.cnt_pair_excluded(i, j, p_.intra_tube_exclusion);
  }
  bool pair(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
            PairForces& out) const {
    return dashpot_pair(el, i, j, d, p_.ratio, p_.stiffness, p_.cutoff, p_.shear, out);
  }
  bool batched() const { return eval_ == DashpotEvaluation::Batched; }
  void batch(const Elements& el, PairBatch& b) const {
    dashpot_batch(el, b, p_.ratio, p_.stiffness, p_.shear);
  }
  // batch() reads v_j and m_j of an element of another tube, a cache miss each: fetched while
  // the driver gathers the rest of the batch.
  void touch(const Elements& el, std::uint32_t j) const { dashpot_touch(el, j); }
  void stiffness(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                 StiffnessSums& s) const {
    dashpot_stiffness(el, i, j, d, p_.ratio, p_.stiffness, p_.cutoff, s);
  }
  const ContactDampingParams& params() const { return p_; }

 private:
  ContactDampingParams p_;
  DashpotEvaluation eval_;
};

extern template class PairModel<ContactDampingKernel>;

class ViscousContactDamping final : public PairModel<ContactDampingKernel> {
 public:
  explicit ViscousContactDamping(ContactDampingParams p,
                                 DashpotEvaluation e = DashpotEvaluation::Batched)
      : PairModel<ContactDampingKernel>(p, e) {}
  const ContactDampingParams& params() const { return k_.params(); }
};

}  // namespace mdem
