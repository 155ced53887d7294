// The largest vibration frequency by Lanczos over differenced forces (integrate/spectrum.h),
// against closed forms: a free chain of grains in linear contact (the discrete string's top mode),
// the same chain with its first grain fixed (the mask of fixed degrees of freedom), and one CNT
// parallel bond between two segments (stretch, twist and the two shear-bending blocks from the
// bond's stiffness, with the segments' rotational inertia). Also: the engine's automatic step,
// a Gershgorin bound, stays below the true critical step; the state is left as it was; bad
// settings are refused by name.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "mdem/core/cnt.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/contact/linear_contact.h"
#include "mdem/force/contact/np_cnt_contact.h"
#include "mdem/force/contact/np_np_contact.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/integrate/spectrum.h"
#include "mdem/integrate/system.h"
#include "mdem/scene/grain.h"
#include "mdem/scene/nanoparticle.h"
#include "mdem/scene/tube_builder.h"

namespace mdem {
namespace {

constexpr double kPi = std::numbers::pi;
const double kE = units::GPa(79.0);  // Au

IntegratorSettings one_thread() {
  IntegratorSettings s;
  s.threads = 1;
  return s;
}

// n Au grains of radius 1 nm on the x axis, each overlapping the next by 0.01 nm.
System chain(int n, bool fix_first) {
  Elements el;
  for (int i = 0; i < n; ++i) el.add(grain_element(Vec3(1.99 * i, 0, 0), 1.0, gold()));
  if (fix_first) el.fix_all(0);
  System sys(std::move(el), one_thread());
  sys.add(std::make_unique<LinearContact>(kE, 1.0));
  sys.initialize();
  return sys;
}

SpectrumSettings tight() {
  SpectrumSettings s;
  s.tolerance = 1e-9;
  return s;
}

TEST(Spectrum, FreeChainOfGrainsHasTheDiscreteStringsTopMode) {
  const int n = 8;
  System sys = chain(n, false);
  const double k = sys.find<LinearContact>()->stiffness(1.0, 1.0);
  const double m = sys.elements().mass[0];
  // Free–free chain of n masses and n − 1 springs: ω_j = 2√(k/m) sin(jπ/2n), j = 0..n−1. The
  // contacts' repulsion makes the transverse modes slightly unstable (negative), not larger.
  const double expected = 2.0 * std::sqrt(k / m) * std::sin((n - 1) * kPi / (2.0 * n));
  const SpectrumEstimate e = largest_frequency(sys, tight());
  EXPECT_TRUE(e.converged);
  EXPECT_NEAR(e.omega_max / expected, 1.0, 1e-6) << e.omega_max << " vs " << expected;
  EXPECT_NEAR(e.critical_dt, 2.0 / expected, 1e-6 * 2.0 / expected);
  EXPECT_TRUE(e.smooth);
  EXPECT_NEAR(e.omega_fine / e.omega_max, 1.0, 1e-6);
  // The automatic step's bound is below the true limit (here 2/√(4k/m) against 2/ω_max).
  EXPECT_LE(sys.critical_dt(), e.critical_dt);
  EXPECT_NEAR(sys.critical_dt(), 1.0 / std::sqrt(k / m), 1e-9 / std::sqrt(k / m));
}

TEST(Spectrum, FixedGrainsDegreesOfFreedomAreLeftOut) {
  const int n = 8;
  System sys = chain(n, true);
  const double k = sys.find<LinearContact>()->stiffness(1.0, 1.0);
  const double m = sys.elements().mass[0];
  // Fixed–free chain of M = n − 1 masses: ω_j = 2√(k/m) sin((2j − 1)π / (2(2M + 1))), j = 1..M.
  const int M = n - 1;
  const double expected =
      2.0 * std::sqrt(k / m) * std::sin((2.0 * M - 1.0) * kPi / (2.0 * (2.0 * M + 1.0)));
  const SpectrumEstimate e = largest_frequency(sys, tight());
  EXPECT_TRUE(e.converged);
  EXPECT_NEAR(e.omega_max / expected, 1.0, 1e-6) << e.omega_max << " vs " << expected;
  // And unfixed it is the free chain's, which is higher: the mask changed the answer.
  System free = chain(n, false);
  EXPECT_GT(largest_frequency(free, tight()).omega_max, 1.001 * expected);
}

// Largest eigenvalue of the mass-weighted 4×4 shear–bending block of one bond along x between
// two segments of mass m and transverse moment I, bond points a from each centre: energy
// ½ ksA (y2 − y1 − a(θ1 + θ2))² + ½ knI (θ2 − θ1)² in (y1, θ1, y2, θ2).
double shear_bending_top(double ksA, double knI, double a, double m, double I) {
  Eigen::Vector4d g(-1, -a, 1, -a);  // d(gap)/d(y1, θ1, y2, θ2)
  Eigen::Vector4d b(0, -1, 0, 1);    // d(θ2 − θ1)
  Eigen::Matrix4d K = ksA * g * g.transpose() + knI * b * b.transpose();
  const Eigen::Vector4d w(1 / std::sqrt(m), 1 / std::sqrt(I), 1 / std::sqrt(m), 1 / std::sqrt(I));
  const Eigen::Matrix4d Kw = w.asDiagonal() * K * w.asDiagonal();
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(Kw).eigenvalues().maxCoeff();
}

// The top frequency of two segments joined by one bond of stiffness k, the segments' principal
// moments set to `inertia` (body x along the tube), against the closed form; also checks that the
// automatic step's bound is below it.
void expect_bond_modes(const BondStiffness& k, const Vec3& inertia, const char* top) {
  SCOPED_TRACE(top);
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 2, 0);
  for (std::size_t i = 0; i < el.size(); ++i) el.inertia[i] = inertia;
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, k);
  const double m = el.mass[0];
  System sys(std::move(el), one_thread());
  sys.add(std::move(bonds));
  sys.initialize();
  const double a = 0.5 * cnt::kSegmentLength;
  const double stretch = 2.0 * k.kn_area / m;
  const double twist = 2.0 * k.ks_polar / inertia.x();
  // Translation along y goes with rotation about z, along z with rotation about y.
  const double bend_y = shear_bending_top(k.ks_area, k.kn_inertia, a, m, inertia.z());
  const double bend_z = shear_bending_top(k.ks_area, k.kn_inertia, a, m, inertia.y());
  const double expected = std::sqrt(std::max({stretch, twist, bend_y, bend_z}));
  const SpectrumEstimate e = largest_frequency(sys, tight());
  EXPECT_TRUE(e.converged);
  EXPECT_TRUE(e.smooth);
  EXPECT_NEAR(e.omega_max / expected, 1.0, 1e-5)
      << "stretch " << std::sqrt(stretch) << " twist " << std::sqrt(twist) << " bending "
      << std::sqrt(bend_y) << ", " << std::sqrt(bend_z);
  EXPECT_LE(sys.critical_dt(), e.critical_dt);
}

TEST(Spectrum, OneBondsModesWithRotationsAboutEachBodyAxis) {
  const BondStiffness cnt = cnt_bond_stiffness();
  const double I = cnt::kInertia;
  // The (10,10) CNT's: stretch is the top mode.
  expect_bond_modes(cnt, Vec3(I, I, I), "stretch");
  // A stiff twist on a light axial moment: the top mode is a rotation about body x.
  BondStiffness twist = cnt;
  twist.ks_polar *= 3;
  expect_bond_modes(twist, Vec3(0.5 * I, I, I), "twist");
  // Stiff bending, moments unequal about y and z: the top mode bends about the lighter axis.
  BondStiffness bend = cnt;
  bend.kn_inertia *= 4;
  expect_bond_modes(bend, Vec3(I, 0.6 * I, 1.3 * I), "bending about y");
  expect_bond_modes(bend, Vec3(I, 1.3 * I, 0.6 * I), "bending about z");
}

// Two bonded 12-segment tubes crossing at 30° in vdW contact, 0.2 nm closer than the well.
System two_tubes() {
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 12, 0);
  const Vec3 dir = Vec3(std::cos(kPi / 6), std::sin(kPi / 6), 0);
  add_straight_tube(el, Vec3(8.1, 0, 1.5) - 5.5 * cnt::kSegmentLength * dir, dir, 12, 1);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  System sys(std::move(el), one_thread());
  sys.add(std::move(bonds));
  sys.add(std::make_unique<AnisotropicVdw>());
  sys.initialize();
  return sys;
}

TEST(Spectrum, TheAutomaticStepsBoundIsBelowTheTrueCriticalStep) {
  System sys = two_tubes();
  const SpectrumEstimate e = largest_frequency(sys);
  EXPECT_TRUE(e.converged);
  EXPECT_TRUE(e.smooth);
  EXPECT_GT(e.omega_max, 0);
  EXPECT_LE(sys.critical_dt(), e.critical_dt);
}

// Two single segments crossed at 90° (axes x and y), centres on the z axis R apart.
System crossed_pair(double R) {
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 1, 0);
  add_straight_tube(el, Vec3(0, 0, R), Vec3::UnitY(), 1, 1);
  System sys(std::move(el), one_thread());
  sys.add(std::make_unique<AnisotropicVdw>());
  sys.initialize();
  return sys;
}

TEST(Spectrum, DampedCriticalStepIsLoweredByTheLargestElementsDashpots) {
  // System::damped_critical_dt(ω) = (2/ω)(√(1+ζ²) − ζ), the damped oscillator's limit under
  // velocity Verlet, with the largest element's ζ = Σc/(m ω): what the tensile job checks a
  // caller's step against after measuring ω. Two segments of two tubes crossed 1.5 nm apart with
  // a dashpot of ratio ψ: c = 2ψ√(m_eff k), m_eff = m/2 (thesis Eq. 33–34); a third segment out
  // of reach (20 nm) has no dashpot.
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 1, 0);
  add_straight_tube(el, Vec3(0, 0, 1.5), Vec3::UnitY(), 1, 1);
  add_straight_tube(el, Vec3(0, 0, 20.0), Vec3::UnitX(), 1, 2);
  const double omega = 12.5;  // rad/ps
  {
    System bare(el, one_thread());
    bare.add(std::make_unique<AnisotropicVdw>());
    bare.initialize();
    EXPECT_EQ(bare.damped_critical_dt(omega), 2.0 / omega);
  }
  ContactDampingParams dp;
  dp.ratio = 0.3;
  System sys(std::move(el), one_thread());
  sys.add(std::make_unique<AnisotropicVdw>());
  sys.add(std::make_unique<ViscousContactDamping>(dp));
  sys.initialize();
  const double c = 2.0 * 0.3 * std::sqrt(0.5 * cnt::kMass * 100.0);
  const double zeta = c / (cnt::kMass * omega);
  EXPECT_NEAR(sys.damped_critical_dt(omega), 2.0 / omega * (std::sqrt(1.0 + zeta * zeta) - zeta),
              1e-15);
  EXPECT_LT(sys.damped_critical_dt(omega), 2.0 / omega);
  EXPECT_EQ(sys.damped_critical_dt(0.0), std::numeric_limits<double>::infinity());
  EXPECT_EQ(sys.damped_critical_dt(-1.0), std::numeric_limits<double>::infinity());
  EXPECT_THROW(sys.damped_critical_dt(std::nan("")), std::invalid_argument);
}

TEST(Spectrum, AForceThatJumpsIsReportedNotTakenForAStiffness) {
  // model.md §4: W(R) = 90 (R/r)^-7.5 above R/r = 2.75 and constant below, so a crossed pair's
  // force jumps at R = 2.75 r (a kink in U). Straddling it, the difference quotient reads
  // jump / move: ten times larger at a tenth of the move.
  const VdwParams p;
  System kinked = crossed_pair(p.w_knee * p.radius);
  const SpectrumEstimate k = largest_frequency(kinked);
  EXPECT_FALSE(k.smooth);
  EXPECT_GT(k.omega_fine, 2.0 * k.omega_max) << k.omega_fine << " vs " << k.omega_max;
  // 0.01 nm away from the knee the same pair is smooth.
  System off = crossed_pair(p.w_knee * p.radius + 0.01);
  const SpectrumEstimate o = largest_frequency(off);
  EXPECT_TRUE(o.smooth) << o.omega_fine << " vs " << o.omega_max;
  EXPECT_GT(o.omega_max, 0);
}

TEST(Spectrum, WithoutTheCheckTwoForceEvaluationsPerStep) {
  System sys = chain(8, false);
  SpectrumSettings s = tight();
  s.check_smoothness = false;
  const SpectrumEstimate e = largest_frequency(sys, s);
  EXPECT_EQ(e.force_evaluations, 2L * e.iterations);
  EXPECT_EQ(e.omega_fine, 0);
}

Vec3 random_unit(std::mt19937_64& g) {
  std::normal_distribution<double> n;
  return Vec3(n(g), n(g), n(g)).normalized();
}

// The automatic step's critical step is a bound: at most the true 2/ω_max of the state, for a
// pair of each contact kind at random separations and orientations over its whole reach
// (overlapping, in the well, in the cutoff ramp). A state where the forces are not smooth at the
// difference's scale (a pair at a kink of its law) has no ω_max to compare with and is skipped.
// Two NPs have one stiff mode, the radial one, which Gershgorin's bound gives exactly: the
// comparison allows the differences' error (1e-6).
TEST(Spectrum, TheBoundHoldsForEveryContactAtRandomStates) {
  std::mt19937_64 g(11);
  std::uniform_real_distribution<double> u(0, 1);
  const auto check = [&](const char* what, Elements el, auto add_models, double R) {
    System sys(std::move(el), one_thread());
    add_models(sys);
    sys.initialize();
    SpectrumSettings s = tight();
    s.tolerance = 1e-10;
    const SpectrumEstimate e = largest_frequency(sys, s);
    if (!e.smooth || !(e.omega_max > 0)) return 0;
    EXPECT_LE(sys.critical_dt(), e.critical_dt * (1 + 1e-6))
        << what << " at R = " << R << ": bound " << sys.critical_dt() << " ps, true "
        << e.critical_dt << " ps";
    return 1;
  };
  int compared = 0;
  for (int k = 0; k < 60; ++k) {
    {  // two CNT segments of different tubes
      const double R = 0.3 + u(g) * 5.0;
      Elements el;
      el.add(cnt_segment(Vec3::Zero(), quat_from_axis(random_unit(g)), 0, 0));
      el.add(cnt_segment(R * random_unit(g), quat_from_axis(random_unit(g)), 1, 0));
      compared += check(
          "CNT-CNT", std::move(el), [](System& s) { s.add(std::make_unique<AnisotropicVdw>()); },
          R);
    }
    {  // an NP beside a segment
      const double R = 1.0 + u(g) * 4.4;
      Elements el;
      el.add(cnt_segment(Vec3::Zero(), quat_from_axis(random_unit(g)), 0, 0));
      el.add(nanoparticle(R * random_unit(g)));
      compared += check(
          "NP-CNT", std::move(el), [](System& s) { s.add(std::make_unique<NpCntContact>()); }, R);
    }
    {  // two NPs, from the start of the linear branch (D = 0.1: below it the law has no
       // curvature, and a repulsive central force no positive stiffness) to the cutoff
      const double R = 5.26 + u(g) * 2.74;
      Elements el;
      el.add(nanoparticle(Vec3::Zero()));
      el.add(nanoparticle(R * random_unit(g)));
      compared += check(
          "NP-NP", std::move(el), [](System& s) { s.add(std::make_unique<NpNpContact>()); }, R);
    }
  }
  EXPECT_GE(compared, 175) << compared;  // of 180: only states at a kink are skipped
}

TEST(Spectrum, LeavesTheStateAsItWas) {
  System sys = two_tubes();
  const Elements before = sys.elements();
  const double energy = sys.energy().total();
  largest_frequency(sys);
  const Elements& after = sys.elements();
  for (std::size_t i = 0; i < before.size(); ++i) {
    EXPECT_EQ(after.x[i], before.x[i]);
    EXPECT_EQ(after.q[i].coeffs(), before.q[i].coeffs());
    EXPECT_EQ(after.f[i], before.f[i]);
    EXPECT_EQ(after.t[i], before.t[i]);
  }
  EXPECT_EQ(sys.energy().total(), energy);
}

TEST(Spectrum, AStateWithNothingFreeHasNoLimit) {
  Elements el;
  el.add(grain_element(Vec3::Zero(), 1.0, gold()));
  el.add(grain_element(Vec3(1.99, 0, 0), 1.0, gold()));
  el.fix_all(0);
  el.fix_all(1);
  System sys(std::move(el), one_thread());
  sys.add(std::make_unique<LinearContact>(kE, 1.0));
  const SpectrumEstimate e = largest_frequency(sys);
  EXPECT_TRUE(e.converged);
  EXPECT_EQ(e.omega_max, 0);
  EXPECT_EQ(e.critical_dt, std::numeric_limits<double>::infinity());
  EXPECT_EQ(e.force_evaluations, 0);
}

TEST(Spectrum, BadSettingsAreRefusedByName) {
  System sys = chain(3, false);
  const auto refused = [&](SpectrumSettings s, const std::string& what) {
    try {
      largest_frequency(sys, s);
      ADD_FAILURE() << "accepted " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (int it : {-1, 0, 1, 10001, 1 << 30}) refused({.max_iterations = it}, "max_iterations");
  for (double t : {0.0, -1e-3, 1.0, 5.0, nan, inf}) refused({.tolerance = t}, "tolerance");
  for (double d : {0.0, -1e-5, 0.02, 1e9, nan, inf}) refused({.displacement = d}, "displacement");
}

}  // namespace
}  // namespace mdem
