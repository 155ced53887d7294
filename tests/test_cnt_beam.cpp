// One tube against beam theory (model.md §3): a chain of parallel-bonded segments is a
// Timoshenko beam with E = kn·T, G = ks·T, bending stiffness B = kn·I·T, torsion G·J, axial E·A.
#include <gtest/gtest.h>

#include <cmath>

#include "mdem/core/cnt.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/integrate/system.h"
#include "mdem/scene/tube_builder.h"
#include "support.h"

using namespace mdem;

namespace {

constexpr double kT = cnt::kSegmentLength;
const double kE = cnt::kBondKn * kT;  // eV/nm³
const double kG = cnt::kBondKs * kT;

// A cantilever: segment 0 clamped, load applied at the centre of the last segment, so the beam
// length is L = (n−1)·T. Relaxed to static equilibrium with local damping.
struct Cantilever {
  System sys;
  std::size_t tip;
  double length;
};

Cantilever make_cantilever(int n) {
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), n, 0);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  el.fix_all(0);
  IntegratorSettings s;
  s.local_damping = 0.7;
  Cantilever c{System(std::move(el), s), static_cast<std::size_t>(n - 1), (n - 1) * kT};
  c.sys.add(std::move(bonds));
  return c;
}

}  // namespace

TEST(CntBeam, CantileverDeflectsAsTimoshenko) {
  // δ = F L³/(3 B) + F L/(G A), B = kn·I·T (shear coefficient 1: the ring's shear spring ks·A).
  Cantilever c = make_cantilever(21);
  const double F = 0.004;  // eV/nm: δ/L ≈ 1 %, small-deflection regime
  c.sys.elements().f_ext[c.tip] = Vec3(0, F, 0);
  const long steps = mdem::testing::relax(c.sys, 1e-4 * F, 1e-12, 2'000'000);
  ASSERT_LT(steps, 2'000'000) << "did not reach equilibrium";
  const double L = c.length;
  const double B = cnt::kBondKn * cnt::kBondI * kT;
  const double expected = F * L * L * L / (3 * B) + F * L / (kG * cnt::kBondArea);
  const double delta = c.sys.elements().x[c.tip].y();
  EXPECT_NEAR(delta, expected, 0.02 * expected) << "deflection " << delta << " nm";
  // The tip slope is F L²/(2B) in bending (the shear spring adds no rotation).
  const double slope = (c.sys.elements().q[c.tip] * Vec3::UnitX()).y();
  EXPECT_NEAR(slope, F * L * L / (2 * B), 0.02 * F * L * L / (2 * B));
}

TEST(CntBeam, TwistedTubeStoresTSquaredLOverTwoGJ) {
  // Torque T about the axis at the free end: twist angle T L/(G J), energy T² L/(2 G J).
  Cantilever c = make_cantilever(11);
  const double torque = 5.0;  // eV
  c.sys.elements().t_ext[c.tip] = Vec3(torque, 0, 0);
  const long steps = mdem::testing::relax(c.sys, 1e-5 * torque, 1e-12, 2'000'000);
  ASSERT_LT(steps, 2'000'000);
  const double L = c.length;
  const double GJ = kG * cnt::kBondJ;
  const double e = c.sys.energy().potential.stored[static_cast<int>(EnergyTerm::BondTorsion)];
  EXPECT_NEAR(e, torque * torque * L / (2 * GJ), 0.01 * torque * torque * L / (2 * GJ));
  const Quat& q = c.sys.elements().q[c.tip];
  const double angle = 2 * std::atan2(q.vec().x(), q.w());
  EXPECT_NEAR(angle, torque * L / GJ, 0.01 * torque * L / GJ);
  // Pure torsion: nothing else is stored.
  const auto& st = c.sys.energy().potential.stored;
  EXPECT_LT(st[static_cast<int>(EnergyTerm::BondBending)], 1e-9 * e);
  EXPECT_LT(st[static_cast<int>(EnergyTerm::BondTension)], 1e-9 * e);
}

TEST(CntBeam, AxialLoadStretchesByFLOverEA) {
  Cantilever c = make_cantilever(11);
  const double F = 5.0;  // eV/nm ≈ 0.8 nN
  c.sys.elements().f_ext[c.tip] = Vec3(F, 0, 0);
  const long steps = mdem::testing::relax(c.sys, 1e-5 * F, 1e-12, 2'000'000);
  ASSERT_LT(steps, 2'000'000);
  const double L = c.length;
  const double expected = F * L / (kE * cnt::kBondArea);
  const double stretch = c.sys.elements().x[c.tip].x() - L;
  EXPECT_NEAR(stretch, expected, 0.01 * expected);
  // Work of the constant load is 2× the stored energy at static equilibrium (Clapeyron); the rest
  // went into damping.
  const double stored = c.sys.energy().potential.total_stored();
  EXPECT_NEAR(stored, 0.5 * F * stretch, 0.01 * stored);
  EXPECT_NEAR(c.sys.energy().external_work, F * stretch, 0.01 * F * stretch);
}
