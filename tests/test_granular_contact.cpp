// Granular contacts (model.md §6, thesis Eq. 36): the linear frictionless grain–grain contact, the
// grain–platen contact and the spherical packing walls, each against a hand computation or a
// conservation law: Eq. 36's force and stiffness, no tension, Newton's third law, and undamped
// elastic collisions that conserve energy and momentum.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "mdem/core/units.h"
#include "mdem/force/contact/linear_contact.h"
#include "mdem/force/wall/planar_wall.h"
#include "mdem/force/wall/spherical_wall.h"
#include "mdem/integrate/system.h"
#include "mdem/scene/grain.h"

namespace mdem {
namespace {

constexpr double kPi = std::numbers::pi;
const double kE = units::GPa(79.0);  // Au

// Undamped, one thread. Collisions are tested at a hundredth of the critical step: at the default
// safety (0.6) a contact lasts under three steps and velocity Verlet's error in where it starts
// and ends shows as a few % of energy; this tests the force law, not the integrator.
IntegratorSettings undamped(double safety = 0.01) {
  IntegratorSettings s;
  s.threads = 1;
  s.safety = safety;
  return s;
}

// Two Au grains of radii r1, r2 on the x axis, centres `distance` apart.
System pair_system(double r1, double r2, double distance) {
  Elements el;
  el.add(grain_element(Vec3::Zero(), r1, gold()));
  el.add(grain_element(Vec3(distance, 0, 0), r2, gold()));
  System sys(std::move(el), undamped());
  sys.add(std::make_unique<LinearContact>(kE, std::max(r1, r2)));
  sys.initialize();
  return sys;
}

TEST(LinearContact, Eq36ForceAndEnergy) {
  const double r1 = 1.0, r2 = 1.5, overlap = 0.2;
  System sys = pair_system(r1, r2, r1 + r2 - overlap);
  // Eq. 36 by hand: k_n = π min(R)² E* / (R1 + R2), one material E* = E/2.
  const double kn = kPi * 1.0 * 1.0 * (kE / 2.0) / 2.5;
  EXPECT_NEAR(sys.find<LinearContact>()->stiffness(r1, r2), kn, 1e-12 * kn);
  const Elements& el = sys.elements();
  EXPECT_NEAR(el.f[1].x(), kn * overlap, 1e-12 * kn);  // pushes j away along +x
  EXPECT_EQ(el.f[1].y(), 0.0);
  EXPECT_EQ(el.f[1].z(), 0.0);
  // Newton's third law, and no moment from a central frictionless contact.
  EXPECT_EQ((el.f[0] + el.f[1]).norm(), 0.0);
  EXPECT_EQ(el.t[0].norm() + el.t[1].norm(), 0.0);
  const double e = sys.energy().potential.stored[static_cast<int>(EnergyTerm::Contact)];
  EXPECT_NEAR(e, 0.5 * kn * overlap * overlap, 1e-12 * e);
  // In user units: about 7.7 nN for 0.2 nm of overlap of 1 and 1.5 nm Au grains.
  EXPECT_NEAR(units::to_nN(el.f[1].x()), units::to_nN(kn * 0.2), 1e-9);
}

TEST(LinearContact, NoForceWhenApartOrJustTouching) {
  for (double gap : {0.0, 1e-9, 0.3}) {
    System sys = pair_system(1.0, 1.5, 2.5 + gap);
    const Elements& el = sys.elements();
    EXPECT_EQ(el.f[0].norm(), 0.0) << "gap " << gap;
    EXPECT_EQ(el.f[1].norm(), 0.0) << "gap " << gap;
    EXPECT_EQ(sys.energy().potential.total_stored(), 0.0);
  }
}

TEST(LinearContact, LeavesPlatensAndOtherKindsAlone) {
  Elements el;
  el.add(grain_element(Vec3::Zero(), 1.0, gold()));
  add_platen(el, Vec3(0.5, 0, 0), Vec3(-1, 0, 0), 1.0, 1.0);
  LinearContact c(kE, 1.0);
  EXPECT_TRUE(c.excludes(el, 0, 1));
  el.add(grain_element(Vec3(1.0, 0, 0), 1.0, gold()));
  EXPECT_FALSE(c.excludes(el, 0, 2));
}

// Velocities of an isolated pair after it collided head-on, from rest at a small gap.
struct Collision {
  Vec3 v1, v2;
  double ke0, ke1, p0_x, p1_x, balance_error;
  double max_force_nN = 0;
};

Collision collide(double r1, double r2, double v1, double v2) {
  Elements el;
  el.add(grain_element(Vec3::Zero(), r1, gold()));
  el.add(grain_element(Vec3(r1 + r2 + 0.05, 0, 0), r2, gold()));
  el.v[0] = Vec3(v1, 0, 0);
  el.v[1] = Vec3(v2, 0, 0);
  System sys(std::move(el), undamped());
  sys.add(std::make_unique<LinearContact>(kE, std::max(r1, r2)));
  sys.initialize();
  const Elements& e = sys.elements();
  Collision c;
  c.ke0 = sys.energy().kinetic();
  c.p0_x = e.mass[0] * e.v[0].x() + e.mass[1] * e.v[1].x();
  bool touched = false;
  for (int k = 0; k < 100000; ++k) {
    sys.step();
    const bool touching = e.f[1].norm() > 0;
    c.max_force_nN = std::max(c.max_force_nN, units::to_nN(e.f[1].norm()));
    touched = touched || touching;
    if (touched && !touching && (e.x[1] - e.x[0]).norm() > r1 + r2 + 0.05) break;
  }
  EXPECT_TRUE(touched);
  c.v1 = e.v[0];
  c.v2 = e.v[1];
  c.ke1 = sys.energy().kinetic();
  c.p1_x = e.mass[0] * e.v[0].x() + e.mass[1] * e.v[1].x();
  c.balance_error = sys.energy_balance_error();
  return c;
}

TEST(LinearContact, ElasticHeadOnCollisionConservesEnergyAndMomentum) {
  // Equal grains exchange velocities.
  {
    const Collision c = collide(1.2, 1.2, 0.1, -0.1);
    EXPECT_NEAR(c.v1.x(), -0.1, 1e-3 * 0.1);
    EXPECT_NEAR(c.v2.x(), 0.1, 1e-3 * 0.1);
    EXPECT_NEAR(c.ke1, c.ke0, 1e-4 * c.ke0);
    EXPECT_NEAR(c.p1_x, c.p0_x, 1e-12 * std::abs(c.ke0));
    EXPECT_LT(c.balance_error, 1e-3);
  }
  // Unequal grains: the textbook 1-D elastic collision, relative velocity reversed.
  {
    const double r1 = 1.0, r2 = 1.5, u1 = 0.15, u2 = -0.05;
    const double m1 = gold().density * 4.0 / 3.0 * kPi * r1 * r1 * r1;
    const double m2 = gold().density * 4.0 / 3.0 * kPi * r2 * r2 * r2;
    const Collision c = collide(r1, r2, u1, u2);
    const double w1 = ((m1 - m2) * u1 + 2 * m2 * u2) / (m1 + m2);
    const double w2 = ((m2 - m1) * u2 + 2 * m1 * u1) / (m1 + m2);
    EXPECT_NEAR(c.v1.x(), w1, 1e-3 * std::abs(u1 - u2));
    EXPECT_NEAR(c.v2.x(), w2, 1e-3 * std::abs(u1 - u2));
    EXPECT_NEAR(c.v2.x() - c.v1.x(), -(u2 - u1), 1e-3 * std::abs(u1 - u2));
    EXPECT_NEAR(c.ke1, c.ke0, 1e-4 * c.ke0);
    EXPECT_NEAR(c.p1_x, c.p0_x, 1e-12);
    EXPECT_EQ(c.v1.y(), 0.0);
    EXPECT_EQ(c.v2.z(), 0.0);
  }
}

TEST(PlanarWallContact, RigidPlatenForceOnBothSides) {
  // A grain of radius R overlapping a platen (normal +z) by u: F = π R E u along +z on the
  // grain, the opposite force on the platen, energy ½ k u².
  const double R = 1.5, u = 0.1;
  Elements el;
  el.add(grain_element(Vec3(0.3, -0.2, R - u), R, gold()));
  add_platen(el, Vec3(5.0, 7.0, 0.0), Vec3(0, 0, 1), 10.0, 5.0);
  System sys(std::move(el), undamped());
  sys.add(std::make_unique<PlanarWallContact>(kE));
  sys.initialize();
  const double k = kPi * R * kE;
  EXPECT_NEAR(sys.find<PlanarWallContact>()->stiffness(R), k, 1e-12 * k);
  const Elements& e = sys.elements();
  EXPECT_NEAR(e.f[0].z(), k * u, 1e-12 * k * u);
  EXPECT_EQ(e.f[0].x(), 0.0);
  EXPECT_EQ(e.f[0].y(), 0.0);
  EXPECT_EQ((e.f[0] + e.f[1]).norm(), 0.0);  // the reaction goes to the platen
  EXPECT_EQ(e.t[1].norm(), 0.0);             // and is a force only
  const double en = sys.energy().potential.stored[static_cast<int>(EnergyTerm::Contact)];
  EXPECT_NEAR(en, 0.5 * k * u * u, 1e-12 * en);
  // A tilted platen pushes along its own normal.
  Elements el2;
  const Vec3 nrm = Vec3(1, 0, 1).normalized();
  el2.add(grain_element(nrm * (R - u), R, gold()));
  add_platen(el2, Vec3::Zero(), nrm, 10.0, 5.0);
  System sys2(std::move(el2), undamped());
  sys2.add(std::make_unique<PlanarWallContact>(kE));
  sys2.initialize();
  EXPECT_NEAR((sys2.elements().f[0] - k * u * nrm).norm(), 0.0, 1e-9 * k * u);
}

TEST(PlanarWallContact, GrainBouncesOffFixedPlatenWithSpeedConserved) {
  const double R = 1.0, v = 0.2;
  Elements el;
  el.add(grain_element(Vec3(0, 0, R + 0.05), R, gold()));
  el.v[0] = Vec3(0.01, 0, -v);
  add_platen(el, Vec3::Zero(), Vec3(0, 0, 1), 10.0, 5.0);  // all DOFs fixed
  System sys(std::move(el), undamped());
  sys.add(std::make_unique<PlanarWallContact>(kE));
  sys.initialize();
  const Elements& e = sys.elements();
  bool touched = false;
  double platen_push = 0;
  for (int k = 0; k < 100000; ++k) {
    sys.step();
    touched = touched || e.f[0].z() > 0;
    platen_push = std::min(platen_push, e.f[1].z());
    if (touched && e.x[0].z() > R + 0.05) break;
  }
  ASSERT_TRUE(touched);
  EXPECT_LT(platen_push, 0.0);  // the platen felt the grain
  EXPECT_NEAR(e.v[0].z(), v, 1e-3 * v);
  EXPECT_NEAR(e.v[0].x(), 0.01, 1e-15);  // frictionless: tangential velocity untouched
  EXPECT_EQ(e.x[1].norm(), 0.0);         // a fixed platen stays put and does no work
  EXPECT_EQ(sys.energy().external_work, 0.0);
  EXPECT_LT(sys.energy_balance_error(), 1e-3);
}

TEST(SphericalWallContact, ForceLawOuterAndInner) {
  const double R = 1.0, u = 0.1, Rout = 10.0, Rin = 4.0;
  Elements el;
  const Vec3 dir = Vec3(1, 2, 2) / 3.0;
  el.add(grain_element(dir * (Rout - R + u), R, gold()));  // into the outer wall
  el.add(grain_element(-dir * (Rin + R - u), R, gold()));  // into the inner wall
  el.add(grain_element(Vec3(0, 7, 0), R, gold()));         // free
  System sys(std::move(el), undamped());
  sys.add(std::make_unique<SphericalWallContact>(Vec3::Zero(), Rout, Rin, kE));
  sys.initialize();
  const double k = kPi * R * kE;
  const Elements& e = sys.elements();
  EXPECT_NEAR((e.f[0] - (-k * u) * dir).norm(), 0.0, 1e-12 * k);  // inwards
  EXPECT_NEAR((e.f[1] - (-k * u) * dir).norm(), 0.0, 1e-12 * k);  // outwards, away from centre
  EXPECT_EQ(e.f[2].norm(), 0.0);
  const double en = sys.energy().potential.stored[static_cast<int>(EnergyTerm::Contact)];
  EXPECT_NEAR(en, k * u * u, 1e-12 * en);
}

TEST(SphericalWallContact, HoldsGrainsInside) {
  // Grains flying about in a spherical container, undamped: they bounce off the wall (and each
  // other) and never leave; the energy is conserved.
  const double Rout = 8.0, R = 1.0;
  Elements el;
  const Vec3 dirs[] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  int k = 0;
  for (const Vec3& d : dirs) {
    el.add(grain_element(d * 3.0, R, gold()));
    el.v.back() = 0.1 * Vec3(d.y() + 0.3 * k, d.z() - 0.2, d.x() + 0.1 * k) + 0.1 * d;
    ++k;
  }
  IntegratorSettings st = undamped();
  // No grain starts near a wall or another grain, so none counts for the automatic step: give
  // one, a fiftieth of √(m/k) of the wall contact.
  st.dt = 0.02 * std::sqrt(gold().density * 4.0 / 3.0 * kPi * R * R * R / (kPi * R * kE));
  System sys(std::move(el), st);
  sys.add(std::make_unique<LinearContact>(kE, R));
  sys.add(std::make_unique<SphericalWallContact>(Vec3::Zero(), Rout, 0.0, kE));
  sys.initialize();
  const double ke0 = sys.energy().kinetic();
  double worst = 0;
  for (int s = 0; s < 20000; ++s) {
    sys.step();
    for (std::size_t i = 0; i < sys.elements().size(); ++i)
      worst = std::max(worst, sys.elements().x[i].norm() + R - Rout);
  }
  // Deepest possible overlap with the wall: all the kinetic energy in one grain's wall spring.
  EXPECT_GT(worst, 0.0);  // they did reach the wall
  EXPECT_LT(worst, std::sqrt(2.0 * ke0 / (kPi * R * kE)));
  EXPECT_LT(worst, 0.2 * R);
  EXPECT_NEAR(sys.energy().kinetic() + sys.energy().potential.total_stored(), ke0, 1e-3 * ke0);
}

}  // namespace
}  // namespace mdem
