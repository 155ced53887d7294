// Greenhill's twist buckling of one (10,10) tube (issue 17, item 1): a straight rod carrying an
// end torque M about its axis stays straight below M_c and buckles into a helix above it,
//   M_c = 2.86π·B/L  both ends clamped, the loaded one free only to turn about the axis
//                    (kL = 8.987 = 2.861π, the root of tan(kL/2) = kL/2, k = M/B);
//   M_c = 2π·B/L     both ends pinned (on the axis, tilting freely),
// with B = kn·I·T the tube's bending stiffness (model.md §3, 2237 eV·nm) and L the distance
// between the end segments' centres. Nothing here comes from the code's own output: B and L are
// the model's constants, M_c the classical elastic-rod result.
//
// The set-up: a 50-segment tube (L = 66.4 nm: M_c = 48.5 nN·nm clamped, 33.9 nN·nm pinned) along
// z, bonds only (no vdW: Greenhill's rod has no self-contact), no damping. A lateral perturbation
// of 1e-3 nm (half a sine wave in x over the interior segments) is seeded, the torque about +z on
// the far end segment is ramped over 50 ps by the twist protocol's per-element grip load (a
// moment of fixed direction) and held 300 ps. The loaded end stays on the axis (x, y fixed) and
// slides along it freely. Clamped: the near end is fixed, the loaded end turns about z only, so
// the torque's work is −M·φ, a potential. Pinned: the near end's position is fixed and it tilts
// freely, its axial rotation held so that it reacts the torque; the loaded end tilts freely.
//
// Why not the issue's "clamped, the other end on the axis with its axial rotation free" with a
// free-tilting loaded end: a moment of fixed direction on an end that tilts is not conservative
// (Ziegler's axial torque). For that case the static criterion has no critical torque at all (the
// buckling condition 1 − e^{ix} + ix − ix²/(2(i + x)) = 0, x = kL, has no real root), and in our
// runs the perturbation grows slowly at every torque scanned, down to 0.7 M_c (the scan below).
//
// Bounded: below M_c the lowest bending mode stays stable; as the torque rises its frequency
// falls, ω² ∝ 1 − (M/M_c)² to first order, so an adiabatic oscillation's amplitude grows as
// ω^(−1/2): at 0.8 M_c by (1 − 0.64)^(−1/4) = 1.3. We allow 3 (the seeded shape is not exactly
// the lowest mode, and the ramp is not perfectly adiabatic) — far below the growth above M_c.
// Grows: above M_c the mode is unstable. The largest offset is asserted to grow more than
// a hundredfold (the run stops at a thousandfold): at 1.2 M_c clamped, at 1.5 M_c pinned (at
// 1.2 M_c the pinned tube needs ~400 ps; near M_c the growth is slow).
// Measured with the scan (600 ps holds): clamped x2.9 at 0.95, x35 at 1.00, x1000 at 1.05;
// pinned x2.3 at 0.95, x10 at 1.00, x114 at 1.05: both thresholds within 5 % of Greenhill's.
//
// Post-buckling: no energy split against the elastica is tested. Under a held dead torque with
// the loaded end free to slide, nothing bounds the work M·φ once the tube coils (it keeps
// winding until the run guard stops it), so there is no post-buckled equilibrium to compare with
// Love's helix, which needs a prescribed end force or end distance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <numbers>

#include "mdem/core/cnt.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/integrate/system.h"
#include "mdem/protocol/twist_protocol.h"
#include "mdem/scene/tube_builder.h"

namespace mdem {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kSegments = 50;
constexpr double kSeed = 1e-3;  // nm
constexpr double kRampPs = 50, kHoldPs = 300;

// The ends: both clamped, the loaded one free to turn about the axis only (its tangent held along
// z, so the torque's work is -M·φ, a potential: Greenhill's 2.86π), or both pinned (tilting free;
// the near end's axial rotation held to react the torque: 2π). `IssueClampedHinge` is the issue's
// set-up, near end clamped and the loaded end tilting freely under the fixed-direction torque: a
// non-conservative load (Ziegler) with no static critical torque at all, only scanned below.
enum class NearEnd { Clamped, Pinned, IssueClampedHinge };

double bending_stiffness() { return cnt::kBondKn * cnt::kBondI * cnt::kSegmentLength; }  // eV·nm
double tube_length() { return (kSegments - 1) * cnt::kSegmentLength; }

// Greenhill's critical axial torque (eV).
double greenhill_torque(NearEnd e) {
  return (e == NearEnd::Pinned ? 2.0 : 2.86) * kPi * bending_stiffness() / tube_length();
}

struct Growth {
  double ramp_max = 0;  // largest lateral offset of a segment centre during the ramp (nm)
  double hold_max = 0;  // ... during the hold
};

// Runs the tube under `ratio` × M_c and returns the largest lateral offsets.
Growth perturbation_growth(NearEnd near_end, double ratio, double hold_ps = kHoldPs) {
  Elements el;
  const std::vector<std::size_t> ids =
      add_straight_tube(el, Vec3::Zero(), Vec3::UnitZ(), kSegments, 0);
  // The bonds' rest state is the straight tube; the perturbation is then a stressed offset.
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  for (int k = 1; k + 1 < kSegments; ++k)
    el.x[ids[k]].x() += kSeed * std::sin(kPi * k / (kSegments - 1));
  const std::size_t a = ids.front(), b = ids.back();
  if (near_end == NearEnd::Pinned) {
    for (int k : {0, 1, 2, 5}) el.dof[a][k] = DofMode::Fixed;
  } else {
    el.fix_all(a);
  }
  el.dof[b][0] = el.dof[b][1] = DofMode::Fixed;
  if (near_end == NearEnd::Clamped) el.dof[b][3] = el.dof[b][4] = DofMode::Fixed;

  IntegratorSettings s;
  s.local_damping = 0;
  s.threads = 1;
  System sys(std::move(el), s);
  sys.add(std::move(bonds));
  TwistLoading l;
  l.torque_max = ratio * greenhill_torque(near_end);
  l.rate = l.torque_max / kRampPs;
  l.hold = hold_ps;
  l.grip_load = GripLoad::PerElement;
  // Grip a is the held end: its moment acts on fixed rotational DOFs about z and does nothing.
  sys.add_updater(
      std::make_shared<TwistProtocol>(l, std::vector<std::size_t>{a}, std::vector<std::size_t>{b}));
  sys.initialize();

  Growth g;
  const long chunk = 20;
  while (sys.time() < kRampPs + hold_ps) {
    sys.run(chunk);
    double off = 0;
    for (std::size_t i : ids)
      off = std::max(off, std::hypot(sys.elements().x[i].x(), sys.elements().x[i].y()));
    double& m = sys.time() < kRampPs ? g.ramp_max : g.hold_max;
    m = std::max(m, off);
    // Grown a thousandfold: buckled. Stop there; the coil would go on winding under the held
    // torque (nothing bounds the work of a dead torque on a free end) until the run guard stops it.
    if (off > 1000 * kSeed) break;
  }
  return g;
}

TEST(Greenhill, CriticalTorqueFromTheModelConstants) {
  // The issue's figure: 2.86π·B/L = 48.5 nN·nm for the 50-segment tube (B = 2237 eV·nm).
  EXPECT_NEAR(bending_stiffness(), 2236.8, 0.1);
  EXPECT_NEAR(units::to_nNnm(greenhill_torque(NearEnd::Clamped)), 48.5, 0.05);
  EXPECT_NEAR(units::to_nNnm(greenhill_torque(NearEnd::Pinned)), 33.9, 0.05);
}

void expect_threshold(NearEnd e, double above_ratio) {
  const Growth below = perturbation_growth(e, 0.8);
  EXPECT_LT(below.hold_max, 3 * kSeed) << "0.8 M_c: ramp " << below.ramp_max << " nm";
  const Growth above = perturbation_growth(e, above_ratio);
  EXPECT_GT(above.hold_max, 100 * kSeed) << above_ratio << " M_c: ramp " << above.ramp_max << " nm";
}

TEST(Greenhill, ClampedTubeBucklesAboveTwoPointEightSixPiBOverL) {
  expect_threshold(NearEnd::Clamped, 1.2);
}

TEST(Greenhill, PinnedPinnedTubeBucklesAboveTwoPiBOverL) { expect_threshold(NearEnd::Pinned, 1.5); }

// The bracket of the threshold: the largest growth over the hold for torques from 0.7 to 1.5 M_c,
// the three set-ups. Not run by default (36 runs, ~20 s); run with
// --gtest_also_run_disabled_tests, GH_HOLD=<ps> for another hold.
TEST(Greenhill, DISABLED_ThresholdScan) {
  const char* env = std::getenv("GH_HOLD");
  const double hold = env ? std::atof(env) : kHoldPs;
  for (NearEnd e : {NearEnd::Clamped, NearEnd::Pinned, NearEnd::IssueClampedHinge})
    for (double r : {0.7, 0.8, 0.85, 0.9, 0.95, 1.0, 1.05, 1.1, 1.15, 1.2, 1.3, 1.5}) {
      const Growth g = perturbation_growth(e, r, hold);
      std::printf("%s M/M_c = %.2f: largest offset ramp %.3g nm, hold %.3g nm (x%.3g)\n",
                  e == NearEnd::Clamped  ? "clamped-clamped"
                  : e == NearEnd::Pinned ? "pinned-pinned"
                                         : "clamped-hinge",
                  r, g.ramp_max, g.hold_max, g.hold_max / kSeed);
    }
}

}  // namespace
}  // namespace mdem
