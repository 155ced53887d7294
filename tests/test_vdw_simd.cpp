// The vectorised (batched) CNT–CNT vdW kernel against the scalar reference (vdw_pair): pair by
// pair over random pairs covering every branch of the law, and over a whole random film through
// the pair driver (open and periodic, filtered and unfiltered lists, 1 and 2 threads); and the
// batched evaluation's determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "hwy/targets.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/neighbor/neighbor_list.h"
#include "mdem/scene/tube_builder.h"

using namespace mdem;

namespace {

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Vec3 v(g(rng), g(rng), g(rng));
  return v.normalized();
}

// Pair classes the random set must reach (each is asserted to occur).
struct Coverage {
  int overlap = 0, lj = 0, ramp = 0, beyond = 0, window = 0, antiparallel = 0, coincident = 0,
      parallel = 0, below_knee = 0;
};

// Random pairs over all branches: centre distances from coincident to beyond the cutoff,
// axes random, near-parallel and antiparallel, near-perpendicular (flip-blend window), and
// centre lines along an axis (end to end).
struct PairSet {
  std::vector<Vec3> r, b1, b2;
};

PairSet random_pairs(const VdwParams& p, int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  PairSet s;
  const double rc = p.cutoff();
  for (int k = 0; k < n; ++k) {
    const Vec3 b1 = random_unit(rng);
    Vec3 b2 = random_unit(rng);
    const int axes_kind = k % 5;
    if (axes_kind == 1) b2 = (b1 + 1e-3 * u01(rng) * random_unit(rng)).normalized();   // parallel
    if (axes_kind == 2) b2 = -(b1 + 1e-2 * u01(rng) * random_unit(rng)).normalized();  // anti
    if (axes_kind == 3) {  // γ near 90°: |b1·b2| < 0.25
      const Vec3 perp = b1.cross(random_unit(rng)).normalized();
      b2 = (perp + (0.5 * u01(rng) - 0.25) * b1).normalized();
    }
    Vec3 dir = random_unit(rng);
    if (k % 7 == 0) dir = (b1 + 0.05 * random_unit(rng)).normalized();  // nearly coaxial
    double R;
    const int dist_kind = k % 11;
    if (dist_kind == 0)
      R = std::pow(10.0, -14.0 + 8.0 * u01(rng));  // 1e-14 .. 1e-6 nm: coincident-ish
    else if (dist_kind < 4)
      R = 0.05 + 1.6 * u01(rng);  // deep overlap: the linear branch
    else
      R = 1.2 * rc * u01(rng);  // everything up to 20 % beyond the cutoff
    s.r.push_back(R * dir);
    s.b1.push_back(b1);
    s.b2.push_back(b2);
  }
  return s;
}

// Largest |batched − scalar| over a pair's outputs, relative to the pair's scale
// (|U| + |f| + |τ1| + |τ2|, in eV with lengths in nm, at least 1e-6 eV), and the pair classes
// reached.
double max_relative_difference(const VdwParams& p, const PairSet& s, Coverage& cov) {
  const VdwConstants k(p);
  std::vector<VdwPairResult> batched(s.r.size());
  vdw_pairs_batched(k, s.r, s.b1, s.b2, batched);
  double worst = 0.0;
  for (std::size_t m = 0; m < s.r.size(); ++m) {
    const VdwPairResult ref = vdw_pair(k, Vec3::Zero(), s.b1[m], s.r[m], s.b2[m]);
    const VdwPairResult& got = batched[m];
    const double scale = std::abs(ref.energy) + ref.f1.norm() + ref.t1.norm() + ref.t2.norm();
    const double diff =
        std::max({std::abs(got.energy - ref.energy), (got.f1 - ref.f1).norm(),
                  (got.f2 - ref.f2).norm(), (got.t1 - ref.t1).norm(), (got.t2 - ref.t2).norm()});
    const double R = s.r[m].norm(), c = s.b1[m].dot(s.b2[m]);
    if (R >= p.cutoff()) ++cov.beyond;
    if (scale == 0.0) {
      EXPECT_EQ(diff, 0.0) << "pair " << m << " (beyond the cutoff) must give exact zeros";
      continue;
    }
    // The scale is floored at 1e-6 eV: at the end of the cutoff ramp the law fades to zero
    // while t = R/T − 3 has lost digits to cancellation (in either kernel), so a pair there is
    // compared to 1e-18 eV, ~1e-17 of the well depth, rather than to its own vanishing size.
    worst = std::max(worst, diff / std::max(scale, 1e-6));
    // Classes reached.
    if (R * R < 1e-24) ++cov.coincident;
    if (R < p.cutoff() && R > 3 * p.segment_length) ++cov.ramp;
    if (R < p.cutoff() && R / p.radius < p.w_knee) ++cov.below_knee;
    if (std::abs(c) < p.flip_blend) ++cov.window;
    if (c < 0) ++cov.antiparallel;
    if (std::abs(c) > 0.999) ++cov.parallel;
    // D at this pair, from the scalar code's δ (exposed for tests).
    if (R > 1e-12) {
      const Vec3 n = s.r[m] / R;
      const Vec3 b2f = c < 0 ? Vec3(-s.b2[m]) : s.b2[m];
      const double cos_t = std::clamp((s.b1[m] + b2f).normalized().dot(n), -1.0, 1.0);
      const double D = R / (p.radius * vdw_delta(p, std::acos(cos_t))) - 2.0;
      if (D < p.d_min)
        ++cov.overlap;
      else
        ++cov.lj;
    }
  }
  return worst;
}

void expect_covered(const Coverage& c) {
  EXPECT_GT(c.overlap, 100);
  EXPECT_GT(c.lj, 100);
  EXPECT_GT(c.ramp, 100);
  EXPECT_GT(c.beyond, 0);
  EXPECT_GT(c.window, 100);
  EXPECT_GT(c.antiparallel, 100);
  EXPECT_GT(c.coincident, 10);
  EXPECT_GT(c.parallel, 100);
  EXPECT_GT(c.below_knee, 100);
}

constexpr double kRoundOff = 1e-12;

TEST(VdwSimd, RandomPairsEqualScalarKernelDefaultModel) {
  const VdwParams p;  // flip_blend 0.2, exact torques
  Coverage cov;
  const double worst = max_relative_difference(p, random_pairs(p, 200000, 1), cov);
  EXPECT_LT(worst, kRoundOff) << "on " << vdw_simd_target();
  expect_covered(cov);
  std::printf("batched path on %s: largest relative difference %.3g\n", vdw_simd_target(), worst);
}

TEST(VdwSimd, RandomPairsEqualScalarKernelLiteralAndPfc) {
  VdwParams literal;
  literal.flip_blend = 0.0;
  Coverage cov;
  EXPECT_LT(max_relative_difference(literal, random_pairs(literal, 50000, 2), cov), kRoundOff);
  VdwParams pfc;
  pfc.torque = VdwTorque::Pfc;
  EXPECT_LT(max_relative_difference(pfc, random_pairs(pfc, 50000, 3), cov), kRoundOff);
  // Parameters that need pow(): the batched path falls back to the scalar code.
  VdwParams general;
  general.alpha = 9.0;
  general.w_exponent = 7.0;
  EXPECT_LT(max_relative_difference(general, random_pairs(general, 20000, 4), cov), kRoundOff);
}

// Every instruction set the build carries and this CPU runs (AVX-512, AVX2, SSE4, plain C++),
// forced in turn: the widest is what runs, but a CPU without it gets the next.
TEST(VdwSimd, EveryInstructionSetEqualsScalarKernel) {
  const VdwParams p;
  const PairSet pairs = random_pairs(p, 20000, 5);
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  EXPECT_GE(targets.size(), 2u);  // at least a vector set and the plain C++ fallback
  for (std::int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    EXPECT_STREQ(vdw_simd_target(), hwy::TargetName(target));
    Coverage cov;
    const double worst = max_relative_difference(p, pairs, cov);
    EXPECT_LT(worst, kRoundOff) << hwy::TargetName(target);
    std::printf("%s: largest relative difference %.3g\n", hwy::TargetName(target), worst);
  }
  hwy::SetSupportedTargetsForTest(0);
}

TEST(VdwSimd, NanPropagatesAndFarPairsAreZero) {
  const VdwConstants k{VdwParams{}};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Vec3> r = {Vec3(nan, 0, 0), Vec3(1e300, 0, 0), Vec3(0, 0, 1.7)};
  const std::vector<Vec3> b(3, Vec3::UnitX());
  const std::vector<Vec3> b2(3, Vec3::UnitY());
  std::vector<VdwPairResult> out(3);
  vdw_pairs_batched(k, r, b, b2, out);
  EXPECT_TRUE(std::isnan(out[0].energy));
  EXPECT_TRUE(std::isnan(out[0].f1.x()));
  EXPECT_EQ(out[1].energy, 0.0);
  EXPECT_EQ(out[1].f1, Vec3::Zero());
  EXPECT_EQ(out[1].t1, Vec3::Zero());
  EXPECT_LT(out[2].energy, 0.0);  // crossed tubes at 1.7 nm attract
  std::vector<VdwPairResult> short_out(2);
  EXPECT_THROW(vdw_pairs_batched(k, r, b, b2, short_out), std::invalid_argument);
}

// A random film of short tubes (with overlaps, so the linear branch is reached), intra-tube pairs
// excluded by the kernel.
Elements random_film(unsigned seed, double side, int tubes, int segments) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.5 * side, 0.5 * side), z(-2.0, 2.0);
  Elements el;
  const double T = VdwParams{}.segment_length;
  for (int t = 0; t < tubes; ++t) {
    Vec3 dir = random_unit(rng);
    dir.z() *= 0.1;
    dir.normalize();
    const Vec3 start(u(rng), u(rng), z(rng));
    for (int s = 0; s < segments; ++s)
      el.add(cnt_segment(start + s * T * dir, quat_from_axis(dir), t, s));
  }
  return el;
}

struct Forces {
  std::vector<Vec3> f, t;
  double energy = 0;
};

Forces evaluate(const AnisotropicVdw& vdw, const Elements& el, const NeighborList& nl,
                int threads) {
  ForceSink sink;
  sink.resize(el.size(), threads, false);
  vdw.compute(el, &nl, sink);
  Forces out;
  out.f.resize(el.size());
  out.t.resize(el.size());
  std::vector<Vec3> fd, td;
  out.energy = sink.reduce(out.f, out.t, fd, td).total_stored();
  return out;
}

// Largest difference of any element's force or torque, relative to the largest force or torque.
double relative_difference(const Forces& a, const Forces& b) {
  double scale = 0.0, diff = 0.0;
  for (std::size_t i = 0; i < a.f.size(); ++i) {
    scale = std::max({scale, a.f[i].norm(), a.t[i].norm()});
    diff = std::max({diff, (a.f[i] - b.f[i]).norm(), (a.t[i] - b.t[i]).norm()});
  }
  return diff / scale;
}

void compare_on_film(const Domain& domain, bool owned_list) {
  Elements el = random_film(7, 40.0, 60, 30);  // 1800 segments
  const AnisotropicVdw batched;
  const AnisotropicVdw scalar(VdwParams{}, VdwEvaluation::Scalar);
  NeighborList nl(batched.cutoff(), 0.5, domain);
  if (owned_list) {
    nl.set_exclusion([&batched](const Elements& e, std::size_t i, std::size_t j) {
      return batched.excludes(e, i, j);
    });
    nl.set_owner(&batched);
  }
  nl.build(el);
  for (int threads : {1, 2}) {
    const Forces ref = evaluate(scalar, el, nl, threads);
    const Forces got = evaluate(batched, el, nl, threads);
    EXPECT_LT(relative_difference(ref, got), kRoundOff) << threads << " threads";
    EXPECT_NEAR(got.energy, ref.energy, kRoundOff * std::abs(ref.energy));
    EXPECT_NE(ref.energy, 0.0);  // pairs interact: the comparison is not of zeros
    // Fixed summation order: the same bits on a second evaluation.
    const Forces again = evaluate(batched, el, nl, threads);
    EXPECT_EQ(again.energy, got.energy);
    for (std::size_t i = 0; i < el.size(); ++i) {
      ASSERT_EQ(again.f[i], got.f[i]) << "element " << i;
      ASSERT_EQ(again.t[i], got.t[i]) << "element " << i;
    }
  }
  // Newton's third law and the balance of angular momentum hold for the batched sum as well.
  const Forces got = evaluate(batched, el, nl, 2);
  Vec3 f_sum = Vec3::Zero(), m_sum = Vec3::Zero();
  double f_scale = 0;
  for (std::size_t i = 0; i < el.size(); ++i) {
    f_sum += got.f[i];
    f_scale = std::max(f_scale, got.f[i].norm());
    if (!domain.any_periodic()) m_sum += el.x[i].cross(got.f[i]) + got.t[i];
  }
  EXPECT_LT(f_sum.norm(), 1e-10 * f_scale * el.size());
  EXPECT_LT(m_sum.norm(), 1e-10 * f_scale * 40.0 * el.size());
}

TEST(VdwSimd, FilmForcesEqualScalarKernelOpenDomain) {
  compare_on_film(Domain{}, true);
  compare_on_film(Domain{}, false);  // a list not built for the kernel: the driver filters
}

TEST(VdwSimd, FilmForcesEqualScalarKernelPeriodic) {
  compare_on_film(Domain(Vec3(-20, -20, -50), Vec3(20, 20, 50), {true, true, false}), true);
}

}  // namespace
