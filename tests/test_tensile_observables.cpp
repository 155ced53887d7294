// The tensile job's observables (tensile.md §3.4–3.6, validation plan §5) on hand-built data whose
// answers are worked out by hand or by construction: aligned pairs, stabilisation time, pore
// raster, modulus, yield, toughness, failure strain, cycle analysis, necking, fragments and tubes
// in tension; and bad input refused with a message naming what is wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/core/cnt.h"
#include "mdem/core/elements.h"
#include "mdem/core/units.h"
#include "mdem/integrate/system.h"
#include "mdem/job/tensile_job.h"
#include "mdem/neighbor/neighbor_list.h"
#include "mdem/observe/aligned_pairs.h"
#include "mdem/observe/cycle_analysis.h"
#include "mdem/observe/fragments.h"
#include "mdem/observe/percentile.h"
#include "mdem/observe/pore_raster.h"
#include "mdem/observe/stress_strain.h"
#include "mdem/observe/tube_tension.h"
#include "mdem/observe/width_profile.h"
#include "mdem/scene/nanoparticle.h"
#include "mdem/scene/tube_builder.h"

using namespace mdem;

namespace {

constexpr double kT = cnt::kSegmentLength;  // 1.356 nm
constexpr double kPi = std::numbers::pi;

// Segments of tube `tube` with indices first_index, first_index + 1, ..., centres start + k·T·dir.
void add_tube(Elements& el, const Vec3& start, const Vec3& dir, int n, int tube,
              int first_index = 0) {
  const Vec3 d = dir.normalized();
  for (int k = 0; k < n; ++k)
    el.add(cnt_segment(start + k * kT * d, quat_from_axis(d), tube, first_index + k));
}

// Expects `f` to throw std::invalid_argument whose message contains `part`.
template <class F>
void expect_invalid(F f, const std::string& part) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected one mentioning \"" << part << "\"";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

std::vector<double> grid(int n, double step, double start = 0) {
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) v[i] = start + i * step;
  return v;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Percentile rule (one helper for every observable).

TEST(Percentile, LinearInterpolationBetweenOrderStatistics) {
  const std::vector<double> v{7, 1, 3, 5};  // sorted 1 3 5 7
  EXPECT_DOUBLE_EQ(percentile(v, 0), 1);
  EXPECT_DOUBLE_EQ(percentile(v, 100), 7);
  EXPECT_DOUBLE_EQ(percentile(v, 50), 4);     // h = 1.5: 3 + 0.5·2
  EXPECT_DOUBLE_EQ(percentile(v, 10), 1.6);   // h = 0.3: 1 + 0.3·2
  EXPECT_DOUBLE_EQ(percentile(v, 99), 6.94);  // h = 2.97: 5 + 0.97·2
  expect_invalid([] { percentile(std::vector<double>{}, 50, "widths"); }, "widths is empty");
  expect_invalid([&] { percentile(v, 101); }, "[0, 100]");
  expect_invalid([] { percentile(std::vector<double>{1, NAN}, 50); }, "values[1]");
}

// ---------------------------------------------------------------------------------------------
// Aligned pairs (§3.4).

TEST(AlignedPairs, ParallelTubesInRegisterCountOnePairPerSegment) {
  const int n = 30;
  Elements el;
  add_tube(el, Vec3(0, 0, 0), Vec3::UnitX(), n, 0);
  add_tube(el, Vec3(0, 1.71, 0), Vec3::UnitX(), n, 1);
  // Each segment's partner is 1.71 nm away (counted); the next ones sit at √(1.71² + T²) =
  // 2.18 nm with axial offset T > T/2 (neither count takes them).
  const AlignedPairCounts c = count_aligned_pairs(el);
  EXPECT_EQ(c.thesis, n);
  EXPECT_EQ(c.registry_free, n);

  // Axes pointing opposite ways are still parallel (γ is the acute angle).
  Elements anti;
  add_tube(anti, Vec3(0, 0, 0), Vec3::UnitX(), n, 0);
  add_tube(anti, Vec3((n - 1) * kT, 1.71, 0), -Vec3::UnitX(), n, 1);
  const AlignedPairCounts a = count_aligned_pairs(anti);
  EXPECT_EQ(a.thesis, n);
  EXPECT_EQ(a.registry_free, n);
}

TEST(AlignedPairs, StaggeredTubesLoseTheThesisCountOnly) {
  const int n = 30;
  // Staggered by T/2: R = √(1.71² + 0.678²) = 1.8395 nm > 1.8, so the thesis count is 0.
  Elements half;
  add_tube(half, Vec3(0, 0, 0), Vec3::UnitX(), n, 0);
  add_tube(half, Vec3(0.5 * kT, 1.71, 0), Vec3::UnitX(), n, 1);
  EXPECT_EQ(count_aligned_pairs(half).thesis, 0);
  // At exactly T/2 both neighbours sit on the registry-free bound |R·b| ≤ T/2, where rounding
  // decides; staggered by 0.45 T the answer is sharp: R = 1.8156 nm (thesis 0), and each segment
  // of tube 0 has one partner at axial offset 0.45 T ≤ T/2 (the other is at 0.55 T): n pairs.
  Elements el;
  add_tube(el, Vec3(0, 0, 0), Vec3::UnitX(), n, 0);
  add_tube(el, Vec3(0.45 * kT, 1.71, 0), Vec3::UnitX(), n, 1);
  const AlignedPairCounts c = count_aligned_pairs(el);
  EXPECT_EQ(c.thesis, 0);
  EXPECT_EQ(c.registry_free, n);
}

TEST(AlignedPairs, CrossingTubesAt30DegreesCountNothing) {
  Elements el;
  const int n = 50;
  add_tube(el, Vec3(-0.5 * (n - 1) * kT, 0, 0), Vec3::UnitX(), n, 0);
  const Vec3 d(std::cos(kPi / 6), std::sin(kPi / 6), 0);
  add_tube(el, Vec3(0, 0, 1.71) - 0.5 * (n - 1) * kT * d, d, n, 1);
  const AlignedPairCounts c = count_aligned_pairs(el);
  EXPECT_EQ(c.thesis, 0);
  EXPECT_EQ(c.registry_free, 0);
}

TEST(AlignedPairs, SegmentsOfOneTubeCountOnlyBeyondTheExclusion) {
  // One straight tube: neighbours are T = 1.356 nm apart and parallel, so without the exclusion
  // the thesis count takes all n − 1 of them; with the default exclusion (20) none.
  Elements line;
  add_tube(line, Vec3::Zero(), Vec3::UnitX(), 30, 0);
  EXPECT_EQ(count_aligned_pairs(line).thesis, 0);
  AlignedPairCriteria none;
  none.exclusion = 0;
  EXPECT_EQ(count_aligned_pairs(line, none).thesis, 29);

  // A hairpin-like tube 0: indices 0–9 along x, and beside them at 1.71 nm indices 30–39 (30
  // apart: counted) — and, in a second scene, indices 10–19 (10 apart: excluded).
  Elements far;
  add_tube(far, Vec3::Zero(), Vec3::UnitX(), 10, 0, 0);
  add_tube(far, Vec3(0, 1.71, 0), Vec3::UnitX(), 10, 0, 30);
  EXPECT_EQ(count_aligned_pairs(far).thesis, 10);
  EXPECT_EQ(count_aligned_pairs(far).registry_free, 10);
  Elements near;
  add_tube(near, Vec3::Zero(), Vec3::UnitX(), 10, 0, 0);
  add_tube(near, Vec3(0, 1.71, 0), Vec3::UnitX(), 10, 0, 10);
  EXPECT_EQ(count_aligned_pairs(near).thesis, 0);
  EXPECT_EQ(count_aligned_pairs(near).registry_free, 0);
}

namespace {

// 1500 segments (40 tubes of 40 indices) in a 12 nm cube with axes near x, so many pairs are
// aligned.
Elements dense_cloud() {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 12), tilt(-0.25, 0.25);
  Elements el;
  for (int i = 0; i < 1500; ++i) {
    const Vec3 d = Vec3(1, tilt(rng), tilt(rng)).normalized();
    el.add(cnt_segment(Vec3(u(rng), u(rng), u(rng)), quat_from_axis(d), i % 40, i / 40));
  }
  return el;
}

// The definition (10°, 1.8 nm, T/2, exclusion 20) applied to every pair of CNT segments.
AlignedPairCounts every_pair(const Elements& el) {
  const double cos10 = std::cos(10 * kPi / 180);
  AlignedPairCounts n;
  for (std::size_t i = 0; i < el.size(); ++i)
    for (std::size_t j = i + 1; j < el.size(); ++j) {
      if (el.kind[i] != ElementKind::CntSegment || el.kind[j] != ElementKind::CntSegment) continue;
      if (el.tube[i] == el.tube[j] && std::abs(el.index[i] - el.index[j]) < 20) continue;
      const Vec3 bi = el.axis(i);
      if (std::abs(bi.dot(el.axis(j))) <= cos10) continue;
      const Vec3 r = el.x[j] - el.x[i];
      n.thesis += r.norm() < 1.8;
      n.registry_free += std::abs(r.dot(bi)) <= 0.5 * kT && (r - r.dot(bi) * bi).norm() < 1.8;
    }
  return n;
}

// A CNT–CNT Verlet list as the vdW model keeps one (cutoff 4T, skin 0.5 nm), with the given
// intra-tube exclusion.
NeighborList vdw_like_list(const Elements& el, int exclusion, double cutoff = 4 * kT) {
  NeighborList list(cutoff, 0.5);
  list.set_kinds(KindPairs::of(ElementKind::CntSegment, ElementKind::CntSegment));
  list.set_exclusion([exclusion](const Elements& e, std::size_t i, std::size_t j) {
    return e.cnt_pair_excluded(i, j, exclusion);
  });
  list.build(el);
  return list;
}

}  // namespace

TEST(AlignedPairs, CellSearchMissesNoPairOfADenseRandomCloud) {
  // Against the definition applied to every pair.
  const Elements el = dense_cloud();
  const AlignedPairCounts all = every_pair(el);
  ASSERT_GT(all.thesis, 100);
  ASSERT_GT(all.registry_free, 100);
  const AlignedPairCounts c = count_aligned_pairs(el);
  EXPECT_EQ(c.thesis, all.thesis);
  EXPECT_EQ(c.registry_free, all.registry_free);
}

TEST(AlignedPairs, KeptListGivesTheDefinitionsCountsOrDeclines) {
  // The counts over a list the caller keeps (the tensile job's frames: the vdW list) are the
  // definition's, also after the elements moved within half the skin, with NPs among the
  // segments, and when the list's own exclusion is narrower than the criteria's.
  Elements el = dense_cloud();
  el.add(nanoparticle(Vec3(6, 6, 6)));
  const AlignedPairCounts all = every_pair(el);
  ASSERT_GT(all.thesis, 100);
  for (int exclusion : {20, 0}) {
    const NeighborList list = vdw_like_list(el, exclusion);
    Elements moved = el;
    for (std::size_t i = 0; i < moved.size(); i += 2) moved.x[i] += Vec3(0.12, -0.1, 0.05);
    for (const Elements* e : {&el, &moved}) {
      const std::optional<AlignedPairCounts> c = count_aligned_pairs(*e, list);
      ASSERT_TRUE(c.has_value()) << "exclusion " << exclusion;
      const AlignedPairCounts want = every_pair(*e);
      EXPECT_EQ(c->thesis, want.thesis) << "exclusion " << exclusion;
      EXPECT_EQ(c->registry_free, want.registry_free) << "exclusion " << exclusion;
    }
  }
  // Declines: an element moved beyond half the skin, a list over other elements, a cutoff
  // shorter than the counts' reach √(1.8² + (T/2)²) = 1.92 nm.
  const NeighborList list = vdw_like_list(el, 20);
  Elements far = el;
  far.x[3] += Vec3(0.3, 0, 0);
  EXPECT_FALSE(count_aligned_pairs(far, list).has_value());
  Elements fewer = dense_cloud();
  EXPECT_FALSE(count_aligned_pairs(fewer, list).has_value());
  EXPECT_FALSE(count_aligned_pairs(el, vdw_like_list(el, 20, 1.9)).has_value());
  EXPECT_TRUE(count_aligned_pairs(el, vdw_like_list(el, 20, 1.93)).has_value());
  AlignedPairCriteria bad;
  bad.max_distance = std::nan("");
  expect_invalid([&] { (void)count_aligned_pairs(el, list, bad); }, "max_distance");
}

TEST(AlignedPairs, StabilisationTime) {
  // By hand: N_end = 40, growth 40, 5 % = 2: the first sample with 40 − N ≤ 2 is N = 38 at t = 4.
  const std::vector<double> t{0, 1, 2, 3, 4, 5, 6}, n{0, 10, 20, 30, 38, 39, 40};
  EXPECT_DOUBLE_EQ(stabilisation_time(t, n), 4);
  // An overshoot above N_end qualifies (N_end − N < 0 ≤ 5 %).
  EXPECT_DOUBLE_EQ(stabilisation_time(t, std::vector<double>{0, 10, 20, 45, 38, 35, 40}), 3);
  // N = 100(1 − e^{−t/τ}) to 4.5 ns: t* = −τ ln(e^{−4.5/τ} + 0.05(1 − e^{−4.5/τ})); the answer
  // is the first sample at or after t*.
  const double tau = 0.9, dt = 0.01;
  std::vector<double> ts, ns;
  for (int k = 0; k <= 450; ++k) {
    ts.push_back(k * dt);
    ns.push_back(100 * (1 - std::exp(-ts.back() / tau)));
  }
  const double e = std::exp(-4.5 / tau);
  const double t_star = -tau * std::log(e + 0.05 * (1 - e));
  const double ts_found = stabilisation_time(ts, ns);
  EXPECT_GE(ts_found, t_star);
  EXPECT_LT(ts_found, t_star + dt);
  expect_invalid([] { stabilisation_time(std::vector<double>{}, std::vector<double>{}); },
                 "t is empty");
  expect_invalid(
      [] {
        stabilisation_time(std::vector<double>{0, 0}, std::vector<double>{1, 2});
      },
      "must increase");
}

// ---------------------------------------------------------------------------------------------
// Pore raster (§3.4).

namespace {

// Four tubes along the lines x = 0, x = S, y = 0, y = S (each running 5 nm past the corners), S =
// 20 + 2 r_d: the void they enclose is the open square (r_d, S − r_d)², 20 × 20 nm.
ProjectedFrame square_frame(double S) {
  Elements el;
  const int n = static_cast<int>(std::ceil((S + 10) / kT)) + 1;
  add_tube(el, Vec3(0, -5, 0), Vec3::UnitY(), n, 0);
  add_tube(el, Vec3(S, -5, 0), Vec3::UnitY(), n, 1);
  add_tube(el, Vec3(-5, 0, 0), Vec3::UnitX(), n, 2);
  add_tube(el, Vec3(-5, S, 0), Vec3::UnitX(), n, 3);
  return projected_frame(el);
}

// Pixel centres lo + (k + ½)p, k = 0 .. n−1, inside the open interval (a, b).
long centres_inside(double lo, double p, int n, double a, double b) {
  long c = 0;
  for (int k = 0; k < n; ++k) {
    const double x = lo + (k + 0.5) * p;
    c += x > a && x < b;
  }
  return c;
}

}  // namespace

TEST(PoreRaster, SquareFrameEnclosesOnePoreOfTheSquaresArea) {
  const double rd = cnt::kRadius, p = 0.5, S = 20 + 2 * rd, side = 20;
  const ProjectedFrame frame = square_frame(S);
  for (double shift : {0.0, 0.13, 0.29, 0.41}) {
    const Window2D w{-10 + shift, S + 10, -10 + shift, S + 10};
    const Raster r = rasterize(frame, w);
    const PoreStats st = pore_stats(r);
    ASSERT_EQ(st.areas.size(), 1u) << "shift " << shift;
    // The pore is the pixels whose centres lie in the open square (r_d, S − r_d)²: counted here
    // from the pixel grid alone...
    const long nx = centres_inside(w.x_lo, p, r.nx, rd, S - rd);
    const long ny = centres_inside(w.y_lo, p, r.ny, rd, S - rd);
    EXPECT_DOUBLE_EQ(st.areas[0], nx * ny * p * p) << "shift " << shift;
    // ... and within the discretisation bound: an open interval of length ℓ holds ℓ/p ± 1 pixel
    // centres, so |A − ℓ²| ≤ 2ℓp + p².
    EXPECT_LE(std::abs(st.areas[0] - side * side), 2 * side * p + p * p);
    EXPECT_EQ(st.large, 1);  // 400 nm² > 200 nm²
    EXPECT_EQ(st.histogram[5], 1);
    EXPECT_DOUBLE_EQ(st.weighted_mean_area, st.areas[0]);
    EXPECT_EQ(st.edge_discarded, 1);  // the void outside the frame
    EXPECT_GT(st.void_fraction * r.nx * r.ny, st.areas[0] / (p * p));
  }
}

TEST(PoreRaster, PoreTouchingTheWindowEdgeIsDiscarded) {
  const double S = 20 + 2 * cnt::kRadius;
  // The window starts at x = 5, inside the frame: the enclosed void reaches its left edge.
  const Raster r = rasterize(square_frame(S), Window2D{5, S + 10, -10, S + 10});
  const PoreStats st = pore_stats(r);
  EXPECT_TRUE(st.areas.empty());
  EXPECT_EQ(st.large, 0);
  EXPECT_GE(st.edge_discarded, 1);
}

TEST(PoreRaster, VoidPixelsTouchingOnlyAtACornerAreTwoPores) {
  // 8 × 8 pixels of material with two 2 × 2 void blocks meeting at one corner: (2..3, 2..3) and
  // (4..5, 4..5). Material connects diagonally, void does not: two pores of 4 pixels.
  Raster r;
  r.window = Window2D{0, 4, 0, 4};
  r.pixel = 0.5;
  r.nx = r.ny = 8;
  r.material.assign(64, 1);
  for (int iy = 2; iy < 4; ++iy)
    for (int ix = 2; ix < 4; ++ix) {
      r.material[iy * 8 + ix] = 0;
      r.material[(iy + 2) * 8 + ix + 2] = 0;
    }
  PoreStats st = pore_stats(r);
  ASSERT_EQ(st.areas.size(), 2u);
  EXPECT_DOUBLE_EQ(st.areas[0], 1.0);
  EXPECT_DOUBLE_EQ(st.areas[1], 1.0);
  EXPECT_EQ(st.histogram[0], 2);  // [0.25, 10)
  EXPECT_DOUBLE_EQ(st.void_fraction, 8.0 / 64);
  // Joined along an edge (pixel (4, 3) opened), they are one pore of 9 pixels.
  r.material[3 * 8 + 4] = 0;
  st = pore_stats(r);
  ASSERT_EQ(st.areas.size(), 1u);
  EXPECT_DOUBLE_EQ(st.areas[0], 9 * 0.25);
}

TEST(PoreRaster, NanoparticleDiscAndPercentileWindow) {
  // One NP of radius 3 nm: its material pixels lie between the discs of radius r ∓ p/√2.
  ProjectedFrame f;
  f.np_centre.push_back(Vec3(10.1, 9.87, 2));
  f.np_radius.push_back(3.0);
  const double p = 0.5, h = p / std::sqrt(2.0);
  const Raster r = rasterize(f, Window2D{0, 20, 0, 20});
  long material = 0;
  for (auto m : r.material) material += m;
  EXPECT_GE(material * p * p, kPi * (3 - h) * (3 - h));
  EXPECT_LE(material * p * p, kPi * (3 + h) * (3 + h));
  const PoreStats st = pore_stats(r);
  EXPECT_TRUE(st.areas.empty());
  EXPECT_DOUBLE_EQ(st.void_fraction, 1.0 - material / 1600.0);

  // Window of centres on the grid x = 0..100, y = 0..50 (step 1): by hand P2(x) = 2, P98(x) = 98,
  // P2(y) = 1, P98(y) = 49; shrunk by 5 % of the sides 96 and 48.
  std::vector<Vec3> c;
  for (int x = 0; x <= 100; ++x)
    for (int y = 0; y <= 50; ++y) c.emplace_back(x, y, 0);
  const Window2D w = percentile_window(c);
  EXPECT_NEAR(w.x_lo, 6.8, 1e-12);
  EXPECT_NEAR(w.x_hi, 93.2, 1e-12);
  EXPECT_NEAR(w.y_lo, 3.4, 1e-12);
  EXPECT_NEAR(w.y_hi, 46.6, 1e-12);

  expect_invalid([&] { rasterize(f, Window2D{0, 0.2, 0, 20}); }, "at least one pixel");
  f.np_centre[0].x() = NAN;
  expect_invalid([&] { rasterize(f, Window2D{0, 20, 0, 20}); }, "NP centre 0");
}

// ---------------------------------------------------------------------------------------------
// Stress–strain curve (§3.5).

TEST(StressStrain, ModulusOfALinearSeriesIsExact) {
  std::vector<double> e, s;
  for (int i = 0; i <= 300; ++i) {
    e.push_back(i / 10000.0);
    s.push_back(12.0 * e.back() + 0.3);
  }
  const LineFit f = modulus_fit(e, s);
  EXPECT_NEAR(f.slope, 12.0, 1e-9);
  EXPECT_NEAR(f.intercept, 0.3, 1e-12);
  EXPECT_EQ(f.samples, 101u);  // ε = 0.0100, 0.0101, ..., 0.0200
  expect_invalid([&] { modulus_fit(e, s, 0.05, 0.06); }, "0 frame(s) with strain in [0.05, 0.06]");
  expect_invalid([&] { modulus_fit(std::vector<double>{}, std::vector<double>{}); },
                 "strain is empty");
  s[7] = NAN;
  expect_invalid([&] { modulus_fit(e, s); }, "stress[7]");
  expect_invalid([&] { modulus_fit(e, std::vector<double>(3, 1.0)); }, "301 samples");
}

TEST(StressStrain, OffsetYieldOfABilinearCurveAtTheKink) {
  // σ = 10ε up to ε_k = 3 %, then slope 2. The 0.2 % offset line 10(ε − 0.002) meets the second
  // branch 0.3 + 2(ε − 0.03) at ε = 0.03 + 0.002·10/(10 − 2) = 0.0325; the 0.2 % moving average
  // there spans [0.0315, 0.0335], all on the straight second branch, so it changes nothing.
  std::vector<double> e, s;
  for (int i = 0; i <= 600; ++i) {
    e.push_back(i / 10000.0);
    s.push_back(e.back() <= 0.03 ? 10 * e.back() : 0.3 + 2 * (e.back() - 0.03));
  }
  const LineFit f = modulus_fit(e, s);
  EXPECT_NEAR(f.slope, 10, 1e-9);
  const std::optional<double> y = offset_yield_strain(e, s, f);
  ASSERT_TRUE(y.has_value());
  EXPECT_NEAR(*y, 0.0325, 1e-9);
  // The moving average at ε = 0 spans frames 0..10 (|Δε| ≤ 0.001): mean σ = 10·0.0005.
  EXPECT_NEAR(moving_average(e, s)[0], 0.005, 1e-12);
  // A curve that stays straight never yields.
  std::vector<double> straight(e.size());
  for (std::size_t i = 0; i < e.size(); ++i) straight[i] = 10 * e[i];
  EXPECT_FALSE(offset_yield_strain(e, straight, f).has_value());
  std::vector<double> back = e;
  std::swap(back[3], back[4]);
  expect_invalid([&] { moving_average(back, s); }, "must not decrease");
}

TEST(StressStrain, AlignedPairOnsetIsFiveSigmaAboveTheBaseline) {
  // Baseline (ε ≤ 1 %): ten frames, five of 100 and five of 102: mean 101, sample standard
  // deviation √(10/9) = 1.0541, threshold 101 + 5·1.0541 = 106.27. The first count above it is
  // 107, at ε = 0.0135 (106 before it is not).
  std::vector<double> e, n;
  for (int i = 0; i < 10; ++i) {
    e.push_back(0.0005 + i * 0.001);
    n.push_back(i % 2 ? 102 : 100);
  }
  for (double c : {103.0, 104.0, 106.0, 107.0, 110.0}) {
    e.push_back(0.0005 + e.size() * 0.001);
    n.push_back(c);
  }
  const std::optional<double> onset = count_onset_strain(e, n);
  ASSERT_TRUE(onset.has_value());
  EXPECT_DOUBLE_EQ(*onset, 0.0135);
  expect_invalid([&] { count_onset_strain(e, n, 0.0001); }, "the baseline needs at least 2");
}

TEST(StressStrain, ToughnessOfATriangleAndFailureAfterThePeak) {
  // Triangle: σ rises from 0 to 1 GPa at ε = 0.5 and falls back to 0 at ε = 1: area ½·1·1.
  std::vector<double> e = grid(101, 0.01), s;
  for (double x : e) s.push_back(x <= 0.5 ? 2 * x : 2 * (1 - x));
  EXPECT_NEAR(toughness(e, s), 0.5, 1e-12);

  // σ rises to 1.5 at ε = 0.2, dips to 0.5 at 0.3 (below half the later peak, but before it),
  // peaks at 2 at ε = 0.6 and then falls as 2 − 2(ε − 0.6): half the peak at ε = 1.1.
  e = grid(161, 0.01);
  s.clear();
  for (double x : e) {
    if (x <= 0.2)
      s.push_back(7.5 * x);
    else if (x <= 0.3)
      s.push_back(1.5 - 10 * (x - 0.2));
    else if (x <= 0.6)
      s.push_back(0.5 + 5 * (x - 0.3));
    else
      s.push_back(2 - 2 * (x - 0.6));
  }
  const std::optional<double> ef = failure_strain(e, s);
  ASSERT_TRUE(ef.has_value());
  EXPECT_NEAR(*ef, 1.1, 1e-9);
  // Never dropping to half the peak: no failure strain.
  EXPECT_FALSE(failure_strain(grid(10, 0.1), grid(10, 1.0, 1.0)).has_value());
  expect_invalid(
      [] {
        toughness(std::vector<double>{0, INFINITY}, std::vector<double>{0, 1});
      },
      "strain[1]");
}

// ---------------------------------------------------------------------------------------------
// Cycle analysis (§3.6).

namespace {

// Frames every dt ps of ε(t) = −a(1 − cos ωt) (tensile.md's waveform, a = ε_a/2) and σ = Eε + η
// dε/dt, until the first frame at or past `cycles` periods.
struct CycleFrames {
  std::vector<double> t, e, s;
};
CycleFrames cycle_frames(double period, double a, double E, double eta, int cycles, double dt) {
  const double w = 2 * kPi / period;
  CycleFrames f;
  for (int k = 0; f.t.empty() || f.t.back() < cycles * period; ++k) {
    const double t = k * dt;
    f.t.push_back(t);
    f.e.push_back(-a * (1 - std::cos(w * t)));
    f.s.push_back(E * f.e.back() + eta * (-a * w * std::sin(w * t)));
  }
  return f;
}

}  // namespace

TEST(CycleAnalysis, ElasticLoopHasNoAreaNoPhaseAndTheModulus) {
  const double P = 151.5, a = 0.005, E = 5.0;  // ε̇_avg = 1.32e-7/fs, ε_a = 1 %
  const CycleFrames f = cycle_frames(P, a, E, 0, 6, 1.0);
  CycleSettings cs;
  cs.period = P;
  const std::vector<CycleResult> r = analyse_cycles(f.t, f.e, f.s, cs);
  ASSERT_EQ(r.size(), 6u);
  for (const CycleResult& c : r) {
    EXPECT_NEAR(c.loop_area, 0, 1e-12) << "cycle " << c.cycle;
    EXPECT_NEAR(c.phase_lead, 0, 1e-9);
    EXPECT_NEAR(c.modulus, E, 1e-9);
    EXPECT_GT(c.modulus_samples, 10u);
    EXPECT_NEAR(c.peak_tension, 0, 1e-12);
    EXPECT_NEAR(c.peak_compression, -E * 2 * a, 1e-5);  // at t = P/2, between frames
  }
}

TEST(CycleAnalysis, ViscousLoopHasTheEllipseAreaAndPhaseLead) {
  // σ = Eε + η dε/dt with ωη/E = tan(2π·0.1): σ leads ε by 0.1 P. The loop is an ellipse of area
  // π σ0 ε0 sin φ = π a² ηω (a = strain amplitude), positive (dissipated).
  const double P = 250.9, a = 0.005, E = 5.0, w = 2 * kPi / P;
  const double eta = E * std::tan(2 * kPi * 0.1) / w;
  const CycleFrames f = cycle_frames(P, a, E, eta, 6, 1.0);
  CycleSettings cs;
  cs.period = P;
  const std::vector<CycleResult> r = analyse_cycles(f.t, f.e, f.s, cs);
  ASSERT_EQ(r.size(), 6u);
  const double area = kPi * a * a * eta * w;
  for (const CycleResult& c : r) {
    EXPECT_NEAR(c.loop_area / area, 1, 1e-3) << "cycle " << c.cycle;
    EXPECT_NEAR(c.loop_area_j_per_cm3, 1000 * c.loop_area, 1e-15);
    EXPECT_NEAR(c.phase_lead, 0.1, 1e-3);
  }
  // Stress lagging instead (η < 0) gives a negative area and phase.
  const CycleFrames g = cycle_frames(P, a, E, -eta, 2, 1.0);
  const std::vector<CycleResult> lag = analyse_cycles(g.t, g.e, g.s, cs);
  EXPECT_NEAR(lag[0].loop_area / area, -1, 1e-3);
  EXPECT_NEAR(lag[0].phase_lead, -0.1, 1e-3);
}

TEST(CycleAnalysis, RefusesBadInput) {
  const CycleFrames f = cycle_frames(151.5, 0.005, 5, 0, 2, 1.0);
  CycleSettings cs;
  expect_invalid([&] { analyse_cycles(f.t, f.e, f.s, cs); }, "the period is 0");
  cs.period = 1000;
  expect_invalid([&] { analyse_cycles(f.t, f.e, f.s, cs); }, "less than one period");
  cs.period = 151.5;
  const CycleFrames small = cycle_frames(151.5, 0.0005, 5, 0, 2, 1.0);  // ε never below −0.1 %
  expect_invalid([&] { analyse_cycles(small.t, small.e, small.s, cs); },
                 "cycle 0 has 0 frame(s) on its returning half");
  std::vector<double> s = f.s;
  s[40] = NAN;
  expect_invalid([&] { analyse_cycles(f.t, f.e, s, cs); }, "stress[40]");
  expect_invalid(
      [&] {
        analyse_cycles(std::vector<double>{}, std::vector<double>{}, std::vector<double>{}, cs);
      },
      "t is empty");
}

// ---------------------------------------------------------------------------------------------
// Necking (§3.5).

TEST(WidthProfile, NarrowedBandOfARectangleOfPoints) {
  // Points on the grid x = 0..199, y = −50..50 (step 1); for 100 ≤ x < 120 y is scaled by 0.9.
  // By hand: P1(y) = −49 and P99(y) = 49 of the 101 rows (also with each row repeated 20 times
  // in a bin), so w = 98, and 88.2 in the narrowed band; extents 100 and 90.
  std::vector<Vec3> pts, scaled_all;
  for (int x = 0; x < 200; ++x)
    for (int y = -50; y <= 50; ++y) {
      const double f = (x >= 100 && x < 120) ? 0.9 : 1.0;
      pts.emplace_back(x, f * y, 0);
      scaled_all.emplace_back(x, 0.9 * y, 0);
    }
  const Width mid = mid_width(pts, 110, 200 / 20.0);  // |x − 110| < L/20 = 10: x = 101..119
  EXPECT_NEAR(mid.width, 88.2, 1e-9);
  EXPECT_NEAR(mid.extent, 90, 1e-9);
  EXPECT_EQ(mid.elements, 19u * 101u);
  const Width outside = mid_width(pts, 50, 10);
  EXPECT_NEAR(outside.width, 98, 1e-9);
  EXPECT_NEAR(shrinkage(mid.width, outside.width), 0.1, 1e-12);
  // A uniform lateral scaling by 0.9 of the whole film: 10.0 % shrinkage.
  EXPECT_NEAR(shrinkage(mid_width(scaled_all, 100, 10).width, mid_width(pts, 50, 10).width), 0.1,
              1e-12);

  const WidthProfile prof = width_profile(pts, 0, 200);
  ASSERT_EQ(prof.bins.size(), 10u);
  for (std::size_t k = 0; k < 10; ++k)
    EXPECT_NEAR(prof.bins[k].width.width, k == 5 ? 88.2 : 98.0, 1e-9) << "bin " << k;
  EXPECT_EQ(prof.min_bin, 5u);
  EXPECT_NEAR(prof.min_width, 88.2, 1e-9);

  expect_invalid([&] { mid_width(pts, 1000, 10); }, "the mid slab must hold at least one");
  expect_invalid([&] { width_profile(pts, 10, 10); }, "x_lo < x_hi");
  expect_invalid([] { shrinkage(1, 0); }, "initial width w0");
}

// ---------------------------------------------------------------------------------------------
// Fragments (§3.5).

TEST(Fragments, ComponentsOfAKnownGraph) {
  // 200 elements: a chain 0..119, a ring 120..189, and ten singletons 190..199 (under 1 % = 2
  // elements each: ignored). Repeated edges and self-loops change nothing.
  std::vector<Edge> edges;
  for (std::uint32_t i = 0; i < 119; ++i) edges.emplace_back(i + 1, i);
  for (std::uint32_t i = 120; i < 190; ++i) edges.emplace_back(i, i == 189 ? 120 : i + 1);
  edges.emplace_back(5, 6);
  edges.emplace_back(195, 195);
  const Fragments f = count_fragments(200, edges);
  EXPECT_EQ(f.count, 2u);
  ASSERT_EQ(f.sizes.size(), 2u);
  EXPECT_EQ(f.sizes[0], 120u);
  EXPECT_EQ(f.sizes[1], 70u);
  EXPECT_EQ(f.ignored, 10u);
  EXPECT_EQ(f.ignored_elements, 10u);
  // One edge joining them: one fragment.
  edges.emplace_back(60, 150);
  EXPECT_EQ(count_fragments(200, edges).count, 1u);
  // Counting every component (min fraction 0): 1 + 10.
  EXPECT_EQ(count_fragments(200, edges, 0.0).count, 11u);
  edges.emplace_back(3, 200);
  expect_invalid([&] { count_fragments(200, edges); }, "outside 0..199");
}

TEST(Fragments, FilmLinksOnlyAttractingPairs) {
  // Two NPs 5.3 nm apart (gap 0.3 nm: inside the NP-NP cutoff of 8 nm, but on the repulsive
  // branch, U > 0, as V = 0 at 5.35 nm, tensile.md §1.2) are two fragments; 6.0 nm apart (U < 0)
  // one. A bonded 4-segment tube far from both is one more either way. Linking every pair within
  // the cutoff (the criterion before) makes the two NPs one fragment at both distances.
  for (const double r : {5.3, 6.0}) {
    Elements el;
    add_straight_tube(el, Vec3(0, 40, 0), Vec3::UnitX(), 4, 0);
    el.add(nanoparticle(Vec3(0, 0, 0)));
    el.add(nanoparticle(Vec3(r, 0, 0)));
    IntegratorSettings is;
    is.threads = 1;
    const auto sys = tensile_film_system(std::move(el), is, 0.0);
    sys->initialize();
    const double u = sys->energy().potential.stored[static_cast<int>(EnergyTerm::NpNp)];
    EXPECT_EQ(u > 0, r < 5.35) << "r = " << r << ": U = " << u;
    const Fragments f = count_film_fragments(*sys, 0.0);
    EXPECT_EQ(f.count, r < 5.35 ? 3u : 2u) << "r = " << r;
    // The cutoff criterion: bonds plus the NP pair (4, 5), closer than 8 nm.
    std::vector<Edge> within_cutoff = {{0, 1}, {1, 2}, {2, 3}, {4, 5}};
    EXPECT_EQ(count_fragments(6, within_cutoff, 0.0).count, 2u);
  }
  // Before initialization there are no energies to link by.
  Elements el;
  el.add(nanoparticle(Vec3(0, 0, 0)));
  IntegratorSettings is;
  is.threads = 1;
  const auto raw = tensile_film_system(std::move(el), is, 0.0);
  EXPECT_THROW(film_fragment_edges(*raw), std::logic_error);
}

// ---------------------------------------------------------------------------------------------
// Tubes in tension (§3.5).

TEST(TubeTension, PulledPushedAndGripOnlyPieces) {
  const double thr = units::nN(0.01);
  std::vector<BondAxialForce> pulled(9, BondAxialForce{0, 0, 0.5, false});
  EXPECT_DOUBLE_EQ(tube_tension(pulled).fraction_pieces, 1.0);
  EXPECT_DOUBLE_EQ(tube_tension(pulled).fraction_tension, 1.0);
  std::vector<BondAxialForce> pushed(9, BondAxialForce{0, 0, -0.5, false});
  EXPECT_DOUBLE_EQ(tube_tension(pushed).fraction_pieces, 0.0);
  EXPECT_DOUBLE_EQ(tube_tension(pushed).fraction_compression, 1.0);

  // Piece 0 (parent 0): 2 bonds at +1. Piece 1 (parent 0): 8 bonds at −0.5. Piece 2 (parent 1):
  // only grip bonds (left out). Piece 3 (parent 1): a grip bond at −10 (left out of its mean) and
  // one free bond at +thr/2 (in tension, but under the threshold).
  std::vector<BondAxialForce> b;
  for (int i = 0; i < 2; ++i) b.push_back({0, 0, 1.0, false});
  for (int i = 0; i < 8; ++i) b.push_back({1, 0, -0.5, false});
  for (int i = 0; i < 3; ++i) b.push_back({2, 1, -5.0, true});
  b.push_back({3, 1, -10.0, true});
  b.push_back({3, 1, 0.5 * thr, false});
  const TubeTension t = tube_tension(b);
  EXPECT_EQ(t.pieces, 3u);
  EXPECT_DOUBLE_EQ(t.fraction_pieces, 2.0 / 3);       // pieces 0 and 3
  EXPECT_DOUBLE_EQ(t.fraction_tension, 1.0 / 3);      // piece 0
  EXPECT_DOUBLE_EQ(t.fraction_compression, 1.0 / 3);  // piece 1
  // Parent 0 by length: (2·1 − 8·0.5)/10 < 0, although its two pieces' plain mean is +0.25.
  // Parent 1: +thr/2 > 0.
  EXPECT_EQ(t.parents, 2u);
  EXPECT_DOUBLE_EQ(t.fraction_parents, 0.5);

  b.push_back({0, 7, 1.0, false});
  expect_invalid([&] { tube_tension(b); }, "a piece has one parent");
  std::vector<BondAxialForce> grip_only(3, BondAxialForce{0, 0, 1.0, true});
  expect_invalid([&] { tube_tension(grip_only); }, "every bond lies inside a grip");
}
