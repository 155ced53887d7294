// The vectorised (batched) CNT contact dashpot against its scalar reference (pair()): pair by
// pair over random pairs (distances from coincident to the cutoff, random relative velocities,
// unequal masses, NaN), on every instruction set the build carries, and over a random film
// through the pair driver (open and periodic, 1 and 2 threads), with the dashpot's own
// conservation laws (Newton's third law, angular momentum) and determinism of the batched sum;
// and the dashpot evaluated in one pass with its vdW contact against the two passes apart.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "hwy/targets.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/integrate/system.h"
#include "mdem/neighbor/neighbor_list.h"
#include "mdem/scene/tube_builder.h"

using namespace mdem;

namespace {

constexpr double kRoundOff = 1e-13;

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

// n random segments (masses scaled by 0.5 .. 2, random velocities up to 5 nm/ps) and a batch of
// pairs (0, 1), (2, 3), ... with displacements from 0 (coincident) to the cutoff.
struct PairCase {
  Elements el;
  std::vector<Vec3> d;
};

PairCase random_pairs(int pairs, double cutoff, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  PairCase c;
  for (int k = 0; k < 2 * pairs; ++k) {
    c.el.add(cnt_segment(Vec3::Zero(), Quat::Identity(), k, 0));
    c.el.mass[k] *= 0.5 + 1.5 * u01(rng);
    c.el.v[k] = 5.0 * u01(rng) * random_unit(rng);
  }
  for (int p = 0; p < pairs; ++p) {
    double R = cutoff * u01(rng);
    if (p % 13 == 0) R = 0.0;                                 // coincident: no centre line
    if (p % 17 == 0) R = std::pow(10.0, -12 + 6 * u01(rng));  // nearly coincident
    Vec3 dir = random_unit(rng);
    if (p % 5 == 0)  // relative velocity along the centre line
      dir = (c.el.v[2 * p + 1] - c.el.v[2 * p]).normalized();
    c.d.push_back(R * dir);
  }
  return c;
}

// Largest |batched − scalar| force over the pairs, relative to the pair's scale c·|v_rel| (its
// force were the relative velocity along the centre line: n·v_rel cancels digits when the two
// are nearly perpendicular, in either kernel), and the number of pairs with a non-zero force.
double max_relative_difference(const ContactDampingKernel& k, const PairCase& c, int& forced) {
  const ContactDampingKernel scalar(k.params(), DashpotEvaluation::Scalar);
  double worst = 0;
  forced = 0;
  const int pairs = static_cast<int>(c.d.size());
  for (int start = 0; start < pairs; start += PairBatch::kCapacity) {
    PairBatch b;
    b.n = std::min(PairBatch::kCapacity, pairs - start);
    for (int p = 0; p < b.n; ++p) {
      b.i[p] = static_cast<std::uint32_t>(2 * (start + p));
      b.j[p] = b.i[p] + 1;
      b.dx[p] = c.d[start + p].x();
      b.dy[p] = c.d[start + p].y();
      b.dz[p] = c.d[start + p].z();
    }
    k.batch(c.el, b);
    for (int p = 0; p < b.n; ++p) {
      PairForces ref;
      const bool acts = scalar.pair(c.el, b.i[p], b.j[p], c.d[start + p], ref);
      const Vec3 got(b.fx[p], b.fy[p], b.fz[p]);
      if (!acts) {
        EXPECT_EQ(got, Vec3::Zero()) << "pair " << start + p << " has no centre line";
        continue;
      }
      EXPECT_EQ(ref.f1, -ref.f2);
      forced += ref.f1.norm() > 0;
      const double scale = dashpot_coefficient(k.params().ratio, c.el.mass[b.i[p]],
                                               c.el.mass[b.j[p]], k.params().stiffness) *
                           (c.el.v[b.j[p]] - c.el.v[b.i[p]]).norm();
      worst = std::max(worst, (got - ref.f1).norm() / scale);
    }
  }
  return worst;
}

TEST(DashpotSimd, RandomPairsEqualScalarKernel) {
  const ContactDampingKernel k(ContactDampingParams{});
  const PairCase c = random_pairs(20000, k.cutoff(), 1);
  int forced = 0;
  const double worst = max_relative_difference(k, c, forced);
  EXPECT_LT(worst, kRoundOff) << "on " << contact_damping_simd_target();
  EXPECT_GT(forced, 18000);  // the comparison is not of zeros
  std::printf("batched dashpot on %s: largest relative difference %.3g\n",
              contact_damping_simd_target(), worst);
  // Another ratio and stiffness: the coefficient is the batch's, not a constant of the build.
  ContactDampingParams p;
  p.ratio = 0.7;
  p.stiffness = 3.5;
  EXPECT_LT(max_relative_difference(ContactDampingKernel(p), c, forced), kRoundOff);
  // With the shear dashpot (the whole relative velocity).
  p.shear = true;
  const double shear = max_relative_difference(ContactDampingKernel(p), c, forced);
  EXPECT_LT(shear, kRoundOff);
  EXPECT_GT(forced, 18000);
}

// The shear dashpot against Eq. 33-34 by hand: two segments 2 nm apart along x (masses m and 2m),
// moving apart along the centre line at 0.3 nm/ps and sliding across it at 0.4 nm/ps along y and
// −0.1 along z. c = 2ψ√(m_eff k), m_eff = 2m/3; normal-only: F_2 = −c·0.3 x̂; with shear
// F_2 = −c·(0.3, 0.4, −0.1); F_1 = −F_2 in both, and the dissipated power −F·v_rel < 0.
TEST(DashpotShear, SlidingAcrossTheCentreLineIsDampedByHand) {
  Elements el;
  el.add(cnt_segment(Vec3::Zero(), Quat::Identity(), 0, 0));
  el.add(cnt_segment(Vec3(2, 0, 0), Quat::Identity(), 1, 0));
  const double m = el.mass[0];
  el.mass[1] = 2 * m;
  el.v[0] = Vec3(0.1, -0.2, 0.05);
  const Vec3 u(0.3, 0.4, -0.1);
  el.v[1] = el.v[0] + u;
  ContactDampingParams p;
  const double c = 2 * p.ratio * std::sqrt(2 * m / 3 * p.stiffness);
  for (bool shear : {false, true}) {
    p.shear = shear;
    for (DashpotEvaluation e : {DashpotEvaluation::Scalar, DashpotEvaluation::Batched}) {
      const ContactDampingKernel k(p, e);
      Vec3 f1, f2;
      if (e == DashpotEvaluation::Scalar) {
        PairForces out;
        ASSERT_TRUE(k.pair(el, 0, 1, Vec3(2, 0, 0), out));
        f1 = out.f1;
        f2 = out.f2;
      } else {
        PairBatch b;
        b.n = 1;
        b.i[0] = 0;
        b.j[0] = 1;
        b.dx[0] = 2;
        b.dy[0] = b.dz[0] = 0;
        k.batch(el, b);
        f1 = Vec3(b.fx[0], b.fy[0], b.fz[0]);
        f2 = -f1;
      }
      const Vec3 expected = shear ? Vec3(-c * u) : Vec3(-c * 0.3, 0, 0);
      EXPECT_LT((f2 - expected).norm(), 1e-14 * c) << "shear " << shear;
      EXPECT_EQ(f1, -f2);
      EXPECT_LT(f2.dot(u), 0.0);
    }
  }
}

TEST(DashpotSimd, EveryInstructionSetEqualsScalarKernel) {
  const ContactDampingKernel k(ContactDampingParams{});
  const PairCase c = random_pairs(4000, k.cutoff(), 2);
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  EXPECT_GE(targets.size(), 2u);  // at least a vector set and the plain C++ fallback
  for (std::int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    EXPECT_STREQ(contact_damping_simd_target(), hwy::TargetName(target));
    int forced = 0;
    const double worst = max_relative_difference(k, c, forced);
    EXPECT_LT(worst, kRoundOff) << hwy::TargetName(target);
    ContactDampingParams p;
    p.shear = true;
    EXPECT_LT(max_relative_difference(ContactDampingKernel(p), c, forced), kRoundOff)
        << hwy::TargetName(target) << " with shear";
    std::printf("%s: largest relative difference %.3g\n", hwy::TargetName(target), worst);
  }
  hwy::SetSupportedTargetsForTest(0);
}

TEST(DashpotSimd, NanPropagates) {
  PairCase c = random_pairs(3, 5.0, 3);
  c.d[1] = Vec3(std::numeric_limits<double>::quiet_NaN(), 0, 0);
  c.el.v[4] = Vec3(std::numeric_limits<double>::quiet_NaN(), 0, 0);  // pair 2's velocity
  c.d[2] = Vec3(1, 0, 0);
  const ContactDampingKernel k(ContactDampingParams{});
  PairBatch b;
  b.n = 3;
  for (int p = 0; p < 3; ++p) {
    b.i[p] = static_cast<std::uint32_t>(2 * p);
    b.j[p] = b.i[p] + 1;
    b.dx[p] = c.d[p].x();
    b.dy[p] = c.d[p].y();
    b.dz[p] = c.d[p].z();
  }
  k.batch(c.el, b);
  EXPECT_TRUE(std::isnan(b.fx[1]));
  EXPECT_TRUE(std::isnan(b.fx[2]));
}

// A random film of short tubes with random velocities, intra-tube pairs excluded.
Elements random_film(unsigned seed, double side, int tubes, int segments) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.5 * side, 0.5 * side), z(-2.0, 2.0);
  Elements el;
  const double T = ContactDampingParams{}.cutoff / 4;
  for (int t = 0; t < tubes; ++t) {
    Vec3 dir = random_unit(rng);
    dir.z() *= 0.1;
    dir.normalize();
    const Vec3 start(u(rng), u(rng), z(rng));
    for (int s = 0; s < segments; ++s) {
      el.add(cnt_segment(start + s * T * dir, quat_from_axis(dir), t, s));
      el.v.back() = 2.0 * random_unit(rng);
    }
  }
  return el;
}

std::vector<Vec3> damping_forces(const ViscousContactDamping& m, const Elements& el,
                                 const NeighborList& nl, int threads) {
  ForceSink sink;
  sink.resize(el.size(), threads, true);
  m.compute(el, &nl, sink);
  std::vector<Vec3> f(el.size()), t(el.size()), fd(el.size()), td(el.size());
  sink.reduce(f, t, fd, td);
  for (const Vec3& x : td) EXPECT_EQ(x, Vec3::Zero());  // a central force: no torques
  return fd;
}

void compare_on_film(const Domain& domain, bool shear) {
  const Elements el = random_film(7, 40.0, 60, 30);  // 1800 segments, 2 threads from 4096 pairs
  ContactDampingParams p;
  p.shear = shear;
  const ViscousContactDamping batched(p);
  const ViscousContactDamping scalar(p, DashpotEvaluation::Scalar);
  NeighborList nl(batched.cutoff(), 0.5, domain);
  nl.set_exclusion([&batched](const Elements& e, std::size_t i, std::size_t j) {
    return batched.excludes(e, i, j);
  });
  nl.set_owner(&batched);
  nl.build(el);
  ASSERT_GT(nl.pair_count(), 4096u);
  for (int threads : {1, 2}) {
    const std::vector<Vec3> ref = damping_forces(scalar, el, nl, threads);
    const std::vector<Vec3> got = damping_forces(batched, el, nl, threads);
    double scale = 0, diff = 0, power = 0;
    Vec3 f_sum = Vec3::Zero(), m_sum = Vec3::Zero();
    for (std::size_t i = 0; i < el.size(); ++i) {
      scale = std::max(scale, ref[i].norm());
      diff = std::max(diff, (got[i] - ref[i]).norm());
      f_sum += got[i];
      m_sum += el.x[i].cross(got[i]);
      power += got[i].dot(el.v[i]);
    }
    EXPECT_GT(scale, 0.0);
    EXPECT_LT(diff, kRoundOff * scale) << threads << " threads";
    // A dashpot only dissipates, and its pair forces are equal and opposite (along the centre
    // line without shear, so then they also keep the angular momentum).
    EXPECT_LT(power, 0.0);
    EXPECT_LT(f_sum.norm(), 1e-12 * scale * el.size());
    if (!domain.any_periodic() && !shear) {
      EXPECT_LT(m_sum.norm(), 1e-12 * scale * 40.0 * el.size());
    }
    // Fixed summation order: the same bits on a second evaluation.
    EXPECT_EQ(damping_forces(batched, el, nl, threads), got);
  }
}

TEST(DashpotSimd, FilmForcesEqualScalarKernel) {
  compare_on_film(Domain{}, false);
  compare_on_film(Domain{}, true);
  compare_on_film(Domain(Vec3(-20, -20, -50), Vec3(20, 20, 50), {true, true, false}), false);
}

// Everything a force evaluation leaves: the reduced forces, torques, damping forces and torques,
// and the stored energy.
struct Evaluation {
  std::vector<Vec3> f, t, fd, td;
  double energy = 0;
  bool operator==(const Evaluation&) const = default;
};

template <class Compute>
Evaluation evaluate(const Elements& el, int threads, Compute compute) {
  ForceSink sink;
  sink.resize(el.size(), threads, true);
  compute(sink);
  Evaluation e{std::vector<Vec3>(el.size()), std::vector<Vec3>(el.size()),
               std::vector<Vec3>(el.size()), std::vector<Vec3>(el.size())};
  e.energy = sink.reduce(e.f, e.t, e.fd, e.td).total_stored();
  return e;
}

// One pass over the vdW contact's list for the contact and its dashpot gives, bit for bit, what
// the two passes give one after the other: the same lanes in the same order, each kernel into
// its own buffers (a fused pass that dropped a batch, mixed the buffers or scattered the dashpot
// onto the contact's lanes would differ by whole pair forces).
void fused_equals_apart(const Domain& domain, bool shear) {
  Elements el = random_film(11, 40.0, 60, 30);
  // Rotate the segments a little off their tube axes, so the vdW torques are not trivial.
  std::mt19937_64 rng(3);
  for (std::size_t i = 0; i < el.size(); ++i)
    el.q[i] = (Quat(Eigen::AngleAxisd(0.2, random_unit(rng))) * el.q[i]).normalized();
  const AnisotropicVdw vdw;
  ContactDampingParams p;
  p.shear = shear;
  const ViscousContactDamping dashpot(p);
  ASSERT_EQ(vdw.cutoff(), dashpot.cutoff());
  NeighborList nl(vdw.cutoff(), 0.5, domain);
  nl.set_exclusion(
      [&vdw](const Elements& e, std::size_t i, std::size_t j) { return vdw.excludes(e, i, j); });
  nl.set_owner(&vdw);
  nl.build(el);
  ASSERT_GT(nl.pair_count(), 4096u);
  for (int threads : {1, 2}) {
    const Evaluation apart = evaluate(el, threads, [&](ForceSink& s) {
      vdw.compute(el, &nl, s);
      dashpot.compute(el, &nl, s);
    });
    bool fused = false;
    const Evaluation one =
        evaluate(el, threads, [&](ForceSink& s) { fused = dashpot.compute_with(vdw, el, &nl, s); });
    ASSERT_TRUE(fused) << threads << " threads";
    EXPECT_NE(apart.energy, 0.0);
    EXPECT_GT(apart.fd[0].norm() + apart.fd[100].norm(), 0.0);
    EXPECT_TRUE(one == apart) << threads << " threads, shear " << shear;
  }
  // Not fused (the caller then computes each): a scalar dashpot, another owner, no list.
  const ViscousContactDamping scalar(p, DashpotEvaluation::Scalar);
  ForceSink sink;
  sink.resize(el.size(), 1, true);
  EXPECT_FALSE(scalar.compute_with(vdw, el, &nl, sink));
  EXPECT_FALSE(dashpot.compute_with(dashpot, el, &nl, sink));
  EXPECT_FALSE(dashpot.compute_with(vdw, el, nullptr, sink));
}

TEST(DashpotFused, OnePassWithTheVdwContactEqualsTwoPasses) {
  fused_equals_apart(Domain{}, false);
  fused_equals_apart(Domain{}, true);
  fused_equals_apart(Domain(Vec3(-20, -20, -50), Vec3(20, 20, 50), {true, true, false}), false);
}

// The system fuses the two whichever order they were added in, and its forces are those of the
// two passes apart.
TEST(DashpotFused, SystemForcesEqualTwoPassesInEitherOrder) {
  const Elements el = random_film(5, 40.0, 60, 30);
  Evaluation got[2];
  for (int order : {0, 1}) {
    IntegratorSettings s;
    s.threads = 2;
    System sys(el, s);
    if (order == 0) sys.add(std::make_unique<AnisotropicVdw>());
    sys.add(std::make_unique<ViscousContactDamping>(ContactDampingParams{}));
    if (order == 1) sys.add(std::make_unique<AnisotropicVdw>());
    sys.initialize();
    const auto& E = sys.elements();
    // The dashpot is a central force: no damping torques (the system keeps no public copy).
    got[order] = {E.f, E.t, sys.damping_forces(), std::vector<Vec3>(E.size(), Vec3::Zero()),
                  sys.energy().potential.total_stored()};
    const auto* vdw = sys.find<AnisotropicVdw>();
    const auto* dashpot = sys.find<ViscousContactDamping>();
    const NeighborList* nl = sys.neighbors(*vdw);
    ASSERT_EQ(nl, sys.neighbors(*dashpot));
    const Evaluation apart = evaluate(E, 2, [&](ForceSink& k) {
      vdw->compute(E, nl, k);
      dashpot->compute(E, nl, k);
    });
    EXPECT_TRUE(got[order] == apart) << "order " << order;
  }
  EXPECT_TRUE(got[0] == got[1]);
}

}  // namespace
