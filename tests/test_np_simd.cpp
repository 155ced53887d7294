// The NP kernels in batches against their scalar references. The NP–CNT law (NpCntEvaluation::
// Scalar): isolated NP–segment pairs covering every branch of the law in both element orders, on
// every instruction set this CPU runs; a film of tubes and NPs through the pair driver at 1 and 2
// threads, with the batched sums' determinism and momentum balances, over a list of all kinds
// (pairs under the segments) and over the NP–CNT sub-list (pairs under the NPs). The NP–NP law
// (NpNpEvaluation::Scalar): pairs through every branch on every instruction set, and NPs through
// the driver. The NP dashpots (DashpotEvaluation::Scalar) on the same film; the NP–CNT dashpot in
// one pass with its contact, bit for bit the two passes, in the driver and in a system.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "hwy/targets.h"
#include "mdem/core/cnt.h"
#include "mdem/force/contact/np_cnt_contact.h"
#include "mdem/force/contact/np_np_contact.h"
#include "mdem/force/damping/np_contact_damping.h"
#include "mdem/integrate/system.h"
#include "mdem/neighbor/neighbor_list.h"
#include "mdem/scene/nanoparticle.h"
#include "mdem/scene/tube_builder.h"

using namespace mdem;

namespace {

constexpr double kRoundOff = 1e-12;

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

// Pair classes the random set must reach (each is asserted to occur).
struct Coverage {
  int linear = 0, power = 0, ramp = 0, beyond = 0, coincident = 0, end_on = 0, np_first = 0,
      segment_first = 0;
};

// n NP–segment pairs 40 nm apart along y (far beyond the 5.4 nm cutoff, so each element's force
// is its own pair's), NP first in every other pair: centre distances from coincident through the
// linear branch and the well to beyond the cutoff, directions random or near the segment's axis.
struct PairSet {
  Elements el;
  std::vector<Vec3> x_np, x_seg, axis;
  std::vector<std::size_t> np, seg;  // element indices of pair m
};

PairSet isolated_pairs(int n, unsigned seed, Coverage& cov) {
  const NpCntParams p;
  const NpCntKernel k(p, NpCntEvaluation::Scalar);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  PairSet s;
  for (int m = 0; m < n; ++m) {
    const Vec3 centre(0.0, 40.0 * m, 0.0);
    const Vec3 axis = random_unit(rng);
    Vec3 dir = random_unit(rng);
    if (m % 5 == 0) dir = (axis + 0.05 * random_unit(rng)).normalized();  // end-on
    double R;
    const int kind = m % 10;
    if (kind == 0)
      R = std::pow(10.0, -14.0 + 8.0 * u01(rng));  // 1e-14 .. 1e-6 nm: coincident-ish
    else if (kind < 4)
      R = 0.05 + 3.0 * u01(rng);  // overlap: mostly the linear branch
    else
      R = 1.15 * p.cutoff() * u01(rng);  // through the well and the ramp, to beyond the cutoff
    const Vec3 x_np = centre + R * dir;
    const bool np_first = m % 2 == 0;
    if (np_first) {
      s.np.push_back(s.el.add(nanoparticle(x_np)));
      s.seg.push_back(s.el.add(cnt_segment(centre, quat_from_axis(axis), m, 0)));
      ++cov.np_first;
    } else {
      s.seg.push_back(s.el.add(cnt_segment(centre, quat_from_axis(axis), m, 0)));
      s.np.push_back(s.el.add(nanoparticle(x_np)));
      ++cov.segment_first;
    }
    s.x_np.push_back(x_np);
    s.x_seg.push_back(centre);
    s.axis.push_back(s.el.axis(s.seg.back()));
    if (R >= p.cutoff()) {
      ++cov.beyond;
      continue;
    }
    if (R * R < 1e-24) ++cov.coincident;
    if (R > 3 * p.segment_length) ++cov.ramp;
    if (std::abs(axis.dot(dir)) > 0.99) ++cov.end_on;
    if (k.separation(x_np, centre, s.axis.back()) < p.d_min)
      ++cov.linear;
    else
      ++cov.power;
  }
  return s;
}

struct Forces {
  std::vector<Vec3> f, t;
  double energy = 0;
};

// The model's pairs: a list of all kinds with the model's exclusion (each pair under its lower
// index), or (kind_list) the model's own sub-list as a system builds it (an NP–CNT pair under its
// NP, the rarer kind).
NeighborList list_of(const ForceModel& m, const Elements& el, const Domain& domain = Domain{},
                     bool kind_list = false) {
  NeighborList nl(m.cutoff(), 0.5, domain);
  if (kind_list) nl.set_kinds(m.kinds());
  nl.set_exclusion(
      [&m](const Elements& e, std::size_t i, std::size_t j) { return m.excludes(e, i, j); });
  nl.set_owner(&m);
  nl.build(el);
  return nl;
}

template <class M>
Forces evaluate(const M& m, const Elements& el, int threads, const Domain& domain = Domain{},
                bool kind_list = false) {
  const NeighborList nl = list_of(m, el, domain, kind_list);
  ForceSink sink;
  sink.resize(el.size(), threads, false);
  m.compute(el, &nl, sink);
  Forces out;
  out.f.resize(el.size());
  out.t.resize(el.size());
  std::vector<Vec3> fd, td;
  out.energy = sink.reduce(out.f, out.t, fd, td).total_stored();
  return out;
}

// Largest |batched − scalar| of a pair's forces and torques, relative to the pair's scale:
// |U| + |f| + |τ| of the scalar law (eV, lengths in nm, as test_vdw_simd's: at the well's minimum
// the force is the difference of two terms ~100× its size), at least 1e-4 (1e-3 of the well's
// depth): near the end of the cutoff ramp f_c ≈ 3(1 − t)², t = (R − 3T)/T, turns the last-bit
// difference of R (the SIMD |d|² is fused) into ~1e-13 of f_c, and such a pair's own size into
// nothing. Also checks the total energy against Σ|U| of the pairs, and that the NP gets no torque.
double max_relative_difference(const PairSet& s) {
  const NpCntContact batched;
  const NpCntContact scalar(NpCntParams{}, NpCntEvaluation::Scalar);
  const Forces ref = evaluate(scalar, s.el, 1);
  const Forces got = evaluate(batched, s.el, 1);
  const NpCntKernel law(NpCntParams{}, NpCntEvaluation::Scalar);
  double worst = 0.0, sum_abs_u = 0.0;
  for (std::size_t m = 0; m < s.np.size(); ++m) {
    const std::size_t a = s.np[m], b = s.seg[m];
    const PairForces one = law.evaluate(s.x_np[m], s.x_seg[m], s.axis[m]);
    sum_abs_u += std::abs(one.energy);
    // The scalar driver's sums are the single-pair law's (one pair per element).
    EXPECT_EQ(ref.f[a], one.f1) << "pair " << m;
    const double scale = std::abs(one.energy) + ref.f[a].norm() + ref.t[b].norm();
    const double diff = std::max(
        {(got.f[a] - ref.f[a]).norm(), (got.f[b] - ref.f[b]).norm(), (got.t[b] - ref.t[b]).norm()});
    EXPECT_EQ(got.t[a], Vec3::Zero()) << "pair " << m << ": the NP takes no torque";
    if (scale == 0.0 && one.energy == 0.0) {
      EXPECT_EQ(diff, 0.0) << "pair " << m << " (beyond the cutoff) must give exact zeros";
      continue;
    }
    worst = std::max(worst, diff / std::max(scale, 1e-4));
  }
  EXPECT_NE(ref.energy, 0.0);
  EXPECT_NEAR(got.energy, ref.energy, kRoundOff * sum_abs_u);
  return worst;
}

void expect_covered(const Coverage& c) {
  EXPECT_GT(c.linear, 100);
  EXPECT_GT(c.power, 100);
  EXPECT_GT(c.ramp, 100);
  EXPECT_GT(c.beyond, 10);
  EXPECT_GT(c.coincident, 10);
  EXPECT_GT(c.end_on, 100);
  EXPECT_GT(c.np_first, 100);
  EXPECT_GT(c.segment_first, 100);
}

TEST(NpCntSimd, IsolatedPairsEqualTheScalarLaw) {
  Coverage cov;
  const PairSet s = isolated_pairs(20000, 1, cov);
  const double worst = max_relative_difference(s);
  EXPECT_LT(worst, kRoundOff) << "on " << np_cnt_simd_target();
  expect_covered(cov);
  std::printf("batched NP-CNT law on %s: largest relative difference %.3g\n", np_cnt_simd_target(),
              worst);
}

// Every instruction set the build carries and this CPU runs, forced in turn.
TEST(NpCntSimd, EveryInstructionSetEqualsTheScalarLaw) {
  Coverage cov;
  const PairSet s = isolated_pairs(4000, 2, cov);
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  EXPECT_GE(targets.size(), 2u);  // at least a vector set and the plain C++ fallback
  for (std::int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    EXPECT_STREQ(np_cnt_simd_target(), hwy::TargetName(target));
    const double worst = max_relative_difference(s);
    EXPECT_LT(worst, kRoundOff) << hwy::TargetName(target);
    std::printf("%s: largest relative difference %.3g\n", hwy::TargetName(target), worst);
  }
  hwy::SetSupportedTargetsForTest(0);
}

// A film of short tubes with NPs among them (some overlapping, so the linear branch is reached).
Elements film_with_nps(unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-20.0, 20.0), z(-2.0, 2.0);
  Elements el;
  for (int t = 0; t < 40; ++t) {
    Vec3 dir = random_unit(rng);
    dir.z() *= 0.1;
    dir.normalize();
    const Vec3 start(u(rng), u(rng), z(rng));
    for (int s = 0; s < 25; ++s)
      el.add(cnt_segment(start + s * cnt::kSegmentLength * dir, quat_from_axis(dir), t, s));
  }
  for (int k = 0; k < 150; ++k) el.add(nanoparticle(Vec3(u(rng), u(rng), z(rng))));
  for (std::size_t i = 0; i < el.size(); ++i) el.v[i] = 2.0 * random_unit(rng);  // dashpots
  return el;
}

double relative_difference(const Forces& a, const Forces& b) {
  double scale = 0.0, diff = 0.0;
  for (std::size_t i = 0; i < a.f.size(); ++i) {
    scale = std::max({scale, a.f[i].norm(), a.t[i].norm()});
    diff = std::max({diff, (a.f[i] - b.f[i]).norm(), (a.t[i] - b.t[i]).norm()});
  }
  return diff / scale;
}

void compare_on_film(const Domain& domain) {
  const Elements el = film_with_nps(7);  // 1000 segments, 150 NPs
  const NpCntContact batched;
  const NpCntContact scalar(NpCntParams{}, NpCntEvaluation::Scalar);
  for (int threads : {1, 2}) {
    const Forces ref = evaluate(scalar, el, threads, domain);
    const Forces got = evaluate(batched, el, threads, domain);
    EXPECT_NE(ref.energy, 0.0);  // pairs interact: the comparison is not of zeros
    EXPECT_LT(relative_difference(ref, got), kRoundOff) << threads << " threads";
    EXPECT_NEAR(got.energy, ref.energy, kRoundOff * std::abs(ref.energy));
    // Fixed summation order: the same bits on a second evaluation.
    const Forces again = evaluate(batched, el, threads, domain);
    EXPECT_EQ(again.energy, got.energy);
    for (std::size_t i = 0; i < el.size(); ++i) {
      ASSERT_EQ(again.f[i], got.f[i]) << "element " << i;
      ASSERT_EQ(again.t[i], got.t[i]) << "element " << i;
    }
  }
  // The NP–CNT sub-list holds the pairs under the NPs (after the segments in index order), the
  // list of all kinds under the segments: the same forces to round-off.
  for (int threads : {1, 2}) {
    const Forces ref = evaluate(scalar, el, threads, domain);
    const Forces got = evaluate(batched, el, threads, domain, true);
    EXPECT_LT(relative_difference(ref, got), kRoundOff) << threads << " threads, NP rows";
    EXPECT_NEAR(got.energy, ref.energy, kRoundOff * std::abs(ref.energy));
  }
  // Newton's third law and the balance of angular momentum hold for the batched sums.
  const Forces got = evaluate(batched, el, 2, domain);
  Vec3 f_sum = Vec3::Zero(), m_sum = Vec3::Zero();
  double f_scale = 0;
  for (std::size_t i = 0; i < el.size(); ++i) {
    f_sum += got.f[i];
    f_scale = std::max(f_scale, got.f[i].norm());
    if (!domain.any_periodic()) m_sum += el.x[i].cross(got.f[i]) + got.t[i];
  }
  EXPECT_GT(f_scale, 0.0);
  EXPECT_LT(f_sum.norm(), 1e-10 * f_scale * el.size());
  EXPECT_LT(m_sum.norm(), 1e-10 * f_scale * 40.0 * el.size());
}

TEST(NpCntSimd, FilmForcesEqualTheScalarLawOpenDomain) { compare_on_film(Domain{}); }

TEST(NpCntSimd, FilmForcesEqualTheScalarLawPeriodic) {
  compare_on_film(Domain(Vec3(-20, -20, -50), Vec3(20, 20, 50), {true, true, false}));
}

// NP–NP centre displacements through every branch of the law: coincident, overlapping (the
// linear branch below D = d_min), the well, the taper from 7 to 8 nm, and beyond the cutoff.
struct NpNpCoverage {
  int coincident = 0, linear = 0, power = 0, taper = 0, beyond = 0;
};

std::vector<Vec3> np_np_displacements(int n, unsigned seed, NpNpCoverage& cov) {
  const NpNpParams p;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::vector<Vec3> out;
  for (int m = 0; m < n; ++m) {
    double R;
    const int kind = m % 10;
    if (kind == 0)
      R = std::pow(10.0, -14.0 + 8.0 * u01(rng));  // 1e-14 .. 1e-6 nm
    else if (kind < 3)
      R = p.radius * (2.0 + p.d_min) * u01(rng);  // overlapping: D < d_min
    else
      R = 1.1 * p.cutoff() * u01(rng);
    out.push_back(R * random_unit(rng));
    if (R * R < 1e-24)
      ++cov.coincident;
    else if (R >= p.cutoff())
      ++cov.beyond;
    else if (R > p.taper_start)
      ++cov.taper;
    else if (R / p.radius - 2.0 < p.d_min)
      ++cov.linear;
    else
      ++cov.power;
  }
  return out;
}

// Largest difference of the batched law from the scalar one over the displacements, a batch at a
// time, relative to the pair's |U| + |f| (at least 1e-4 eV, as the NP–CNT comparison); a pair
// beyond the cutoff must give exact zeros, and no pair a torque.
double np_np_worst(const std::vector<Vec3>& ds) {
  const NpNpKernel batched;
  const NpNpKernel scalar(NpNpParams{}, NpNpEvaluation::Scalar);
  EXPECT_TRUE(batched.batched());
  EXPECT_FALSE(scalar.batched());
  const Elements none;  // the law reads no element data
  double worst = 0;
  for (std::size_t start = 0; start < ds.size(); start += PairBatch::kCapacity) {
    PairBatch b;
    b.n = static_cast<int>(std::min<std::size_t>(PairBatch::kCapacity, ds.size() - start));
    for (int p = 0; p < b.n; ++p) {
      b.i[p] = 0;
      b.j[p] = 1;
      b.dx[p] = ds[start + p].x();
      b.dy[p] = ds[start + p].y();
      b.dz[p] = ds[start + p].z();
    }
    batched.batch(none, b);
    for (int p = 0; p < b.n; ++p) {
      const std::size_t m = start + static_cast<std::size_t>(p);
      const Vec3 f(b.fx[p], b.fy[p], b.fz[p]);
      EXPECT_EQ(Vec3(b.t1x[p], b.t1y[p], b.t1z[p]), Vec3::Zero()) << "pair " << m;
      EXPECT_EQ(Vec3(b.t2x[p], b.t2y[p], b.t2z[p]), Vec3::Zero()) << "pair " << m;
      PairForces r;
      if (!scalar.evaluate(ds[m], r)) {
        EXPECT_EQ(b.energy[p], 0.0) << "pair " << m << " (beyond the cutoff)";
        EXPECT_EQ(f, Vec3::Zero()) << "pair " << m << " (beyond the cutoff)";
        continue;
      }
      const double diff = std::max(std::abs(b.energy[p] - r.energy), (f - r.f1).norm());
      worst = std::max(worst, diff / std::max(std::abs(r.energy) + r.f1.norm(), 1e-4));
    }
  }
  return worst;
}

TEST(NpNpSimd, EveryInstructionSetEqualsTheScalarLaw) {
  NpNpCoverage cov;
  const std::vector<Vec3> ds = np_np_displacements(20000, 3, cov);
  EXPECT_GT(cov.coincident, 100);
  EXPECT_GT(cov.linear, 100);
  EXPECT_GT(cov.power, 100);
  EXPECT_GT(cov.taper, 100);
  EXPECT_GT(cov.beyond, 100);
  for (std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    const double worst = np_np_worst(ds);
    EXPECT_LT(worst, kRoundOff) << hwy::TargetName(target);
    std::printf("NP-NP on %s: largest relative difference %.3g\n", hwy::TargetName(target), worst);
  }
  hwy::SetSupportedTargetsForTest(0);
}

// NPs among tubes through the driver, over the NP–NP sub-list: the batched forces are the scalar
// law's to round-off on 1 and 2 threads, the same bits on a second evaluation, and sum to zero.
TEST(NpNpSimd, FilmForcesEqualTheScalarLaw) {
  Elements el = film_with_nps(13);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-20.0, 20.0), z(-2.0, 2.0);
  for (int k = 0; k < 450; ++k) el.add(nanoparticle(Vec3(u(rng), u(rng), z(rng))));  // crowded
  const NpNpContact batched;
  const NpNpContact scalar(NpNpParams{}, NpNpEvaluation::Scalar);
  for (const Domain& domain :
       {Domain{}, Domain(Vec3(-20, -20, -50), Vec3(20, 20, 50), {true, true, false})})
    for (int threads : {1, 2}) {
      const Forces ref = evaluate(scalar, el, threads, domain, true);
      const Forces got = evaluate(batched, el, threads, domain, true);
      EXPECT_NE(ref.energy, 0.0);
      EXPECT_LT(relative_difference(ref, got), kRoundOff) << threads << " threads";
      EXPECT_NEAR(got.energy, ref.energy, kRoundOff * std::abs(ref.energy));
      const Forces again = evaluate(batched, el, threads, domain, true);
      EXPECT_EQ(again.energy, got.energy);
      Vec3 f_sum = Vec3::Zero();
      double scale = 0;
      for (std::size_t i = 0; i < el.size(); ++i) {
        ASSERT_EQ(again.f[i], got.f[i]) << "element " << i;
        EXPECT_EQ(got.t[i], Vec3::Zero());
        if (el.kind[i] != ElementKind::Nanoparticle) {
          EXPECT_EQ(got.f[i], Vec3::Zero());
        }
        f_sum += got.f[i];
        scale = std::max(scale, got.f[i].norm());
      }
      EXPECT_GT(scale, 0.0);
      EXPECT_LT(f_sum.norm(), 1e-12 * scale * el.size());
    }
}

// Everything a force evaluation leaves: forces, torques, damping forces and torques, energy.
struct Evaluation {
  std::vector<Vec3> f, t, fd, td;
  double energy = 0;
  bool operator==(const Evaluation&) const = default;
};

template <class Compute>
Evaluation evaluate_all(std::size_t n, int threads, Compute compute) {
  ForceSink sink;
  sink.resize(n, threads, true);
  compute(sink);
  Evaluation e{std::vector<Vec3>(n), std::vector<Vec3>(n), std::vector<Vec3>(n),
               std::vector<Vec3>(n)};
  e.energy = sink.reduce(e.f, e.t, e.fd, e.td).total_stored();
  return e;
}

NpDashpotKernel scalar_of(const NpDashpotKernel& k) {
  return NpDashpotKernel(k.name(), k.owner(), k.kinds(), k.params(), DashpotEvaluation::Scalar);
}

// The NP–CNT and NP–NP dashpots, batched against scalar, on the film with random velocities.
TEST(NpDashpotSimd, FilmDampingForcesEqualTheScalarLaw) {
  const Elements el = film_with_nps(9);
  for (bool shear : {false, true})
    for (const NpDashpotKernel& k :
         {np_cnt_dashpot(0.03, {}, 100.0, shear), np_np_dashpot(0.03, {}, 100.0, shear)}) {
      const NpContactDamping batched(k);
      const NpContactDamping scalar(scalar_of(k));
      const NeighborList nl = list_of(batched, el);
      ASSERT_GT(nl.pair_count(), 0u) << k.name();
      for (int threads : {1, 2}) {
        const auto run = [&](const NpContactDamping& m) {
          return evaluate_all(el.size(), threads, [&](ForceSink& s) { m.compute(el, &nl, s); });
        };
        const Evaluation ref = run(scalar), got = run(batched);
        double scale = 0, diff = 0, power = 0;
        Vec3 f_sum = Vec3::Zero();
        for (std::size_t i = 0; i < el.size(); ++i) {
          scale = std::max(scale, ref.fd[i].norm());
          diff = std::max(diff, (got.fd[i] - ref.fd[i]).norm());
          f_sum += got.fd[i];
          power += got.fd[i].dot(el.v[i]);
          ASSERT_EQ(got.td[i], Vec3::Zero());  // a central (or centre-velocity) force: no torque
          ASSERT_EQ(got.f[i], Vec3::Zero());   // dissipative: the damping slots only
        }
        EXPECT_GT(scale, 0.0) << k.name();
        EXPECT_LT(diff, kRoundOff * scale) << k.name() << ", shear " << shear << ", " << threads;
        EXPECT_LT(power, 0.0);  // a dashpot only dissipates
        EXPECT_LT(f_sum.norm(), 1e-12 * scale * el.size());
        EXPECT_TRUE(run(batched) == got);  // the same bits on a second evaluation
      }
    }
}

// One pass over a contact's list for the contact and its dashpot (made by `dashpot(shear)`) gives,
// bit for bit, the two passes one after the other, on 1 and 2 threads, with and without shear;
// `other` (another contact's dashpot) and a scalar dashpot are not fused with the contact.
template <class Contact, class MakeDashpot>
void expect_one_pass_equals_two(const Elements& el, const Contact& contact,
                                MakeDashpot make_dashpot, const NpDashpotKernel& other) {
  for (bool shear : {false, true}) {
    const NpContactDamping dashpot(make_dashpot(shear));
    ASSERT_EQ(contact.cutoff(), dashpot.cutoff());
    const NeighborList nl = list_of(contact, el);
    for (int threads : {1, 2}) {
      const Evaluation apart = evaluate_all(el.size(), threads, [&](ForceSink& s) {
        contact.compute(el, &nl, s);
        dashpot.compute(el, &nl, s);
      });
      bool fused = false;
      const Evaluation one = evaluate_all(el.size(), threads, [&](ForceSink& s) {
        fused = dashpot.compute_with(contact, el, &nl, s);
      });
      ASSERT_TRUE(fused) << threads << " threads";
      EXPECT_NE(apart.energy, 0.0);
      double damping = 0;
      for (const Vec3& f : apart.fd) damping = std::max(damping, f.norm());
      EXPECT_GT(damping, 0.0);
      EXPECT_TRUE(one == apart) << threads << " threads, shear " << shear;
    }
  }
  const NpContactDamping another(other);
  const NpContactDamping scalar(scalar_of(make_dashpot(false)));
  const NeighborList nl = list_of(contact, el);
  ForceSink sink;
  sink.resize(el.size(), 1, true);
  EXPECT_FALSE(another.compute_with(contact, el, &nl, sink));
  EXPECT_FALSE(scalar.compute_with(contact, el, &nl, sink));
}

TEST(NpDashpotFused, OnePassWithTheNpCntContactEqualsTwoPasses) {
  expect_one_pass_equals_two(
      film_with_nps(11), NpCntContact{},
      [](bool shear) { return np_cnt_dashpot(0.03, {}, 100.0, shear); }, np_np_dashpot());
}

// The same for the NP–NP contact and its dashpot, on NPs crowded enough for a team (from
// kParallelMinItems listed pairs, as the passes apart).
TEST(NpDashpotFused, OnePassWithTheNpNpContactEqualsTwoPasses) {
  Elements el = film_with_nps(23);
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> u(-20.0, 20.0), z(-2.0, 2.0);
  for (int k = 0; k < 450; ++k) el.add(nanoparticle(Vec3(u(rng), u(rng), z(rng))));
  for (std::size_t i = 0; i < el.size(); ++i) el.v[i] = 2.0 * random_unit(rng);
  const NpNpContact contact;
  ASSERT_GE(static_cast<long>(list_of(contact, el).pair_count()), kParallelMinItems);
  expect_one_pass_equals_two(
      el, contact, [](bool shear) { return np_np_dashpot(0.03, {}, 100.0, shear); },
      np_cnt_dashpot());
}

// A list of at least kParallelMinItems pairs is shared by the team, however few more: the NP–NP
// pairs of the tensile film with 4000 NPs (4088 listed) ran on one thread below twice that. On 2
// threads the second thread's buffers hold forces, and the sums are the 1-thread ones to
// round-off (momentum conserved).
TEST(NpNpContact, AListFromKParallelMinItemsPairsIsSharedByTheTeam) {
  Elements el = film_with_nps(23);
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(-20.0, 20.0), z(-2.0, 2.0);
  const NpNpContact contact;
  while (static_cast<long>(list_of(contact, el).pair_count()) < kParallelMinItems)
    for (int k = 0; k < 5; ++k) el.add(nanoparticle(Vec3(u(rng), u(rng), z(rng))));
  const NeighborList nl = list_of(contact, el);
  const long pairs = static_cast<long>(nl.pair_count());
  ASSERT_GE(pairs, kParallelMinItems);
  ASSERT_LT(pairs, 2 * kParallelMinItems);
  ForceSink two;
  two.resize(el.size(), 2, false);
  contact.compute(el, &nl, two);
  std::size_t second = 0;  // elements the second thread wrote
  for (std::size_t i = 0; i < el.size(); ++i) second += two.force(1)[i] != Vec3::Zero();
  EXPECT_GT(second, el.size() / 100) << pairs << " pairs";
  const Evaluation both =
      evaluate_all(el.size(), 2, [&](ForceSink& s) { contact.compute(el, &nl, s); });
  const Evaluation one =
      evaluate_all(el.size(), 1, [&](ForceSink& s) { contact.compute(el, &nl, s); });
  double scale = 0, diff = 0;
  Vec3 f_sum = Vec3::Zero();
  for (std::size_t i = 0; i < el.size(); ++i) {
    scale = std::max(scale, one.f[i].norm());
    diff = std::max(diff, (both.f[i] - one.f[i]).norm());
    f_sum += both.f[i];
  }
  EXPECT_GT(scale, 0.0);
  EXPECT_LT(diff, kRoundOff * scale);
  EXPECT_LT(f_sum.norm(), 1e-12 * scale * el.size());
  EXPECT_NEAR(both.energy, one.energy, kRoundOff * std::abs(one.energy));
}

// A system pairs the NP–CNT dashpot with its contact, whichever was added first; its forces are
// bit for bit those of the two passes apart.
TEST(NpDashpotFused, SystemForcesEqualTwoPassesInEitherOrder) {
  const Elements el = film_with_nps(5);
  Evaluation got[2];
  for (int order : {0, 1}) {
    IntegratorSettings s;
    s.threads = 2;
    System sys(el, s);
    if (order == 0) sys.add(std::make_unique<NpCntContact>());
    sys.add(std::make_unique<NpContactDamping>(np_cnt_dashpot()));
    if (order == 1) sys.add(std::make_unique<NpCntContact>());
    sys.initialize();
    const Elements& E = sys.elements();
    const auto* contact = sys.find<NpCntContact>();
    const auto* dashpot = sys.find<NpContactDamping>();
    const NeighborList* nl = sys.neighbors(*contact);
    ASSERT_EQ(nl, sys.neighbors(*dashpot));
    got[order] = {E.f, E.t, sys.damping_forces(), std::vector<Vec3>(E.size(), Vec3::Zero()),
                  sys.energy().potential.total_stored()};
    const Evaluation apart = evaluate_all(E.size(), 2, [&](ForceSink& k) {
      contact->compute(E, nl, k);
      dashpot->compute(E, nl, k);
    });
    EXPECT_NE(apart.energy, 0.0);
    EXPECT_TRUE(got[order] == apart) << "order " << order;
  }
  EXPECT_TRUE(got[0] == got[1]);
}

}  // namespace

// Elements::axis (the NP–CNT law's segment axis) is written out in scalars; it must stay Eigen's
// q * UnitX bit for bit (so the NP–CNT forces did not change; to round-off in a build with fused
// multiply-adds), on unit, nearly unit and signed-zero quaternions. Independent check: a unit
// quaternion's rotation matrix's first column, to round-off.
TEST(ElementsAxis, IsEigensRotationOfUnitX) {
  std::mt19937_64 rng(29);
  std::normal_distribution<double> g;
  Elements el;
  std::vector<Quat> qs = {Quat::Identity(), Quat(0, 1, 0, 0),          Quat(0, 0, 1, 0),
                          Quat(0, 0, 0, 1), Quat(-0.0, -0.0, 1, -0.0), Quat(-1, 0, 0, 0)};
  for (int k = 0; k < 4000; ++k) {
    Quat q(g(rng), g(rng), g(rng), g(rng));
    q.normalize();
    if (k % 2 == 1) q.coeffs() *= 1 + 1e-9 * g(rng);  // a little off the unit sphere, as q drifts
    qs.push_back(q);
  }
  for (const Quat& q : qs) {
    ElementInit e;
    e.q = q;
    e.mass = 1;
    e.inertia = Vec3::Ones();
    e.radius = 1;
    el.add(e);
  }
  for (std::size_t i = 0; i < qs.size(); ++i) {
    el.q[i] = qs[i];  // (add() normalises)
    const Vec3 eigen = qs[i] * Vec3::UnitX();
    const Vec3 a = el.axis(i);
#ifndef __FMA__
    EXPECT_EQ(a, eigen) << "quaternion " << i;
#else  // (a native build may contract the two forms into fused multiply-adds differently)
    EXPECT_LT((a - eigen).norm(), 1e-15 * qs[i].squaredNorm()) << "quaternion " << i;
#endif
    if (std::abs(qs[i].norm() - 1) < 1e-15) {
      EXPECT_LT((a - qs[i].toRotationMatrix().col(0)).norm(), 1e-14) << "quaternion " << i;
    }
  }
}
