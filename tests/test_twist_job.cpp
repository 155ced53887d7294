// The twist job on small ropes, against physics that does not depend on the code: static
// equilibrium (the grips' internal moment balances the applied one), elasticity (an unloaded rope
// returns towards straight), the energy balance W_ext = ΔE + E_diss, and the boundary
// conditions' kinematics.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "mdem/core/units.h"
#include "mdem/job/twist_job.h"

namespace mdem {
namespace {

TwistJobSpec small_rope(int layers, int segments, double torque_nNnm, double hold_ps) {
  TwistJobSpec s;
  s.rope.layers = layers;
  s.rope.segments = segments;
  s.loading.torque_max = units::nNnm(torque_nNnm);
  s.loading.rate = units::nNnm(1.0);
  s.loading.hold = hold_ps;
  return s;
}

IntegratorSettings damped(double alpha) {
  IntegratorSettings st;
  st.local_damping = alpha;
  st.threads = 1;
  return st;
}

// At rest under a constant moment, every free DOF of a grip is balanced, so the internal moment
// on each grip equals the applied torque: the reaction matches T within 1 % once the rope has
// settled (strong local damping to get there in a few hundred ps).
TEST(TwistJob, GripsHoldTheSetTorque) {
  TwistJob job(small_rope(2, 20, 2.0, 200), damped(0.7));
  run_job(job, {10.0, 0}, {});
  const TwistReport r = job.report();
  EXPECT_NEAR(r.applied_torque_nNnm, 2.0, 1e-12);
  EXPECT_NEAR(r.grip_reaction_nNnm, 2.0, 0.02);
  EXPECT_GT(r.shift_angle_deg, 20.0);  // it really twisted
  EXPECT_GT(r.twist_angle_deg, 2.0);
}

// A small torque twists the rope elastically: unloaded, it untwists. The outer tubes' tilt and
// the bond energy fall to a small part of their loaded values (the last few degrees relax slowly:
// the restoring moment of a geometric twist grows as the tilt cubed).
TEST(TwistJob, SmallTorqueUntwistsBackTowardsStraight) {
  TwistJobSpec s = small_rope(2, 20, 2.0, 100);
  s.loading.unload = true;
  s.loading.unload_hold = 300;
  TwistJob job(s, damped(0.7));
  const auto cols = job.columns();
  const auto col = [&](const char* n) {
    return std::find(cols.begin(), cols.end(), n) - cols.begin();
  };
  double peak_tilt = 0, loaded_bond = 0;
  JobObserver obs;
  obs.frame = [&](const SeriesFrame& f) {
    if (f.time_ps > 102) return;  // loaded: ramp (2 ps) and hold (100 ps)
    peak_tilt = std::max(peak_tilt, f.values[col("twist_angle_deg")]);
    loaded_bond = f.values[col("bond_bending_eV")] + f.values[col("bond_torsion_eV")];
  };
  run_job(job, {2.0, 0}, obs);
  const TwistReport r = job.report();
  const EnergyTally& e = job.system().energy().potential;
  const double bond = e.stored[static_cast<int>(EnergyTerm::BondBending)] +
                      e.stored[static_cast<int>(EnergyTerm::BondTorsion)];
  EXPECT_GT(peak_tilt, 4.0);
  EXPECT_LT(r.twist_angle_deg, 0.35 * peak_tilt);
  EXPECT_LT(bond, 0.15 * loaded_bond);
  EXPECT_EQ(r.morphology, Morphology::Straight);
  EXPECT_EQ(r.topological_charge, 0);
  EXPECT_NEAR(r.applied_torque_nNnm, 0.0, 1e-12);
}

// Work of the grip loads = change of stored + kinetic energy + energy the dashpots took, to the
// integrator's accuracy, with no local damping (only the vdW dashpots).
TEST(TwistJob, EnergyBalanceClosesUnderLoad) {
  TwistJob job(small_rope(3, 16, 5.0, 20), damped(0.0));
  run_job(job, {5.0, 0}, {});
  const EnergyLedger& L = job.system().energy();
  EXPECT_GT(L.external_work, 1.0);  // eV: the load did real work
  EXPECT_GT(L.dissipated, 0.0);
  EXPECT_LT(job.system().energy_balance_error(), 0.01);
}

// Twist relaxation: during the hold the grip elements stay where the ramp left them (prescribed
// zero velocity), carry no load, and spin freely.
TEST(TwistJob, TwistRelaxationHoldsGripPositionsAndFreesTheirSpin) {
  TwistJobSpec s = small_rope(2, 12, 2.0, 10);
  s.loading.boundary = TwistBoundary::TwistRelaxation;
  TwistJob job(s, damped(0.1));
  System& sys = job.system();
  sys.initialize();
  sys.run(static_cast<long>(std::ceil(2.0 / sys.dt())) + 2);  // just past the ramp
  const Elements& el = sys.elements();
  const std::vector<std::size_t> grip_a = el.group_indices(kRopeGripA);
  std::vector<Vec3> held;
  for (std::size_t i : grip_a) held.push_back(el.x[i]);
  sys.run(200);
  double spin = 0;
  for (std::size_t k = 0; k < grip_a.size(); ++k) {
    const std::size_t i = grip_a[k];
    EXPECT_LT((el.x[i] - held[k]).norm(), 1e-12);
    EXPECT_EQ(el.f_ext[i].norm(), 0.0);
    EXPECT_EQ(el.t_ext[i].norm(), 0.0);
    EXPECT_EQ(el.dof[i][3], DofMode::Free);
    spin = std::max(spin, el.w[i].norm());
  }
  EXPECT_GT(spin, 0.0);
}

// Per-element grip load: every grip element carries exactly ±T about the axis through its own
// centre and no force.
TEST(TwistJob, PerElementGripLoadPutsTheTorqueOnEveryElement) {
  TwistJobSpec s = small_rope(2, 12, 3.0, 5);
  s.loading.grip_load = GripLoad::PerElement;
  TwistJob job(s, damped(0.1));
  job.system().initialize();
  job.system().run(200);  // past the 3 ps ramp at ~20 fs
  const Elements& el = job.system().elements();
  for (std::size_t i : el.group_indices(kRopeGripB)) {
    EXPECT_NEAR(el.t_ext[i].z(), units::nNnm(3.0), 1e-9);
    EXPECT_EQ(el.f_ext[i].norm(), 0.0);
  }
  for (std::size_t i : el.group_indices(kRopeGripA))
    EXPECT_NEAR(el.t_ext[i].z(), -units::nNnm(3.0), 1e-9);
}

// The rope's own section: charge 0 as built; spread in-plane by 1.5 (no neighbour within
// 1.37 d) every internal tube counts six.
TEST(TwistJob, RopeSectionChargeIsZeroAsBuiltAndCountsEveryLostNeighbour) {
  TwistJob job(small_rope(5, 12, 1.0, 1), damped(0.0));
  Elements& el = job.system().elements();
  const Rope& rope = job.rope();
  EXPECT_EQ(rope_topological_charge(el, rope, rope_axis(el, rope)).charge, 0);
  for (Vec3& x : el.x) x.head<2>() *= 1.5;
  EXPECT_EQ(rope_topological_charge(el, rope, rope_axis(el, rope)).charge, 6 * 37);
}

TEST(Morphology, FirstRuleThatHoldsNamesIt) {
  Rope rope;
  rope.lattice.spacing = 1.7;
  rope.initial_radius = 8.5;
  RopeShape s;
  s.clusters = 1;
  EXPECT_EQ(classify_morphology(s, rope), Morphology::Straight);
  s.twist_angle_deg = 6;
  EXPECT_EQ(classify_morphology(s, rope), Morphology::Spindle);
  s.core_void_radius = 1.2 * 1.7 + 0.01;
  EXPECT_EQ(classify_morphology(s, rope), Morphology::BirdCage);
  s.axis_deviation = 4.3;
  EXPECT_EQ(classify_morphology(s, rope), Morphology::Helix);
  s.clusters = 2;
  EXPECT_EQ(classify_morphology(s, rope), Morphology::Separated);
}

}  // namespace
}  // namespace mdem

namespace mdem {
namespace {

// Initial temperature by equipartition: ½ kB T per translational and per rotational DOF, within
// the sampling error of 7 tubes × 20 segments (840 DOFs: ~5 % rms), and reproducible by seed.
TEST(TwistJob, InitialTemperatureFollowsEquipartitionAndTheSeed) {
  TwistJobSpec s = small_rope(2, 20, 1.0, 1);
  s.temperature_k = 300;
  s.seed = 7;
  TwistJob a(s, damped(0.0)), b(s, damped(0.0));
  a.system().initialize();
  const double n = static_cast<double>(a.system().elements().size());
  const double kT = units::kBoltzmann * 300;
  EXPECT_NEAR(a.system().energy().kinetic_translational / (1.5 * n * kT), 1.0, 0.2);
  EXPECT_NEAR(a.system().energy().kinetic_rotational / (1.5 * n * kT), 1.0, 0.2);
  EXPECT_EQ(a.system().elements().v, b.system().elements().v);
  s.seed = 8;
  TwistJob c(s, damped(0.0));
  EXPECT_NE(a.system().elements().v, c.system().elements().v);
}

}  // namespace
}  // namespace mdem

namespace mdem {
namespace {

// Cancelling stops the run loop between chunks and keeps everything reported so far: the frames
// up to the stop, whose last one is the state the run stopped in.
TEST(RunJob, CancelStopsEarlyAndKeepsTheFramesSoFar) {
  TwistJob job(small_rope(2, 12, 2.0, 50), damped(0.1));
  std::vector<SeriesFrame> frames;
  JobObserver obs;
  obs.frame = [&](const SeriesFrame& f) { frames.push_back(f); };
  obs.cancelled = [&] { return frames.size() >= 5; };
  const JobRunResult r = run_job(job, {1.0, 0}, obs);
  EXPECT_TRUE(r.cancelled);
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_EQ(frames.back().step, r.steps);
  EXPECT_EQ(r.steps, job.system().steps());
  EXPECT_LT(job.system().time(), 0.2 * job.duration());
}

}  // namespace
}  // namespace mdem
