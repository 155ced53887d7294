#pragma once
// Energy bookkeeping (model.md §7): every stored-energy component has a slot, so a run can
// report W_ext = ΔE_stored + ΔE_kin + E_dissipated and its error.
#include <array>
#include <string_view>

namespace mdem {

enum class EnergyTerm : int {
  BondTension = 0,
  BondShear,
  BondBending,
  BondTorsion,
  Vdw,
  NpCnt,  // nanoparticle–CNT segment contacts (model.md §5)
  NpNp,   // nanoparticle–nanoparticle contacts (model.md §5)
  Contact,
  kCount
};
inline constexpr int kEnergyTermCount = static_cast<int>(EnergyTerm::kCount);

inline constexpr std::array<std::string_view, kEnergyTermCount> kEnergyTermNames = {
    "bond_tension", "bond_shear", "bond_bending", "bond_torsion",
    "vdw",          "np_cnt",     "np_np",        "contact"};

// Potential energies of one force evaluation, by component.
struct EnergyTally {
  std::array<double, kEnergyTermCount> stored{};
  // Stored energy a model removed for good in this evaluation by an irreversible event (plastic
  // flow of a bond: capped force × plastic slip; a bond breaking: its energy less that of the
  // contact replacing it). The system books it as dissipated during run(); it is zero when the
  // state did not change since the last evaluation.
  double released = 0;

  void add(EnergyTerm t, double e) { stored[static_cast<int>(t)] += e; }
  double total_stored() const {
    double s = 0;
    for (double e : stored) s += e;
    return s;
  }
  EnergyTally& operator+=(const EnergyTally& o) {
    for (int k = 0; k < kEnergyTermCount; ++k) stored[k] += o.stored[k];
    released += o.released;
    return *this;
  }
};

// The running balance of a simulation.
struct EnergyLedger {
  EnergyTally potential;  // at the current step
  double kinetic_translational = 0;
  double kinetic_rotational = 0;
  double external_work = 0;  // work done on the system by external loads and constraints
  double dissipated = 0;     // removed by damping, plus stored energy released (EnergyTally)
  double initial_total = 0;  // stored + kinetic at step 0

  double kinetic() const { return kinetic_translational + kinetic_rotational; }
  double total() const { return potential.total_stored() + kinetic(); }
  // W_ext - (ΔE_stored + ΔE_kin + E_dissipated); zero for an exact integrator.
  double balance_residual() const { return external_work - (total() - initial_total + dissipated); }
};

}  // namespace mdem
