#pragma once
// Bonds between grains (thesis Eq. 37–38, model.md §6): a parallel bond (the total formulation of
// parallel_bond.h) with the grain neck's section and stiffness, in one of three kinds:
//   elastic  — never yields or breaks;
//   plastic  — elastic–perfectly plastic in tension/compression and shear with Tresca limits
//              |F_n| ≤ σ_y·A, |F_s| ≤ τ_y·A (τ_y = σ_y/2): the force is capped by return mapping
//              and the excess displacement recorded as plastic slip (normal and shear); bending
//              and twist stay elastic. (The thesis's "multiply by 1 − |ΔF|" is unit-inconsistent.)
//   brittle  — breaks for good when σ ≥ σ_f or τ ≥ τ_f = σ_f/2, with the edge stresses
//              σ = F_n/A (tension positive) + |M_b|·R_b/I and τ = |F_s|/A + |M_t|·R_b/J.
// Section: R_b = min(R1, R2), A = πR_b², I = πR_b⁴/4, J = 2I; kn = E/L, ks = G/L with L the
// centre distance at bonding, G = E/(2(1+ν)).
//
// A pair keeps its record after its bond breaks: it then interacts only by a linear frictionless
// contact (Eq. 36 stiffness) that pushes when the centres come closer than the bonding distance
// L (the grains touched there when bonded; a packing leaves them overlapped, so R1 + R2 would push
// at once). LinearContact skips every pair this model owns.
//
// Energy: stored bond energy by component (EnergyTerm::Bond*), post-break contact energy as
// EnergyTerm::Contact; plastic work (capped force × slip increment) and a breaking bond's energy
// (less the contact energy that replaces it) go to EnergyTally::released. Plastic slip and broken
// flags change only when compute() meets a new state (each bond is updated by the one thread that
// evaluates it), and are saved in checkpoints.
#include <cstdint>
#include <vector>

#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/pair_driver.h"
#include "mdem/scene/grain.h"

namespace mdem {

enum class BondBehaviour : std::uint8_t { Elastic = 0, Plastic = 1, Brittle = 2 };

struct GrainBondParams {
  GrainMaterial material;  // E and ν of the neck
  BondBehaviour behaviour = BondBehaviour::Elastic;
  double strength = 0;  // σ_y (plastic) or σ_f (brittle), eV/nm³; the shear limit is half of it
};

// One bond and what happened to it.
struct GrainBondRecord {
  Bond bond;          // geometry at bonding and stiffness (parallel_bond.h)
  double radius = 0;  // R_b
  double length = 0;  // L, centre distance at bonding
  // Plastic slip is a permanent offset of grain i's bond point, p = plastic_normal·n_i +
  // plastic_shear in grain i's body frame (n_i = bond.ni), so the bond's energy stays a function
  // of the configuration and its forces the exact gradient.
  double plastic_normal = 0;  // accumulated normal plastic slip (nm, signed: + in tension)
  // Accumulated shear plastic slip, body frame of grain i (plus the normal slip's small part off
  // n_i when the bond axis had turned away from body i's bond direction as it flowed).
  Vec3 plastic_shear = Vec3::Zero();
  bool yielded = false;  // has flowed plastically at least once
  bool broken = false;
};

// Edge stresses of one bond at the current state (eV/nm³).
struct BondStress {
  double sigma = 0;  // F_n/A (tension positive) + |M_b| R_b / I
  double tau = 0;    // |F_s|/A + |M_t| R_b / J
};

class GrainBond final : public ForceModel {
 public:
  // Throws std::invalid_argument for a non-positive or non-finite E, ν outside [0, 0.5) or a
  // strength that is not > 0 for plastic and brittle bonds.
  explicit GrainBond(GrainBondParams p);
  std::string_view name() const override { return "grain_bond"; }
  void compute(const Elements& el, const NeighborList* pairs, ForceSink& sink) const override;
  void add_stiffness(const Elements& el, const NeighborList* pairs,
                     StiffnessSums& s) const override;
  std::size_t memory_bytes() const override {
    return capacity_bytes(bonds_) + capacity_bytes(partners_);
  }
  void save_state(StateWriter& w) const override;
  void load_state(StateReader& r) override;
  // The bonds' element indices and the per-element partner lists follow a reordering.
  bool follows_reorder() const override { return true; }
  void reorder(std::span<const std::uint32_t> old_to_new) override;

  // Bonds i and j in their current configuration (the rest state). Returns the bond's index.
  // Throws std::invalid_argument for i == j, coincident centres or a pair already bonded.
  std::size_t add(const Elements& el, std::uint32_t i, std::uint32_t j);

  const GrainBondParams& params() const { return p_; }
  const std::vector<GrainBondRecord>& bonds() const { return bonds_; }
  std::size_t intact_count() const;
  std::size_t broken_count() const;
  std::size_t yielded_count() const;
  // Whether (i, j) has a bond record (intact or broken); O(bonds per grain).
  bool owns(std::size_t i, std::size_t j) const;
  // The stresses of bond k at the current state (zero for a broken bond).
  BondStress stress(const Elements& el, std::size_t k) const;
  // Bond k's stiffness (section times kn, ks).
  BondStiffness stiffness(std::size_t k) const { return bonds_[k].bond.k; }

 private:
  GrainBondParams p_;
  mutable std::vector<GrainBondRecord> bonds_;  // plastic slip and broken flags change in compute
  std::vector<std::vector<std::uint32_t>> partners_;  // per element: bonded partners
};

// Viscous normal dashpots of the failure stage (thesis §6.2, β = 0.5; model.md §6): on every
// intact bond and every pair in linear contact (grain–grain, post-break, grain–platen), a force
// −c·(n·v_rel)·n along the centre line (the platen normal), c = 2β√(m_eff·k_n) with the pair's
// normal stiffness and reduced mass (the grain's mass against a platen).
// Whether (i, j) is not an unbonded Grain–Grain pair (either is not a grain, or bonds, which may be
// null, holds a record of the pair): the pairs the linear contact and its dashpots leave out.
bool grain_contact_excluded(const Elements& el, std::size_t i, std::size_t j,
                            const GrainBond* bonds);

// The pair part of GrainDashpots (pair_driver.h): unbonded Grain–Grain pairs in contact, the
// pairs of the linear contact it belongs to.
class GrainContactDashpotKernel {
 public:
  static constexpr bool kDissipative = true;
  static constexpr bool kTorques = false;
  static constexpr EnergyTerm kTerm = EnergyTerm::Contact;  // unused: dissipative

  GrainContactDashpotKernel(double ratio, const GrainBond* bonds, double contact_youngs,
                            double max_radius)
      : ratio_(ratio), bonds_(bonds), contact_youngs_(contact_youngs), max_radius_(max_radius) {}
  std::string_view name() const { return "grain_dashpots"; }
  std::string_view owner() const { return "linear_contact"; }
  double cutoff() const { return 2.0 * max_radius_; }
  KindPairs kinds() const { return KindPairs::of(ElementKind::Grain, ElementKind::Grain); }
  bool excludes(const Elements& el, std::size_t i, std::size_t j) const;
  bool pair(const Elements& el, std::size_t i, std::size_t j, const Vec3& d, PairForces& out) const;
  void stiffness(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                 StiffnessSums& s) const;

 private:
  double ratio_;
  const GrainBond* bonds_;
  double contact_youngs_, max_radius_;
};

class GrainDashpots final : public ForceModel {
 public:
  // bonds: the bond model (its intact bonds and broken pairs); contact_youngs: E of the linear
  // contacts; max_radius: largest grain radius.
  GrainDashpots(double ratio, const GrainBond* bonds, double contact_youngs, double max_radius);
  std::string_view name() const override { return "grain_dashpots"; }
  double cutoff() const override { return contacts_.cutoff(); }
  KindPairs kinds() const override { return contacts_.kinds(); }
  std::string_view pair_owner() const override { return contacts_.owner(); }
  bool dissipative() const override { return true; }
  // Holds no indices: the platens are found afresh at every evaluation, the bonds are the bond
  // model's.
  bool follows_reorder() const override { return true; }
  bool excludes(const Elements& el, std::size_t i, std::size_t j) const override {
    return contacts_.excludes(el, i, j);
  }
  void compute(const Elements& el, const NeighborList* pairs, ForceSink& sink) const override;
  void add_stiffness(const Elements& el, const NeighborList* pairs,
                     StiffnessSums& s) const override;

 private:
  GrainContactDashpotKernel contacts_;
  double ratio_;
  const GrainBond* bonds_;
  double contact_youngs_, max_radius_;
  mutable PlatenPlanes platens_;  // refreshed at every evaluation
};

}  // namespace mdem
