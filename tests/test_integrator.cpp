// Velocity Verlet, rotation, constraints, energy bookkeeping, critical step and run guard,
// each against an analytical solution or a conservation law.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "mdem/core/cnt.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/integrate/system.h"
#include "mdem/scene/tube_builder.h"
#include "support.h"

using namespace mdem;

namespace {

ElementInit body(const Vec3& x, double mass, const Vec3& inertia) {
  ElementInit e;
  e.x = x;
  e.mass = mass;
  e.inertia = inertia;
  e.radius = 1.0;
  return e;
}

// Two bonded CNT segments along x.
System two_segments(IntegratorSettings s = {}) {
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 2, 0);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  System sys(std::move(el), s);
  sys.add(std::move(bonds));
  return sys;
}

}  // namespace

namespace {

// A free isotropic body (I = 2) spun at ω for `steps` steps of 0.01 ps from a tilted start:
// the orientation it reaches and the one it should, q(t) = exp(ω t) q0.
struct Spin {
  Quat q, expected;
  Vec3 w;
  double kinetic_rotational;
};
Spin spin_freely(const Vec3& w, long steps) {
  Elements el;
  el.add(body(Vec3::Zero(), 1.0, Vec3::Constant(2.0)));
  el.w[0] = w;
  el.q[0] = Quat(Eigen::AngleAxisd(0.4, Vec3(1, 2, 3).normalized()));
  const Quat q0 = el.q[0];
  IntegratorSettings s;
  s.dt = 0.01;
  System sys(std::move(el), s);
  sys.run(steps);
  return {sys.elements().q[0], quat_exp(w * sys.time()) * q0, sys.elements().w[0],
          sys.energy().kinetic_rotational};
}

}  // namespace

TEST(Integrator, IsotropicSpinIsExactUnderFastRotation) {
  // A free isotropic body turns at constant ω: q(t) = exp(ω t) q0, whatever ω·dt is.
  const Spin r = spin_freely(Vec3(3.0, -7.0, 11.0), 10000);  // |ω| dt = 0.13 rad per step
  EXPECT_LT(r.expected.angularDistance(r.q), 1e-8);
  EXPECT_NEAR(r.q.norm(), 1.0, 1e-12);
}

TEST(Integrator, IsotropicSpinIsExactAtSmallAnglesPerStep) {
  // The drift's small-angle branch (|ω| dt below 0.1 rad: series instead of sin, cos and sqrt,
  // renormalisation without a square root): still q(t) = exp(ω t) q0, to round-off per step.
  const Vec3 w(0.3, -0.7, 1.1);          // |ω| dt = 0.0134 rad per step
  const Spin r = spin_freely(w, 20000);  // 268 rad, 43 turns
  EXPECT_LT(r.expected.angularDistance(r.q), 1e-10);
  EXPECT_NEAR(r.q.squaredNorm(), 1.0, 1e-14);
  EXPECT_EQ(r.w, w);
  // Rotational kinetic energy ½ I |ω|², as set.
  EXPECT_DOUBLE_EQ(r.kinetic_rotational, 0.5 * 2.0 * w.squaredNorm());
}

TEST(Integrator, ManyStepsInOneRunEqualSingleStepsBitForBit) {
  // run(n) fuses each step's second pass with the next step's first; run(1) never does. Both
  // must give the same state and books, bit for bit (a 300-step run also crosses the energy
  // guard at steps 100, 200 and 300, where the passes stay apart).
  auto make = [] {
    Elements el;
    add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 12, 0);
    auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
    el.fix_all(0);
    el.f_ext[11] = Vec3(0.3, 0.2, -0.1);
    el.t_ext[11] = Vec3(0.01, 0.0, 0.02);
    el.w[5] = Vec3(0.02, -0.03, 0.01);
    IntegratorSettings s;
    s.local_damping = 0.1;
    System sys(std::move(el), s);
    sys.add(std::move(bonds));
    return sys;
  };
  System a = make(), b = make();
  a.run(300);
  for (int k = 0; k < 300; ++k) b.run(1);
  ASSERT_EQ(a.steps(), b.steps());
  for (std::size_t i = 0; i < a.elements().size(); ++i) {
    EXPECT_EQ(a.elements().x[i], b.elements().x[i]) << i;
    EXPECT_EQ(a.elements().v[i], b.elements().v[i]) << i;
    EXPECT_EQ(a.elements().w[i], b.elements().w[i]) << i;
    EXPECT_EQ(a.elements().q[i].coeffs(), b.elements().q[i].coeffs()) << i;
  }
  EXPECT_EQ(a.energy().external_work, b.energy().external_work);
  EXPECT_EQ(a.energy().dissipated, b.energy().dissipated);
  EXPECT_EQ(a.energy().kinetic_translational, b.energy().kinetic_translational);
  EXPECT_EQ(a.energy().kinetic_rotational, b.energy().kinetic_rotational);
  // And the run did something: the load did work, the damping took some of it.
  EXPECT_GT(a.energy().external_work, 0);
  EXPECT_GT(a.energy().dissipated, 0);
  EXPECT_LT(a.energy_balance_error(), 1e-2);
}

TEST(Integrator, AnisotropicFreeRotorConservesMomentumAndEnergy) {
  // Torque-free asymmetric top spinning near its unstable middle axis (tumbling): angular
  // momentum is conserved exactly by the splitting, kinetic energy to O(dt²) with no drift.
  Elements el;
  const Vec3 I(1.0, 2.0, 3.0);
  el.add(body(Vec3::Zero(), 1.0, I));
  el.w[0] = Vec3(0.05, 20.0, 0.05);
  IntegratorSettings s;
  s.dt = 0.002;
  System sys(std::move(el), s);
  sys.initialize();
  const Elements& e = sys.elements();
  auto L = [&] { return Vec3(e.q[0] * (I.cwiseProduct(e.q[0].conjugate() * e.w[0]))); };
  const Vec3 L0 = L();
  const double K0 = sys.energy().kinetic();
  double max_dk = 0, min_align = 1;
  for (int c = 0; c < 400; ++c) {
    sys.run(50);
    max_dk = std::max(max_dk, std::abs(sys.energy().kinetic() - K0) / K0);
    min_align = std::min(min_align, (e.q[0] * Vec3::UnitY()).dot(L0.normalized()));
  }
  EXPECT_LT((L() - L0).norm(), 1e-9 * L0.norm());
  EXPECT_LT(max_dk, 2e-3);
  // The body flipped over (the middle axis is unstable), so the test exercised real tumbling.
  EXPECT_LT(min_align, -0.9);
}

TEST(Integrator, AxialBondOscillatesAtItsAnalyticalPeriod) {
  // Two segments joined by the axial spring kn·A: ω = √(kn A / μ), μ = m/2.
  const double k = cnt::kBondKn * cnt::kBondArea;
  const double omega = std::sqrt(k / (0.5 * cnt::kMass));
  IntegratorSettings s;
  s.dt = 0.05 / omega;  // Verlet's period error (ω dt)²/24 is then 1e-4
  System sys = two_segments(s);
  sys.elements().v[1] = Vec3(0.05, 0, 0);
  sys.initialize();
  const double period = 2 * std::numbers::pi / omega;
  // Find successive upward zero crossings of the stretch.
  auto stretch = [&] {
    const auto& x = sys.elements().x;
    return (x[1] - x[0]).norm() - cnt::kSegmentLength;
  };
  double prev = stretch(), t_first = -1, t_last = -1;
  int crossings = 0;
  while (sys.time() < 20 * period) {
    sys.step();
    const double s = stretch();
    if (prev < 0 && s >= 0) {
      const double t = sys.time() - sys.dt() * s / (s - prev);
      if (t_first < 0) t_first = t;
      t_last = t;
      ++crossings;
    }
    prev = s;
  }
  ASSERT_GE(crossings, 10);
  const double measured = (t_last - t_first) / (crossings - 1);
  EXPECT_NEAR(measured, period, 2e-3 * period);
}

TEST(Integrator, CriticalStepOfAChainBracketsTheExactLimit) {
  // For a long chain the highest axial mode has ω = 2√(k/m), so the exact Verlet limit is
  // √(m/k) (63.7 fs for the CNT bond); the bound must not exceed the exact limit of the
  // stiffest mode and must not be absurdly conservative.
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 30, 0);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  System sys(std::move(el));
  sys.add(std::move(bonds));
  sys.initialize();
  const double axial_limit = std::sqrt(cnt::kMass / (cnt::kBondKn * cnt::kBondArea));
  EXPECT_LT(sys.critical_dt(), axial_limit);
  EXPECT_GT(sys.critical_dt(), 0.5 * axial_limit);
  EXPECT_DOUBLE_EQ(sys.dt(), sys.settings().safety * sys.critical_dt());
  // The thesis ran CNT systems at 30 fs: the auto step is of that order.
  EXPECT_GT(sys.dt(), 0.020);
  EXPECT_LT(sys.dt(), 0.040);
}

TEST(Integrator, AutoStepRunsStablyJustBelowTheTrueLimit) {
  // At safety 0.95 of the bound, a chain with random velocities must stay bounded: the bound is
  // conservative. The exact limit itself is where the energy would run away.
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 30, 0);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 0.05);
  for (std::size_t i = 0; i < el.size(); ++i) {
    el.v[i] = Vec3(g(rng), g(rng), g(rng));
    el.w[i] = Vec3(g(rng), g(rng), g(rng));
  }
  IntegratorSettings s;
  s.safety = 0.95;
  s.guard_energy_tolerance = 1e9;  // this test watches the energy itself
  System sys(std::move(el), s);
  sys.add(std::move(bonds));
  sys.initialize();
  const double e0 = sys.energy().total();
  double worst = 0;
  for (int c = 0; c < 40; ++c) {
    sys.run(500);
    worst = std::max(worst, std::abs(sys.energy().total() - e0));
  }
  // Verlet near its limit fluctuates strongly but stays bounded; an unstable mode would have
  // grown by many orders of magnitude over 20 000 steps.
  EXPECT_LT(worst, 2.0 * e0);
}

TEST(Integrator, StepAboveTheLimitIsRefusedWithTheLimit) {
  System probe = two_segments();
  probe.initialize();
  const double limit = probe.max_safe_dt();
  IntegratorSettings s;
  s.dt = 3.0 * limit;
  System sys = two_segments(s);
  try {
    sys.initialize();
    FAIL() << "a step 3x over the limit was accepted";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("above the safe limit"), std::string::npos) << m;
    EXPECT_NE(m.find(std::to_string(limit).substr(0, 6)), std::string::npos) << m;
  }
}

TEST(Integrator, BadSettingsAreRefusedNamingTheSetting) {
  const std::pair<std::function<void(IntegratorSettings&)>, std::string> cases[] = {
      {[](IntegratorSettings& s) { s.dt = std::nan(""); }, "dt"},
      {[](IntegratorSettings& s) { s.dt = -1.0; }, "dt"},
      {[](IntegratorSettings& s) { s.dt = std::numeric_limits<double>::infinity(); }, "dt"},
      {[](IntegratorSettings& s) { s.safety = 2.0; }, "safety"},
      {[](IntegratorSettings& s) { s.local_damping = 1.0; }, "local_damping"},
      {[](IntegratorSettings& s) { s.local_damping = std::nan(""); }, "local_damping"},
      {[](IntegratorSettings& s) { s.skin = 0.0; }, "skin"},
      {[](IntegratorSettings& s) { s.skin = 1e300; }, "skin"},
      {[](IntegratorSettings& s) { s.threads = -1; }, "threads"},
  };
  for (const auto& [edit, field] : cases) {
    IntegratorSettings s;
    edit(s);
    System sys = two_segments(s);
    try {
      sys.initialize();
      ADD_FAILURE() << "accepted a bad " << field;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }
}

TEST(Integrator, NonFiniteElementInputIsRefused) {
  const double bad[] = {std::nan(""), std::numeric_limits<double>::infinity()};
  for (double b : bad) {
    Elements el;
    ElementInit e = cnt_segment(Vec3::Zero(), Quat::Identity(), 0, 0);
    EXPECT_THROW(el.add([&] {
      auto c = e;
      c.x.y() = b;
      return c;
    }()),
                 std::invalid_argument);
    EXPECT_THROW(el.add([&] {
      auto c = e;
      c.v.z() = b;
      return c;
    }()),
                 std::invalid_argument);
    EXPECT_THROW(el.add([&] {
      auto c = e;
      c.w.x() = b;
      return c;
    }()),
                 std::invalid_argument);
    EXPECT_THROW(el.add([&] {
      auto c = e;
      c.mass = b;
      return c;
    }()),
                 std::invalid_argument);
    EXPECT_THROW(el.add([&] {
      auto c = e;
      c.q.w() = b;
      return c;
    }()),
                 std::invalid_argument);
    EXPECT_THROW(el.add([&] {
      auto c = e;
      c.radius = b;
      return c;
    }()),
                 std::invalid_argument);
    EXPECT_EQ(el.size(), 0u);
  }
  Elements el;
  EXPECT_THROW(el.add([] {
    auto c = cnt_segment(Vec3::Zero(), Quat::Identity(), 0, 0);
    c.mass = -1;
    return c;
  }()),
               std::invalid_argument);
  // A non-finite external load set after construction is caught before it is integrated.
  System sys = two_segments();
  sys.elements().f_ext[1] = Vec3(std::nan(""), 0, 0);
  EXPECT_THROW(sys.run(10), NumericalError);
}

TEST(Integrator, GuardStopsARunThatGoesUnstableAndNamesStepAndElement) {
  // Stiffen the bond a million-fold after the step was fixed: the integration must blow up, and
  // the guard must stop it with a message, before anything non-finite is produced.
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 10, 0);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  el.v[5] = Vec3(0.01, 0.02, 0);
  System sys(std::move(el));
  ParallelBond* b = sys.add(std::move(bonds));
  sys.initialize();
  for (Bond& bond : b->bonds()) {
    bond.k.kn_area *= 1e6;
    bond.k.ks_area *= 1e6;
  }
  try {
    sys.run(100000);
    FAIL() << "unstable run was not stopped";
  } catch (const NumericalError& e) {
    const std::string m = e.what();
    EXPECT_GT(e.step(), 0);
    EXPECT_LT(e.step(), 100000);
    EXPECT_NE(m.find("step"), std::string::npos) << m;
    EXPECT_NE(m.find("element"), std::string::npos) << m;
    EXPECT_NE(m.find("dt"), std::string::npos) << m;
  }
}

TEST(Integrator, FixedAndPrescribedDofsMoveAsTold) {
  System sys = two_segments();
  Elements& el = sys.elements();
  el.fix_all(0);
  el.dof[1][0] = DofMode::Prescribed;
  el.v_prescribed[1] = Vec3(0.01, 0, 0);  // pulls the bond at 10 m/s
  el.dof[1][3] = DofMode::Prescribed;
  el.w_prescribed[1] = Vec3(0.02, 0, 0);  // twists it
  sys.run(1000);
  EXPECT_EQ(sys.elements().x[0], Vec3::Zero());
  EXPECT_NEAR(sys.elements().x[1].x() - cnt::kSegmentLength, 0.01 * sys.time(), 1e-12);
  // The work done by the constraint equals the energy stored (no damping): the balance closes.
  const auto& E = sys.energy();
  EXPECT_GT(E.external_work, 0);
  EXPECT_LT(sys.energy_balance_error(), 2e-3);
  // Stored twist energy ½ ks J θ² with θ = ω t.
  const double theta = 0.02 * sys.time();
  const double e_twist = E.potential.stored[static_cast<int>(EnergyTerm::BondTorsion)];
  EXPECT_NEAR(e_twist, 0.5 * cnt::kBondKs * cnt::kBondJ * theta * theta, 0.01 * e_twist);
}

TEST(Integrator, EnergyBalanceClosesWithLocalDampingAndExternalWork) {
  // A tube pulled by a constant end force under local damping: W_ext = ΔU + ΔK + E_dissipated.
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 10, 0);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  el.fix_all(0);
  el.f_ext[9] = Vec3(0.5, 0.2, 0.0);
  IntegratorSettings s;
  s.local_damping = 0.3;
  System sys(std::move(el), s);
  sys.add(std::move(bonds));
  sys.run(20000);
  const auto& E = sys.energy();
  EXPECT_GT(E.dissipated, 0.1 * E.external_work);
  EXPECT_LT(sys.energy_balance_error(), 1e-2);
}
