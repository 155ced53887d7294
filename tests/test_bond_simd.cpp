// The parallel bond in SIMD batches (BondEvaluation::Batched, bond_simd) against its scalar
// reference (BondEvaluation::Scalar, bond_eval's code): bond by bond over random states (small
// and large relative rotations, periodic images, 180° bends, a NaN), on every instruction set the
// build carries, and over a perturbed film through compute() at 1 and 2 threads, with the bonds'
// own conservation laws (Newton's third law, angular momentum), bit-for-bit repetition per thread
// count, and the rest-state copy following edits of the bonds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "hwy/targets.h"
#include "mdem/core/cnt.h"
#include "mdem/core/elements.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/scene/tube_builder.h"

using namespace mdem;

namespace {

constexpr double kRoundOff = 1e-13;
constexpr double kPi = 3.14159265358979323846;

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

Quat rotation(const Vec3& axis, double angle) {
  return Quat(Eigen::AngleAxisd(angle, axis.normalized()));
}

// The bond's scale: the loads of a unit deformation, a strain of one bond length ℓ = |c_i| + |c_j|
// and a rotation of 1 rad. An error relative to it is an error in the deformation (rounding of a
// small relative rotation, a difference of O(1) quaternion products, is ~1e-16 rad absolute in
// either code, so the loads of a tiny deformation cannot be compared relative to themselves).
struct Scale {
  double force, torque, energy;
};
Scale bond_scale(const Bond& b) {
  const double l = b.ci.norm() + b.cj.norm();
  const double f = std::max(b.k.kn_area, b.k.ks_area) * l;
  const double rot = std::max(b.k.kn_inertia, b.k.ks_polar);
  return {f, f * l + rot, f * l + rot};
}

struct Eval {
  std::vector<Vec3> f, t;
  EnergyTally e;
  bool operator==(const Eval& o) const { return f == o.f && t == o.t && e.stored == o.e.stored; }
};

Eval evaluate(const ParallelBond& m, const Elements& el, int threads) {
  ForceSink sink;
  sink.resize(el.size(), threads, false);
  sink.clear();
  m.compute(el, nullptr, sink);
  Eval r;
  r.f.resize(el.size());
  r.t.resize(el.size());
  std::vector<Vec3> fd, td;
  r.e = sink.reduce(r.f, r.t, fd, td);
  return r;
}

double term(const EnergyTally& e, EnergyTerm t) { return e.stored[static_cast<int>(t)]; }
constexpr EnergyTerm kTerms[] = {EnergyTerm::BondTension, EnergyTerm::BondShear,
                                 EnergyTerm::BondBending, EnergyTerm::BondTorsion};

// n bonds, bond k between its own elements 2k and 2k+1 (so an element's load is its bond's),
// made at rest and then deformed: random stretch and shear up to 0.2 nm, relative rotations of
// every size from 1e-9 rad to π (a third beyond the series' 0.1 rad), rigid rotations of the
// pair, every 97th bond bent by 180°, and in a periodic box every 3rd j moved by whole box
// lengths (its minimum image is the one bonded).
struct BondCase {
  Elements el;
  ParallelBond batched{BondEvaluation::Batched}, scalar{BondEvaluation::Scalar};
  Domain domain;
};

void random_bonds(BondCase& c, int n, unsigned seed, bool periodic) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double side = 20.0;
  if (periodic) c.domain = Domain(Vec3(-10, -10, -10), Vec3(10, 10, 10), {true, true, false});
  const double T = cnt::kSegmentLength;
  for (int k = 0; k < n; ++k) {
    const Vec3 p = side * Vec3(u01(rng) - 0.5, u01(rng) - 0.5, u01(rng) - 0.5);
    const Vec3 dir = random_unit(rng);
    const Quat q = rotation(dir, 2 * kPi * u01(rng)) * quat_from_axis(dir);
    c.el.add(cnt_segment(p, q, 0, 2 * k));
    c.el.add(cnt_segment(p + T * dir, q, 0, 2 * k + 1));
    BondStiffness s = cnt_bond_stiffness();
    s.ks_area *= 0.5 + u01(rng);  // per-bond stiffness: lanes must not share it
    s.kn_inertia *= 0.5 + u01(rng);
    const Bond b = make_bond(c.el, 2 * k, 2 * k + 1, s);
    c.batched.add(b);
    c.scalar.add(b);

    Vec3& xi = c.el.x[2 * k];
    Vec3& xj = c.el.x[2 * k + 1];
    Quat& qi = c.el.q[2 * k];
    Quat& qj = c.el.q[2 * k + 1];
    xj += 0.2 * u01(rng) * random_unit(rng);
    const int kind = k % 3;
    const double angle = kind == 0   ? std::pow(10.0, -9 + 8 * u01(rng))  // 1e-9 .. 0.1 rad
                         : kind == 1 ? 0.1 * u01(rng)
                                     : 0.1 + (kPi - 0.1) * u01(rng);  // the scalar code's range
    qj = (rotation(random_unit(rng), angle) * qj).normalized();
    if (k % 97 == 5) {  // bent back on itself: R_j n_j = −R_i n_i, no bond axis
      qi = quat_from_axis(dir);
      qj = rotation(dir.unitOrthogonal(), kPi) * qi;
    }
    // A rigid rotation of the pair about i's centre (the bond's loads turn with it).
    const Quat rigid = rotation(random_unit(rng), 2 * kPi * u01(rng));
    xj = xi + rigid * (xj - xi);
    qi = (rigid * qi).normalized();
    qj = (rigid * qj).normalized();
    if (periodic && k % 3 == 1) xj += Vec3(20.0 * (k % 2 ? 1 : -2), 20.0, 0);
  }
  c.batched.bind_domain(&c.domain);
  c.scalar.bind_domain(&c.domain);
}

// Largest difference of forces and torques between the two evaluations over the bonds, relative
// to each bond's scale, with the energies of each term relative to the bonds' summed scale.
double max_relative_difference(const BondCase& c) {
  const Eval ref = evaluate(c.scalar, c.el, 1);
  const Eval got = evaluate(c.batched, c.el, 1);
  double worst = 0, energy_scale = 0;
  const std::vector<Bond>& bonds = c.scalar.bonds();
  for (std::size_t k = 0; k < bonds.size(); ++k) {
    const Scale s = bond_scale(bonds[k]);
    energy_scale += s.energy;
    for (std::size_t e : {2 * k, 2 * k + 1}) {
      EXPECT_TRUE(got.f[e].allFinite() && got.t[e].allFinite()) << "bond " << k;
      worst = std::max(worst, (got.f[e] - ref.f[e]).norm() / s.force);
      worst = std::max(worst, (got.t[e] - ref.t[e]).norm() / s.torque);
    }
    // Newton's third law holds exactly per bond (f_j is −f_i by construction).
    EXPECT_EQ(got.f[2 * k], -got.f[2 * k + 1]);
  }
  for (EnergyTerm t : kTerms)
    worst = std::max(worst, std::abs(term(got.e, t) - term(ref.e, t)) / energy_scale);
  return worst;
}

// The comparison is not of zeros: every term is loaded.
void expect_loaded(const BondCase& c) {
  const Eval ref = evaluate(c.scalar, c.el, 1);
  for (EnergyTerm t : kTerms) EXPECT_GT(term(ref.e, t), 0.0);
}

TEST(BondSimd, RandomStatesEqualScalarCode) {
  for (bool periodic : {false, true}) {
    BondCase c;
    random_bonds(c, 2003, periodic ? 2 : 1, periodic);  // a partial chunk and a partial vector
    expect_loaded(c);
    const double worst = max_relative_difference(c);
    EXPECT_LT(worst, kRoundOff) << "on " << bond_simd_target();
    std::printf("batched bond on %s (%s): largest relative difference %.3g\n", bond_simd_target(),
                periodic ? "periodic" : "open", worst);
  }
}

TEST(BondSimd, EveryInstructionSetEqualsScalarCode) {
  BondCase c;
  random_bonds(c, 600, 3, true);
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  EXPECT_GE(targets.size(), 2u);  // at least a vector set and the plain C++ fallback
  for (std::int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    EXPECT_STREQ(bond_simd_target(), hwy::TargetName(target));
    const double worst = max_relative_difference(c);
    EXPECT_LT(worst, kRoundOff) << hwy::TargetName(target);
    std::printf("%s: largest relative difference %.3g\n", hwy::TargetName(target), worst);
  }
  hwy::SetSupportedTargetsForTest(0);
}

// A single bond (seven padding lanes) and each bond alone: every term's energy equals the
// scalar code's bond by bond, the 180° bend included.
TEST(BondSimd, EnergiesEqualScalarCodeBondByBond) {
  BondCase c;
  random_bonds(c, 200, 4, false);
  for (const Bond& b : c.scalar.bonds()) {
    ParallelBond one;
    one.add(b);
    const Eval got = evaluate(one, c.el, 1);
    const BondResult ref = bond_eval(b, c.el.x[b.i], c.el.q[b.i], c.el.x[b.j], c.el.q[b.j]);
    const double s = bond_scale(b).energy;
    EXPECT_NEAR(term(got.e, EnergyTerm::BondTension), ref.e_tension, kRoundOff * s);
    EXPECT_NEAR(term(got.e, EnergyTerm::BondShear), ref.e_shear, kRoundOff * s);
    EXPECT_NEAR(term(got.e, EnergyTerm::BondBending), ref.e_bending, kRoundOff * s);
    EXPECT_NEAR(term(got.e, EnergyTerm::BondTorsion), ref.e_torsion, kRoundOff * s);
  }
}

TEST(BondSimd, NanPropagates) {
  BondCase c;
  random_bonds(c, 16, 5, false);
  c.el.x[6].y() = std::numeric_limits<double>::quiet_NaN();   // bond 3's element i
  c.el.q[11].w() = std::numeric_limits<double>::quiet_NaN();  // bond 5's element j
  const Eval got = evaluate(c.batched, c.el, 1);
  EXPECT_TRUE(std::isnan(got.f[7].norm()));
  EXPECT_TRUE(std::isnan(got.t[10].norm()));
  EXPECT_TRUE(got.f[0].allFinite());
}

// A film of straight bonded tubes (bonds from the topology, consecutive bonds sharing elements,
// so the lanes of a batch collide in the scatter).
Elements film(unsigned seed, int tubes, int segments, double side) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.5 * side, 0.5 * side);
  Elements el;
  for (int t = 0; t < tubes; ++t) {
    Vec3 dir = random_unit(rng);
    dir.z() *= 0.2;
    add_straight_tube(el, Vec3(u(rng), u(rng), u(rng) * 0.1), dir.normalized(), segments, t);
  }
  return el;
}

void compare_on_film(const Domain& domain) {
  Elements el = film(7, 30, 100, 60.0);  // 2970 bonds: 2 threads from 2048
  auto batched = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  auto scalar = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  // Deformed by random displacements and rotations.
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  for (std::size_t i = 0; i < el.size(); ++i) {
    el.x[i] += 0.05 * u01(rng) * random_unit(rng);
    el.q[i] = (rotation(random_unit(rng), 0.05 * u01(rng)) * el.q[i]).normalized();
  }
  scalar->set_evaluation(BondEvaluation::Scalar);
  ASSERT_EQ(batched->evaluation(), BondEvaluation::Batched);  // the default
  if (domain.any_periodic())
    for (Vec3& x : el.x) x = domain.wrap(x);  // bonds now cross the box's faces
  batched->bind_domain(&domain);
  scalar->bind_domain(&domain);
  const Scale s = bond_scale(batched->bonds()[0]);
  for (int threads : {1, 2}) {
    const Eval ref = evaluate(*scalar, el, threads);
    const Eval got = evaluate(*batched, el, threads);
    double df = 0, dt = 0, fmax = 0;
    Vec3 f_sum = Vec3::Zero(), l_sum = Vec3::Zero();
    for (std::size_t i = 0; i < el.size(); ++i) {
      df = std::max(df, (got.f[i] - ref.f[i]).norm());
      dt = std::max(dt, (got.t[i] - ref.t[i]).norm());
      fmax = std::max(fmax, ref.f[i].norm());
      f_sum += got.f[i];
      l_sum += el.x[i].cross(got.f[i]) + got.t[i];
    }
    EXPECT_GT(fmax, 1e-3 * s.force);  // loaded bonds
    EXPECT_LT(df, 2 * kRoundOff * s.force) << threads << " threads";
    EXPECT_LT(dt, 2 * kRoundOff * s.torque) << threads << " threads";
    for (EnergyTerm t : kTerms) {
      EXPECT_GT(term(ref.e, t), 0.0);
      EXPECT_NEAR(term(got.e, t), term(ref.e, t), kRoundOff * s.energy * el.size());
    }
    // Internal forces: no net force; no net moment in an open domain (objectivity).
    EXPECT_LT(f_sum.norm(), 1e-12 * s.force * el.size());
    if (!domain.any_periodic()) {
      EXPECT_LT(l_sum.norm(), 1e-12 * s.torque * 30 * el.size());
    }
    // Fixed order of the sums: the same bits on a second evaluation.
    EXPECT_EQ(evaluate(*batched, el, threads), got) << threads << " threads";
    std::printf("film (%s), %d threads: force %.3g, torque %.3g of the bond scale\n",
                domain.any_periodic() ? "periodic" : "open", threads, df / s.force, dt / s.torque);
  }
}

TEST(BondSimd, FilmThroughComputeEqualsScalarCode) {
  compare_on_film(Domain{});
  compare_on_film(Domain(Vec3(-30, -30, -50), Vec3(30, 30, 50), {true, true, false}));
}

// Stiffnesses edited through bonds() after an evaluation: the batched copy of the rest state
// follows (every load is linear in the stiffness, and doubling is exact in floating point).
TEST(BondSimd, RestStateFollowsEditsOfTheBonds) {
  BondCase c;
  random_bonds(c, 100, 6, false);
  const Eval before = evaluate(c.batched, c.el, 1);
  for (Bond& b : c.batched.bonds()) {
    b.k.kn_area *= 2;
    b.k.ks_area *= 2;
    b.k.kn_inertia *= 2;
    b.k.ks_polar *= 2;
  }
  const Eval after = evaluate(c.batched, c.el, 1);
  for (std::size_t i = 0; i < c.el.size(); ++i) {
    EXPECT_EQ(after.f[i], 2 * before.f[i]);
    EXPECT_EQ(after.t[i], 2 * before.t[i]);
  }
  for (EnergyTerm t : kTerms) EXPECT_EQ(term(after.e, t), 2 * term(before.e, t));
}

}  // namespace
