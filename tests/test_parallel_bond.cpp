// Single-bond tests of the parallel bond (model.md §3, §6): exact gradient, objectivity,
// small-deformation laws against Table 2-1, Newton's third law, validation, and the threaded
// force loop.
#include <gtest/gtest.h>
#include <omp.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/core/cnt.h"
#include "mdem/core/elements.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/force_model.h"
#include "mdem/scene/tube_builder.h"

namespace mdem {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct State {
  Vec3 xi, xj;
  Quat qi, qj;
};

double energy(const Bond& b, const State& s) {
  return bond_eval(b, s.xi, s.qi, s.xj, s.qj).energy();
}

// Central-difference −∇U: forces w.r.t. positions, torques w.r.t. world rotation vectors applied
// as q' = exp(δφ) q. Order: fi, ti, fj, tj.
std::array<Vec3, 4> fd_generalised_forces(const Bond& b, const State& s, double h) {
  std::array<Vec3, 4> out;
  for (int body = 0; body < 2; ++body) {
    for (int c = 0; c < 3; ++c) {
      const Vec3 e = h * Vec3::Unit(c);
      State p = s, m = s;
      (body == 0 ? p.xi : p.xj) += e;
      (body == 0 ? m.xi : m.xj) -= e;
      out[2 * body](c) = -(energy(b, p) - energy(b, m)) / (2 * h);
      State rp = s, rm = s;
      if (body == 0) {
        rp.qi = quat_exp(e) * s.qi;
        rm.qi = quat_exp(-e) * s.qi;
      } else {
        rp.qj = quat_exp(e) * s.qj;
        rm.qj = quat_exp(-e) * s.qj;
      }
      out[2 * body + 1](c) = -(energy(b, rp) - energy(b, rm)) / (2 * h);
    }
  }
  return out;
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> nd;
  Vec3 v;
  do v = Vec3(nd(rng), nd(rng), nd(rng));
  while (v.norm() < 1e-3);
  return v.normalized();
}

Quat random_quat(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, kPi);
  return quat_exp(u(rng) * random_unit(rng));
}

// A unit vector perpendicular to a.
Vec3 perpendicular(const Vec3& a, std::mt19937_64& rng) {
  const Vec3 r = random_unit(rng);
  Vec3 p = r - r.dot(a) * a;
  if (p.norm() < 1e-6) p = a.unitOrthogonal();
  return p.normalized();
}

Elements two_cnt_segments(const Vec3& x0, const Vec3& dir, double roll) {
  Elements el;
  const Quat q = quat_from_axis(dir) * quat_exp(roll * Vec3::UnitX());
  el.add(cnt_segment(x0, q, 0, 0));
  el.add(cnt_segment(x0 + cnt::kSegmentLength * dir.normalized(), q, 0, 1));
  return el;
}

ElementInit grain(const Vec3& x, const Quat& q, double r) {
  ElementInit e;
  e.kind = ElementKind::Grain;
  e.x = x;
  e.q = q;
  e.radius = r;
  e.mass = r * r * r;
  e.inertia = Vec3::Constant(0.4 * e.mass * r * r);
  return e;
}

// Compares analytic forces/torques with −∇U; relative to the largest component of either.
void expect_gradient_matches(const Bond& b, const State& s, double rel_tol,
                             const std::string& what) {
  const BondResult r = bond_eval(b, s.xi, s.qi, s.xj, s.qj);
  const std::array<Vec3, 4> an = {r.fi, r.ti, r.fj, r.tj};
  const std::array<Vec3, 4> fd = fd_generalised_forces(b, s, 1e-5);
  double scale = 0, err = 0;
  for (int k = 0; k < 4; ++k) {
    scale = std::max(scale, an[k].cwiseAbs().maxCoeff());
    err = std::max(err, (an[k] - fd[k]).cwiseAbs().maxCoeff());
  }
  ASSERT_GT(scale, 0) << what;
  EXPECT_LE(err, rel_tol * scale) << what << "\n fi " << r.fi.transpose() << " | "
                                  << fd[0].transpose() << "\n ti " << r.ti.transpose() << " | "
                                  << fd[1].transpose() << "\n fj " << r.fj.transpose() << " | "
                                  << fd[2].transpose() << "\n tj " << r.tj.transpose() << " | "
                                  << fd[3].transpose();
}

// ---------------------------------------------------------------------------------------------
// 1. Forces and torques are the exact gradient of the bond energy.

TEST(ParallelBond, GradientMatchesFiniteDifferencesCnt) {
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> u(-1, 1);
  const BondStiffness k = cnt_bond_stiffness();
  int checked = 0;
  for (int trial = 0; trial < 120; ++trial) {
    const Vec3 dir = random_unit(rng);
    const Elements el = two_cnt_segments(Vec3(u(rng), u(rng), u(rng)) * 5, dir, kPi * u(rng));
    const Bond b = make_bond(el, 0, 1, k);
    // Alternate small and large deformations.
    const bool large = trial % 2 == 1;
    const double s_len = large ? 0.3 : 0.01;          // nm: stretch / shear amplitude
    const double bend = large ? kPi / 3 : 0.02;       // up to 60°
    const double twist = large ? 2 * kPi / 3 : 0.02;  // up to 120°
    State s{el.x[0], el.x[1], el.q[0], el.q[1]};
    // Stretch + shear of j.
    s.xj += s_len * (u(rng) * dir + u(rng) * perpendicular(dir, rng));
    // Bend j about a perpendicular axis, twist about the axis, small wobble of i.
    s.qj =
        quat_exp(bend * u(rng) * perpendicular(dir, rng)) * quat_exp(twist * u(rng) * dir) * s.qj;
    s.qi = quat_exp((large ? 0.3 : 0.01) * u(rng) * random_unit(rng)) * s.qi;
    s.xi += (large ? 0.1 : 0.005) * Vec3(u(rng), u(rng), u(rng));
    expect_gradient_matches(b, s, 1e-6, "cnt trial " + std::to_string(trial));
    ++checked;
  }
  EXPECT_EQ(checked, 120);
}

TEST(ParallelBond, GradientMatchesFiniteDifferencesUnequalSpheres) {
  std::mt19937_64 rng(777);
  std::uniform_real_distribution<double> u(-1, 1), pos(0, 1);
  for (int trial = 0; trial < 120; ++trial) {
    const double ri = 0.5 + 2.5 * pos(rng), rj = 0.5 + 2.5 * pos(rng);
    const Vec3 d = random_unit(rng);
    const double dist = (ri + rj) * (0.8 + 0.4 * pos(rng));
    Elements el;
    el.add(grain(Vec3(u(rng), u(rng), u(rng)), random_quat(rng), ri));
    el.add(grain(el.x[0] + dist * d, random_quat(rng), rj));
    BondStiffness k;
    k.kn_area = 10 + 1000 * pos(rng);
    k.ks_area = 10 + 1000 * pos(rng);
    k.kn_inertia = 10 + 1000 * pos(rng);
    k.ks_polar = 10 + 1000 * pos(rng);
    const Bond b = make_bond(el, 0, 1, k);
    const double amp = trial % 2 ? 1.0 : 0.02;
    State s{el.x[0], el.x[1], el.q[0], el.q[1]};
    s.xi += amp * 0.2 * dist * Vec3(u(rng), u(rng), u(rng));
    s.xj += amp * 0.2 * dist * Vec3(u(rng), u(rng), u(rng));
    s.qi = quat_exp(amp * 1.0 * u(rng) * random_unit(rng)) * s.qi;
    s.qj = quat_exp(amp * 1.2 * u(rng) * random_unit(rng)) * s.qj;
    expect_gradient_matches(b, s, 1e-6, "sphere trial " + std::to_string(trial));
  }
}

TEST(ParallelBond, MakeBondGeometryForUnequalSpheres) {
  Elements el;
  std::mt19937_64 rng(3);
  const Quat qi = random_quat(rng), qj = random_quat(rng);
  el.add(grain(Vec3(1, 2, 3), qi, 1.0));
  el.add(grain(Vec3(1, 2, 3) + Vec3(3, 0, 4) / 5.0 * 4.0, qj, 3.0));  // centre distance 4
  const Bond b = make_bond(el, 0, 1, cnt_bond_stiffness());
  const Vec3 d = Vec3(3, 0, 4) / 5.0;
  // Bond point 1 nm from i, 3 nm from j (ratio of the radii).
  EXPECT_LT((qi * b.ci - 1.0 * d).norm(), 1e-14);
  EXPECT_LT((qj * b.cj + 3.0 * d).norm(), 1e-14);
  EXPECT_LT((qi * b.ni - d).norm(), 1e-14);
  EXPECT_LT((qj * b.nj - d).norm(), 1e-14);
  const BondResult r = bond_eval(b, el.x[0], el.q[0], el.x[1], el.q[1]);
  EXPECT_LT(r.energy(), 1e-20);
}

// ---------------------------------------------------------------------------------------------
// 2. Objectivity.

TEST(ParallelBond, RigidMotionOfRestStateIsForceFree) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(-1, 1);
  const BondStiffness k = cnt_bond_stiffness();
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 dir = random_unit(rng);
    const Elements el = two_cnt_segments(Vec3(u(rng), u(rng), u(rng)) * 3, dir, kPi * u(rng));
    const Bond b = make_bond(el, 0, 1, k);
    // Angles up to 170°, including exactly 170° and 179°.
    double angle = kPi * (170.0 / 180.0) * std::abs(u(rng));
    if (trial == 0) angle = kPi * 170.0 / 180.0;
    if (trial == 1) angle = kPi * 179.0 / 180.0;
    const Quat Q = quat_exp(angle * random_unit(rng));
    const Vec3 t = 10.0 * Vec3(u(rng), u(rng), u(rng));
    const Vec3 xi = Q * el.x[0] + t, xj = Q * el.x[1] + t;
    const BondResult r = bond_eval(b, xi, Q * el.q[0], xj, Q * el.q[1]);
    EXPECT_LT(r.energy(), 1e-20) << trial;
    EXPECT_LT(r.fi.norm(), 1e-10) << trial;
    EXPECT_LT(r.fj.norm(), 1e-10) << trial;
    EXPECT_LT(r.ti.norm(), 1e-10) << trial;
    EXPECT_LT(r.tj.norm(), 1e-10) << trial;
  }
}

TEST(ParallelBond, RigidRotationOfDeformedStateRotatesForces) {
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(-1, 1);
  const BondStiffness k = cnt_bond_stiffness();
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 dir = random_unit(rng);
    const Elements el = two_cnt_segments(Vec3::Zero(), dir, kPi * u(rng));
    const Bond b = make_bond(el, 0, 1, k);
    State s{el.x[0], el.x[1], el.q[0], el.q[1]};
    s.xj += 0.2 * Vec3(u(rng), u(rng), u(rng));
    s.qj = quat_exp(1.0 * u(rng) * random_unit(rng)) * s.qj;
    s.qi = quat_exp(0.5 * u(rng) * random_unit(rng)) * s.qi;
    const BondResult r0 = bond_eval(b, s.xi, s.qi, s.xj, s.qj);
    const double angle = trial == 0 ? kPi * 170.0 / 180.0 : kPi * std::abs(u(rng));
    const Quat Q = quat_exp(angle * random_unit(rng));
    const Vec3 t = 5.0 * Vec3(u(rng), u(rng), u(rng));
    const BondResult r1 = bond_eval(b, Q * s.xi + t, Q * s.qi, Q * s.xj + t, Q * s.qj);
    EXPECT_NEAR(r1.energy(), r0.energy(), 1e-11 * r0.energy()) << trial;
    EXPECT_NEAR(r1.e_tension, r0.e_tension, 1e-10 * r0.energy()) << trial;
    EXPECT_NEAR(r1.e_shear, r0.e_shear, 1e-10 * r0.energy()) << trial;
    EXPECT_NEAR(r1.e_bending, r0.e_bending, 1e-10 * r0.energy()) << trial;
    EXPECT_NEAR(r1.e_torsion, r0.e_torsion, 1e-10 * r0.energy()) << trial;
    const double scale = std::max({r0.fi.norm(), r0.fj.norm(), r0.ti.norm(), r0.tj.norm()});
    EXPECT_LT((r1.fi - Q * r0.fi).norm(), 1e-10 * scale) << trial;
    EXPECT_LT((r1.fj - Q * r0.fj).norm(), 1e-10 * scale) << trial;
    EXPECT_LT((r1.ti - Q * r0.ti).norm(), 1e-10 * scale) << trial;
    EXPECT_LT((r1.tj - Q * r0.tj).norm(), 1e-10 * scale) << trial;
  }
}

// ---------------------------------------------------------------------------------------------
// 3. Small-deformation laws against the Table 2-1 constants.

class CntBondAlongX : public ::testing::Test {
 protected:
  void SetUp() override {
    el = two_cnt_segments(Vec3::Zero(), Vec3::UnitX(), 0.0);
    b = make_bond(el, 0, 1, cnt_bond_stiffness());
  }
  Elements el;
  Bond b;
  // Table 2-1 numbers, typed in independently of cnt.h.
  const double knA = 4740.0 * 1.427;  // 6763.98 eV/nm²
  const double ksA = 2110.0 * 1.427;  // 3010.97 eV/nm²
  const double knI = 4740.0 * 0.348;  // 1649.52 eV
  const double ksJ = 2110.0 * 0.696;  // 1468.56 eV
  const double T = 1.356;
};

TEST_F(CntBondAlongX, StiffnessMatchesTable21) {
  const BondStiffness k = cnt_bond_stiffness();
  EXPECT_NEAR(k.kn_area, knA, 1e-9);
  EXPECT_NEAR(k.ks_area, ksA, 1e-9);
  EXPECT_NEAR(k.kn_inertia, knI, 1e-9);
  EXPECT_NEAR(k.ks_polar, ksJ, 1e-9);
  // model.md §3: kn·I·T = 2.24e3 eV·nm, the (10,10) bending stiffness of thesis §3.2.
  EXPECT_NEAR(k.kn_inertia * cnt::kSegmentLength, 2.24e3, 0.01e3);
  // Bond point at the midpoint, arms T/2.
  EXPECT_NEAR(b.ci.norm(), T / 2, 1e-14);
  EXPECT_NEAR(b.cj.norm(), T / 2, 1e-14);
}

TEST_F(CntBondAlongX, AxialStretch) {
  for (double un : {1e-4, -1e-3, 0.05}) {
    const Vec3 xj = el.x[1] + un * Vec3::UnitX();
    const BondResult r = bond_eval(b, el.x[0], el.q[0], xj, el.q[1]);
    EXPECT_NEAR(r.fj.x(), -knA * un, 1e-9 * knA * std::abs(un));
    EXPECT_NEAR(r.fj.y(), 0, 1e-12);
    EXPECT_NEAR(r.fj.z(), 0, 1e-12);
    EXPECT_LT((r.fi + r.fj).norm(), 1e-12);
    EXPECT_LT(r.ti.norm() + r.tj.norm(), 1e-10);
    EXPECT_NEAR(r.e_tension, 0.5 * knA * un * un, 1e-9 * r.e_tension);
    EXPECT_NEAR(r.e_shear + r.e_bending + r.e_torsion, 0, 1e-20);
    const BondDeformation d = bond_deformation(b, el.x[0], el.q[0], xj, el.q[1]);
    EXPECT_NEAR(d.u_n, un, 1e-15);
    EXPECT_LT(d.u_s.norm(), 1e-15);
  }
}

TEST_F(CntBondAlongX, Shear) {
  const double us = 2e-3;
  const Vec3 xj = el.x[1] + us * Vec3::UnitY();
  const BondResult r = bond_eval(b, el.x[0], el.q[0], xj, el.q[1]);
  EXPECT_NEAR(r.fj.norm(), ksA * us, 1e-9 * ksA * us);
  EXPECT_NEAR(r.fj.y(), -ksA * us, 1e-9 * ksA * us);
  EXPECT_NEAR(r.e_shear, 0.5 * ksA * us * us, 1e-9 * r.e_shear);
  EXPECT_NEAR(r.e_tension + r.e_bending + r.e_torsion, 0, 1e-20);
  // The shear force acts at the bond point, T/2 from each centre: moment (T/2)·ksA·us about z on
  // each body, in the sense that rotates both back towards the common line.
  // (j's bond point sits at −T/2 x̂ from its centre and is pushed along −y: (−T/2 x̂)×(−F ŷ) = +z.)
  EXPECT_NEAR(r.ti.z(), 0.5 * T * ksA * us, 1e-9 * T * ksA * us);
  EXPECT_NEAR(r.tj.z(), 0.5 * T * ksA * us, 1e-9 * T * ksA * us);
  const BondDeformation d = bond_deformation(b, el.x[0], el.q[0], xj, el.q[1]);
  EXPECT_NEAR(d.u_s.y(), us, 1e-15);
  EXPECT_NEAR(d.u_n, 0, 1e-15);
}

TEST_F(CntBondAlongX, Twist) {
  // Pure twist is exact at any angle below π: the axis and the bond points do not move.
  for (double th : {1e-3, -0.01, 2.0}) {
    const Quat qj = quat_exp(th * Vec3::UnitX()) * el.q[1];
    const BondResult r = bond_eval(b, el.x[0], el.q[0], el.x[1], qj);
    EXPECT_NEAR(r.tj.x(), -ksJ * th, 1e-9 * ksJ * std::abs(th));  // 1468.56 eV · θ
    EXPECT_NEAR(r.ti.x(), ksJ * th, 1e-9 * ksJ * std::abs(th));
    EXPECT_LT(r.tj.tail<2>().norm() + r.ti.tail<2>().norm(), 1e-9);
    EXPECT_LT(r.fi.norm() + r.fj.norm(), 1e-9);
    EXPECT_NEAR(r.e_torsion, 0.5 * ksJ * th * th, 1e-9 * r.e_torsion);
    EXPECT_NEAR(r.e_tension + r.e_shear + r.e_bending, 0, 1e-18);
    const BondDeformation d = bond_deformation(b, el.x[0], el.q[0], el.x[1], qj);
    EXPECT_NEAR(d.theta_t, th, 1e-14);
  }
}

TEST_F(CntBondAlongX, Bend) {
  // Rotate j about the bond point (the gap stays zero) by β about z: a pure bending rotation.
  const Vec3 p = 0.5 * (el.x[0] + el.x[1]);
  for (double beta : {1e-3, -0.02, 0.5}) {
    const Quat R = quat_exp(beta * Vec3::UnitZ());
    const Vec3 xj = p + R * (el.x[1] - p);
    const Quat qj = R * el.q[1];
    const BondResult r = bond_eval(b, el.x[0], el.q[0], xj, qj);
    EXPECT_NEAR(r.tj.z(), -knI * beta, 1e-9 * knI * std::abs(beta));  // 1649.52 eV · β
    EXPECT_NEAR(r.ti.z(), knI * beta, 1e-9 * knI * std::abs(beta));
    EXPECT_LT(r.fi.norm() + r.fj.norm(), 1e-9);
    EXPECT_NEAR(r.e_bending, 0.5 * knI * beta * beta, 1e-9 * r.e_bending);
    EXPECT_NEAR(r.e_tension + r.e_shear + r.e_torsion, 0, 1e-18);
    const BondDeformation d = bond_deformation(b, el.x[0], el.q[0], xj, qj);
    EXPECT_NEAR(d.theta_b.z(), beta, 1e-14);
    EXPECT_NEAR(d.theta_t, 0, 1e-14);
  }
}

TEST_F(CntBondAlongX, StiffnessBounds) {
  ParallelBond pb;
  pb.add(b);
  StiffnessSums s;
  s.reset(2);
  pb.add_stiffness(el, nullptr, s);
  const double a = T / 2;
  for (int e = 0; e < 2; ++e) {
    EXPECT_NEAR(s.kt[e], knA, 1e-9);
    EXPECT_NEAR(s.kr[e], knI + ksA * a * a, 1e-9);
    EXPECT_NEAR(s.ktr[e], ksA * a, 1e-9);
    EXPECT_EQ(s.c[e], 0.0);
  }
}

// ---------------------------------------------------------------------------------------------
// 4. Newton's third law: zero net force and zero net moment about the origin.

TEST(ParallelBond, NetForceAndMomentVanish) {
  std::mt19937_64 rng(4242);
  std::uniform_real_distribution<double> u(-1, 1), pos(0, 1);
  for (int trial = 0; trial < 100; ++trial) {
    Elements el;
    const double ri = 0.5 + pos(rng), rj = 0.5 + 2 * pos(rng);
    el.add(grain(3 * Vec3(u(rng), u(rng), u(rng)), random_quat(rng), ri));
    el.add(grain(el.x[0] + (ri + rj) * random_unit(rng), random_quat(rng), rj));
    const Bond b = make_bond(el, 0, 1, cnt_bond_stiffness());
    const Vec3 xi = el.x[0] + 0.3 * Vec3(u(rng), u(rng), u(rng));
    const Vec3 xj = el.x[1] + 0.3 * Vec3(u(rng), u(rng), u(rng));
    const Quat qi = quat_exp(1.0 * u(rng) * random_unit(rng)) * el.q[0];
    const Quat qj = quat_exp(1.5 * u(rng) * random_unit(rng)) * el.q[1];
    const BondResult r = bond_eval(b, xi, qi, xj, qj);
    const double fscale = r.fi.norm() + r.fj.norm();
    const double mscale =
        xi.norm() * r.fi.norm() + xj.norm() * r.fj.norm() + r.ti.norm() + r.tj.norm();
    EXPECT_LT((r.fi + r.fj).norm(), 1e-13 * fscale) << trial;
    EXPECT_LT((xi.cross(r.fi) + xj.cross(r.fj) + r.ti + r.tj).norm(), 1e-12 * mscale) << trial;
  }
}

// ---------------------------------------------------------------------------------------------
// 5. Validation.

void expect_invalid(const Elements& el, std::uint32_t i, std::uint32_t j, const BondStiffness& k,
                    const std::string& needle) {
  try {
    make_bond(el, i, j, k);
    ADD_FAILURE() << "expected std::invalid_argument mentioning '" << needle << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(ParallelBond, MakeBondValidation) {
  Elements el = two_cnt_segments(Vec3::Zero(), Vec3::UnitX(), 0);
  el.add(cnt_segment(Vec3::Zero(), Quat::Identity(), 1, 0));  // coincides with element 0
  const BondStiffness ok = cnt_bond_stiffness();
  expect_invalid(el, 1, 1, ok, "differ");
  expect_invalid(el, 0, 7, ok, "out of range");
  expect_invalid(el, 0, 2, ok, "coincide");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  BondStiffness k = ok;
  k.kn_area = nan;
  expect_invalid(el, 0, 1, k, "kn_area");
  k = ok;
  k.ks_area = -1;
  expect_invalid(el, 0, 1, k, "ks_area");
  k = ok;
  k.kn_inertia = inf;
  expect_invalid(el, 0, 1, k, "kn_inertia");
  k = ok;
  k.ks_polar = -1e-3;
  expect_invalid(el, 0, 1, k, "ks_polar");
  EXPECT_NO_THROW(make_bond(el, 0, 1, ok));
  EXPECT_NO_THROW(make_bond(el, 1, 0, BondStiffness{}));  // zero stiffness is allowed
}

// ---------------------------------------------------------------------------------------------
// 6. The threaded force loop equals the sum of single-bond evaluations.

TEST(ParallelBond, ComputeOnTubeMatchesBondSum) {
  Elements el;
  // Long enough that the loop runs threaded (more bonds than kParallelMinItems).
  const int segments = static_cast<int>(kParallelMinItems) + 11;
  const std::vector<std::size_t> ids =
      add_straight_tube(el, Vec3(1, -2, 0.5), Vec3(1, 1, 0.3), segments, 0);
  const ParallelBond pb = *ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  ASSERT_EQ(ids.size(), static_cast<std::size_t>(segments));
  ASSERT_EQ(pb.bonds().size(), static_cast<std::size_t>(segments - 1));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (std::size_t e = 0; e < el.size(); ++e) {
    el.x[e] += 0.05 * Vec3(u(rng), u(rng), u(rng));
    el.q[e] = quat_exp(0.1 * Vec3(u(rng), u(rng), u(rng))) * el.q[e];
  }
  const std::size_t n = el.size();
  std::vector<Vec3> f_ref(n, Vec3::Zero()), t_ref(n, Vec3::Zero());
  double e_ref[4] = {0, 0, 0, 0};
  for (const Bond& b : pb.bonds()) {
    const BondResult r = bond_eval(b, el.x[b.i], el.q[b.i], el.x[b.j], el.q[b.j]);
    f_ref[b.i] += r.fi;
    f_ref[b.j] += r.fj;
    t_ref[b.i] += r.ti;
    t_ref[b.j] += r.tj;
    e_ref[0] += r.e_tension;
    e_ref[1] += r.e_shear;
    e_ref[2] += r.e_bending;
    e_ref[3] += r.e_torsion;
  }
  for (double e : e_ref) ASSERT_GT(e, 0);

  const int saved = omp_get_max_threads();
  for (int nt : {1, 2}) {
    omp_set_num_threads(nt);
    ForceSink sink;
    sink.resize(n, nt, false);
    sink.clear();
    pb.compute(el, nullptr, sink);
    std::vector<Vec3> f(n), t(n), fd, td;
    const EnergyTally tally = sink.reduce(f, t, fd, td);
    double fscale = 0;
    for (std::size_t e = 0; e < n; ++e)
      fscale = std::max(fscale, f_ref[e].norm() + t_ref[e].norm());
    for (std::size_t e = 0; e < n; ++e) {
      EXPECT_LT((f[e] - f_ref[e]).norm(), 1e-13 * fscale) << "threads " << nt << " elem " << e;
      EXPECT_LT((t[e] - t_ref[e]).norm(), 1e-13 * fscale) << "threads " << nt << " elem " << e;
    }
    const EnergyTerm terms[4] = {EnergyTerm::BondTension, EnergyTerm::BondShear,
                                 EnergyTerm::BondBending, EnergyTerm::BondTorsion};
    for (int k = 0; k < 4; ++k)
      EXPECT_NEAR(tally.stored[static_cast<int>(terms[k])], e_ref[k], 1e-12 * e_ref[k])
          << "threads " << nt << " term " << k;
    EXPECT_EQ(tally.stored[static_cast<int>(EnergyTerm::Vdw)], 0.0);
    EXPECT_EQ(tally.stored[static_cast<int>(EnergyTerm::NpCnt)], 0.0);
    EXPECT_EQ(tally.stored[static_cast<int>(EnergyTerm::NpNp)], 0.0);
    EXPECT_EQ(tally.stored[static_cast<int>(EnergyTerm::Contact)], 0.0);
    // The per-thread slots of a 2-thread sink both took part (bonds split statically).
    if (nt == 2) {
      double e0 = sink.energy(0).total_stored(), e1 = sink.energy(1).total_stored();
      EXPECT_GT(e0, 0);
      EXPECT_GT(e1, 0);
    }
  }
  omp_set_num_threads(saved);
}

}  // namespace
}  // namespace mdem
