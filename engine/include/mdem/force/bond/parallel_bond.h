#pragma once
// Parallel bond (model.md §3 for CNT segments, §6 for grains): a ring of distributed springs at
// the bond point, resisting stretch (kn·A), shear (ks·A), bending (kn·I) and twist (ks·J).
//
// Total (path-independent) formulation, objective under rigid motion, forces and moments the exact
// gradient of the stored energy:
//   gap      g = (x_j + R_j c_j) − (x_i + R_i c_i)           c: body-frame centre→bond point
//   axis     n = normalize(R_i n_i + R_j n_j)                n: body-frame bond direction i→j
//   rotation θ = log(R_j R_rel0⁻¹ R_iᵀ)  (world rotation vector), R_rel0 = R_iᵀR_j at bonding
//   U = ½ kn A (g·n)² + ½ ks A |g − (g·n)n|² + ½ kn I |θ − (θ·n)n|² + ½ ks J (θ·n)²
// so small deformations give F_n = −kn A u_n, F_s = −ks A u_s, M_b = −kn I θ_b, M_t = −ks J θ_t.
#include <cstdint>
#include <memory>
#include <vector>

#include "mdem/core/capacity_bytes.h"
#include "mdem/force/force_model.h"

namespace mdem {

struct BondStiffness {
  double kn_area = 0;     // kn·A (eV/nm²)
  double ks_area = 0;     // ks·A (eV/nm²)
  double kn_inertia = 0;  // kn·I (eV/rad²)
  double ks_polar = 0;    // ks·J (eV/rad²)
};

// The (10,10) CNT intra-tube bond of Table 2-1 (bending kn·I, torsion ks·J).
BondStiffness cnt_bond_stiffness();

struct Bond {
  std::uint32_t i = 0, j = 0;
  Vec3 ci = Vec3::Zero(), cj = Vec3::Zero();    // body-frame vectors, centre -> bond point
  Vec3 ni = Vec3::UnitX(), nj = Vec3::UnitX();  // body-frame unit bond direction i -> j
  Quat q_rel0 = Quat::Identity();               // q_i⁻¹ q_j at bonding
  BondStiffness k;
};

// A bond between i and j in their current configuration (which becomes the rest state). The bond
// point divides the centre line in the ratio of the radii (the midpoint for equal radii).
// Throws std::invalid_argument when i == j or the centres coincide.
Bond make_bond(const Elements& el, std::uint32_t i, std::uint32_t j, const BondStiffness& k);

struct BondDeformation {
  Vec3 n = Vec3::UnitX();       // current bond axis
  double u_n = 0;               // normal (stretch) displacement, positive in tension (nm)
  Vec3 u_s = Vec3::Zero();      // shear displacement (nm)
  double theta_t = 0;           // twist angle (rad)
  Vec3 theta_b = Vec3::Zero();  // bending rotation vector (rad)
};

struct BondResult {
  double e_tension = 0, e_shear = 0, e_bending = 0, e_torsion = 0;
  Vec3 fi = Vec3::Zero(), fj = Vec3::Zero(), ti = Vec3::Zero(), tj = Vec3::Zero();
  double energy() const { return e_tension + e_shear + e_bending + e_torsion; }
};

BondDeformation bond_deformation(const Bond& b, const Vec3& xi, const Quat& qi, const Vec3& xj,
                                 const Quat& qj);
BondResult bond_eval(const Bond& b, const Vec3& xi, const Quat& qi, const Vec3& xj, const Quat& qj);

// A thread's running sums of bond results (ParallelBond, GrainBond): apply() adds a result's
// forces and moments on i and j to the thread's buffers and its energies to the four bond terms;
// add_to() hands the energies to the thread's tally.
struct BondTally {
  double tension = 0, shear = 0, bending = 0, torsion = 0;
  void apply(const BondResult& r, std::uint32_t i, std::uint32_t j, Vec3* f, Vec3* t) {
    f[i] += r.fi;
    f[j] += r.fj;
    t[i] += r.ti;
    t[j] += r.tj;
    tension += r.e_tension;
    shear += r.e_shear;
    bending += r.e_bending;
    torsion += r.e_torsion;
  }
  void add_to(EnergyTally& e) const {
    e.add(EnergyTerm::BondTension, tension);
    e.add(EnergyTerm::BondShear, shear);
    e.add(EnergyTerm::BondBending, bending);
    e.add(EnergyTerm::BondTorsion, torsion);
  }
};

// Adds an intact bond's stiffness to the stable-time-step sums of its two elements.
void add_bond_stiffness(const Bond& b, StiffnessSums& s);

// How ParallelBond::compute evaluates its bonds: in SIMD batches (bond_simd_target()), equal to
// the scalar code to round-off, not bit for bit; or bond by bond with the scalar code
// (bond_eval's), the reference.
enum class BondEvaluation { Batched, Scalar };

// The instruction set the batched bond evaluation runs on, e.g. "AVX3", "AVX2", "EMU128".
const char* bond_simd_target();

class ParallelBond final : public ForceModel {
 public:
  // The bonds of `type` recorded in el.topology, in their recorded order, each made by make_bond
  // from its first to its second element in the elements' current configuration (their rest
  // state). Throws std::invalid_argument as make_bond does, and std::out_of_range for a tag no
  // element holds.
  static std::unique_ptr<ParallelBond> from_topology(const Elements& el, BondType type,
                                                     const BondStiffness& k);
  explicit ParallelBond(BondEvaluation e = BondEvaluation::Batched) : eval_(e) {}
  std::string_view name() const override { return "parallel_bond"; }
  void add(const Bond& b) {
    bonds_.push_back(b);
    rest_stale_ = true;
  }
  const std::vector<Bond>& bonds() const { return bonds_; }
  // Mutable access marks the batched evaluation's copy of the rest state stale: it is rebuilt at
  // the next compute(). Edit bonds through a reference taken after the last compute().
  std::vector<Bond>& bonds() {
    rest_stale_ = true;
    return bonds_;
  }
  BondEvaluation evaluation() const { return eval_; }
  void set_evaluation(BondEvaluation e) { eval_ = e; }
  // Each bond's two element indices follow a reordering, and the bonds are then sorted by their
  // elements' new indices (lower, then higher).
  bool follows_reorder() const override { return true; }
  void reorder(std::span<const std::uint32_t> old_to_new) override;
  void compute(const Elements& el, const NeighborList* pairs, ForceSink& sink) const override;
  void add_stiffness(const Elements& el, const NeighborList* pairs,
                     StiffnessSums& s) const override;
  std::size_t memory_bytes() const override {
    return capacity_bytes(bonds_) + capacity_bytes(rest_index_) + capacity_bytes(rest_);
  }

 private:
  void compute_scalar(const Elements& el, ForceSink& sink) const;
  void compute_batched(const Elements& el, ForceSink& sink) const;
  void build_rest() const;

  std::vector<Bond> bonds_;
  BondEvaluation eval_;
  // The batched evaluation's copy of the bonds' rest state (bond_simd.h's Rest: blocks of
  // vector-length structure-of-arrays), built from bonds_ at the first compute() after a change
  // (add, reorder, mutable bonds()).
  mutable std::vector<std::int64_t> rest_index_;
  mutable std::vector<double> rest_;
  mutable bool rest_stale_ = true;
};

}  // namespace mdem
