// Neighbour list (cell list + Verlet skin) against an O(N²) brute-force reference, and the
// random-film / seven-tube-bundle generators.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "hwy/targets.h"
#include "mdem/core/cnt.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/io/state_io.h"
#include "mdem/neighbor/neighbor_list.h"
#include "mdem/scene/film_builder.h"
#include "mdem/scene/tube_builder.h"

using namespace mdem;

namespace {

constexpr double kCutoff = 5.424;  // 4T, the vdW cutoff
constexpr double kSkin = 0.5;
using Pair = std::pair<std::uint32_t, std::uint32_t>;

// Restores the OpenMP thread count a test changed.
struct ThreadGuard {
  int saved = omp_get_max_threads();
  ~ThreadGuard() { omp_set_num_threads(saved); }
};

Elements cloud(const std::vector<Vec3>& xs) {
  Elements el;
  for (std::size_t i = 0; i < xs.size(); ++i)
    el.add(cnt_segment(xs[i], Quat::Identity(), static_cast<int>(i), 0));
  return el;
}

// The vdW model's default exclusion: one tube, fewer than 20 indices apart.
bool same_tube_close(const Elements& el, std::size_t i, std::size_t j) {
  return el.tube[i] >= 0 && el.tube[i] == el.tube[j] && std::abs(el.index[i] - el.index[j]) < 20;
}

std::vector<Pair> brute_force(const Elements& el, double range,
                              const NeighborList::Exclusion& ex = {}) {
  std::vector<Pair> out;
  const double r2 = range * range;
  for (std::size_t i = 0; i < el.size(); ++i)
    for (std::size_t j = i + 1; j < el.size(); ++j)
      if ((el.x[j] - el.x[i]).squaredNorm() < r2 && !(ex && ex(el, i, j)))
        out.emplace_back(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
  return out;
}

// The list's pairs as (lower index, higher index), sorted, checking the CSR layout on the way:
// offsets start at 0, are monotone, end at pair_count(); each i's neighbours are strictly
// ascending, > i when of i's kind or in a list of all kinds, and a pair of two kinds in a list of
// some kinds is in the row of the kind with fewer elements in el (ties: the lower kind),
// whatever the indices.
std::vector<Pair> listed(const NeighborList& nl, const Elements& el) {
  const std::size_t n = el.size();
  const auto& off = nl.offsets();
  const auto& nb = nl.neighbors();
  EXPECT_EQ(off.size(), n + 1);
  if (off.size() != n + 1) return {};
  EXPECT_EQ(off[0], 0u);
  EXPECT_EQ(off[n], nb.size());
  EXPECT_EQ(nl.pair_count(), nb.size());
  std::size_t count[kElementKinds] = {};
  for (const ElementKind k : el.kind) ++count[static_cast<int>(k)];
  std::vector<Pair> out;
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_LE(off[i], off[i + 1]);
    for (std::uint32_t m = off[i]; m < off[i + 1]; ++m) {
      const std::uint32_t j = nb[m];
      const int a = static_cast<int>(el.kind[i]), b = static_cast<int>(el.kind[j]);
      if (a == b || nl.kinds().is_all()) {
        EXPECT_GT(j, i) << "neighbour of " << i;
      } else {
        EXPECT_NE(j, i);
        EXPECT_TRUE(count[a] != count[b] ? count[a] < count[b] : a < b)
            << "pair (" << i << ", " << j << ") of kinds " << a << ", " << b
            << " in the row of the kind with more elements";
      }
      if (m > off[i]) {
        EXPECT_LT(nb[m - 1], j) << "neighbours of " << i << " not ascending";
      }
      out.emplace_back(static_cast<std::uint32_t>(std::min<std::size_t>(i, j)),
                       static_cast<std::uint32_t>(std::max<std::size_t>(i, j)));
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

void expect_matches_brute_force(const Elements& el, const NeighborList::Exclusion& ex = {},
                                double cutoff = kCutoff, double skin = kSkin) {
  NeighborList nl(cutoff, skin);
  if (ex) nl.set_exclusion(ex);
  nl.build(el);
  const std::vector<Pair> got = listed(nl, el);
  const std::vector<Pair> want = brute_force(el, cutoff + skin, ex);
  ASSERT_EQ(got.size(), want.size());
  EXPECT_TRUE(got == want);
  // Report the first difference, if any, for diagnosis.
  for (std::size_t k = 0; k < got.size(); ++k)
    if (got[k] != want[k]) {
      ADD_FAILURE() << "first difference at " << k << ": got (" << got[k].first << ", "
                    << got[k].second << "), want (" << want[k].first << ", " << want[k].second
                    << ")";
      break;
    }
}

std::vector<Vec3> uniform_box(std::size_t n, const Vec3& lo, const Vec3& hi, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::vector<Vec3> xs(n);
  for (auto& x : xs)
    for (int d = 0; d < 3; ++d) x[d] = lo[d] + (hi[d] - lo[d]) * unit_interval(rng());
  return xs;
}

Elements small_film(unsigned seed, int tubes = 40, int segments = 30, double side = 60) {
  Elements el;
  FilmSpec s;
  s.side = side;
  s.tubes = tubes;
  s.segments_per_tube = segments;
  s.seed = seed;
  add_random_film(el, s);
  return el;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Neighbour list: pair sets against brute force.

TEST(NeighborList, UniformCloudMatchesBruteForce) {
  expect_matches_brute_force(cloud(uniform_box(3000, Vec3(-20, -20, -20), Vec3(20, 20, 20), 1)));
}

TEST(NeighborList, DenseUniformCloudMatchesBruteForce) {
  // Many pairs per element, several cells per dimension.
  expect_matches_brute_force(cloud(uniform_box(2000, Vec3(0, 0, 0), Vec3(15, 15, 15), 2)));
}

TEST(NeighborList, ClusteredCloudWithFarOutliersMatchesBruteForce) {
  // Tight Gaussian clusters plus a few elements 1e5 nm away: the cell grid is capped instead of
  // spanning the whole box at cutoff resolution.
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0.0, 1.5);
  std::vector<Vec3> xs;
  const std::vector<Vec3> centres = uniform_box(12, Vec3(-30, -30, -30), Vec3(30, 30, 30), 4);
  for (const Vec3& c : centres)
    for (int k = 0; k < 150; ++k) xs.push_back(c + Vec3(g(rng), g(rng), g(rng)));
  xs.push_back(Vec3(1e5, 0, 0));
  xs.push_back(Vec3(1e5 + 1.0, 0, 0));  // a pair far out
  xs.push_back(Vec3(-1e5, 2e5, -3e5));
  xs.push_back(Vec3(0, -1e5, 1e5));
  std::shuffle(xs.begin(), xs.end(), rng);
  expect_matches_brute_force(cloud(xs));
}

TEST(NeighborList, ExtremeCoordinatesMatchBruteForce) {
  // Finite positions whose bounding box overflows (extent 2e308 = inf), next to an ordinary
  // cluster: the grid degenerates along x but the list stays exact.
  std::vector<Vec3> xs = uniform_box(400, Vec3(0, 0, 0), Vec3(20, 20, 20), 16);
  xs.push_back(Vec3(1e308, 0, 0));
  xs.push_back(Vec3(-1e308, 0, 0));
  xs.push_back(Vec3(0, 1e300, 0));
  xs.push_back(Vec3(0, 1e300, 1.0));
  expect_matches_brute_force(cloud(xs));
}

TEST(NeighborList, CollinearCloudsMatchBruteForce) {
  std::mt19937_64 rng(5);
  std::vector<Vec3> along_x, diagonal;
  for (int k = 0; k < 1500; ++k) {
    along_x.push_back(Vec3(300.0 * unit_interval(rng()), 0, 0));
    diagonal.push_back(Vec3::Constant(200.0 * unit_interval(rng())) + Vec3(1, 2, 3));
  }
  expect_matches_brute_force(cloud(along_x));
  expect_matches_brute_force(cloud(diagonal));
}

TEST(NeighborList, PlanarCloudMatchesBruteForce) {
  std::vector<Vec3> xs = uniform_box(2500, Vec3(-50, -50, 0), Vec3(50, 50, 0), 6);
  expect_matches_brute_force(cloud(xs));
  // The same plane tilted out of the coordinate planes.
  const Quat tilt(Eigen::AngleAxisd(0.7, Vec3(1, 2, 0.5).normalized()));
  for (Vec3& x : xs) x = tilt * x;
  expect_matches_brute_force(cloud(xs));
}

TEST(NeighborList, LatticeAtExactlyTheRangeListsOnlyCloserPairs) {
  // A cubic lattice spaced exactly cutoff + skin: nearest neighbours sit on the boundary of the
  // (strict) range and are not listed; spaced slightly closer they are, and diagonals are not.
  const double range = kCutoff + kSkin;
  for (double spacing : {range, range * (1 - 1e-9), 0.75 * range}) {
    std::vector<Vec3> xs;
    for (int a = 0; a < 8; ++a)
      for (int b = 0; b < 8; ++b)
        for (int c = 0; c < 8; ++c) xs.push_back(spacing * Vec3(a, b, c));
    SCOPED_TRACE(spacing);
    expect_matches_brute_force(cloud(xs));
  }
}

TEST(NeighborList, SingleElementAndEmptySystem) {
  NeighborList nl(kCutoff, kSkin);
  Elements one = cloud({Vec3(1, 2, 3)});
  nl.build(one);
  EXPECT_EQ(nl.offsets(), (std::vector<std::uint32_t>{0, 0}));
  EXPECT_EQ(nl.pair_count(), 0u);
  EXPECT_FALSE(nl.needs_rebuild(one));

  Elements none;
  nl.build(none);
  EXPECT_EQ(nl.offsets(), (std::vector<std::uint32_t>{0}));
  EXPECT_EQ(nl.pair_count(), 0u);
  EXPECT_FALSE(nl.needs_rebuild(none));
  EXPECT_EQ(nl.builds(), 2u);
}

TEST(NeighborList, CoincidentElementsArePaired) {
  NeighborList nl(kCutoff, kSkin);
  Elements two = cloud({Vec3(4, 5, 6), Vec3(4, 5, 6)});
  nl.build(two);
  EXPECT_EQ(nl.offsets(), (std::vector<std::uint32_t>{0, 1, 1}));
  EXPECT_EQ(nl.neighbors(), (std::vector<std::uint32_t>{1}));
}

TEST(NeighborList, FilmMatchesBruteForceWithAndWithoutExclusion) {
  const Elements el = small_film(7);
  ASSERT_EQ(el.size(), 40u * 30u);
  expect_matches_brute_force(el);
  expect_matches_brute_force(el, same_tube_close);
}

// The build's candidate test on every instruction set it is compiled for (AVX-512, AVX2, SSE4,
// plain C++): the same pairs as the brute force, on a film, a uniform cloud and a lattice whose
// spacing is the range (differences of lattice positions land on either side of it by rounding, so
// this exercises the strict comparison on both sides).
TEST(NeighborList, EveryInstructionSetListsTheBruteForcePairs) {
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  EXPECT_GE(targets.size(), 2u);  // at least a vector set and the plain C++ fallback
  const Elements film = small_film(5);
  const Elements uniform = cloud(uniform_box(3000, Vec3(0, 0, 0), Vec3(40, 40, 40), 11));
  const double range = kCutoff + kSkin;
  std::vector<Vec3> lattice;
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b)
      for (int c = 0; c < 6; ++c) lattice.push_back(range * Vec3(a, b, c));
  const Elements grid = cloud(lattice);
  for (std::int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    SCOPED_TRACE(hwy::TargetName(target));
    ASSERT_STREQ(neighbor_scan_target(), hwy::TargetName(target));
    expect_matches_brute_force(film, same_tube_close);
    expect_matches_brute_force(uniform);
    expect_matches_brute_force(grid);
  }
  hwy::SetSupportedTargetsForTest(0);
}

// A list of some kind pairs bins each kind in a layer of its own and scans only the partner
// kinds' layers: the same pairs as the brute force filtered by kind, for one-sided sets (NP-CNT),
// one kind (NP-NP), mixed sets, all kinds, with an exclusion, open and periodic, on 1 and 2
// threads and every instruction set.
TEST(NeighborList, KindSubListsListTheBruteForcePairsOfTheirKinds) {
  ThreadGuard guard;
  const ElementKind C = ElementKind::CntSegment, N = ElementKind::Nanoparticle,
                    G = ElementKind::Grain, W = ElementKind::Wall;
  Elements el = cloud(uniform_box(4000, Vec3(0, 0, 0), Vec3(30, 30, 30), 23));
  // Mostly segments, a few NPs, grains and walls, in no order of index.
  std::mt19937_64 rng(5);
  for (std::size_t i = 0; i < el.size(); ++i) {
    const double u = unit_interval(rng());
    el.kind[i] = u < 0.85 ? C : u < 0.92 ? N : u < 0.97 ? G : W;
  }
  const std::vector<KindPairs> sets = {KindPairs::of(N, C),           KindPairs::of(N, N),
                                       KindPairs::of(C, C).add(N, C), KindPairs::of(G, W).add(G, G),
                                       KindPairs::of(W, W),           KindPairs::all()};
  const Domain periodic({0, 0, 0}, {30, 30, 30}, {true, true, false});
  const NeighborList::Exclusion odd_sum = [](const Elements&, std::size_t i, std::size_t j) {
    return (i + j) % 2 == 1;
  };
  const double r2 = (kCutoff + kSkin) * (kCutoff + kSkin);
  for (const Domain& domain : {Domain{}, periodic})
    for (const KindPairs k : sets)
      for (const bool excluding : {false, true}) {
        std::vector<Pair> want;
        for (std::size_t i = 0; i < el.size(); ++i)
          for (std::size_t j = i + 1; j < el.size(); ++j)
            if (k.has(el.kind[i], el.kind[j]) &&
                domain.delta(el.x[i], el.x[j]).squaredNorm() < r2 &&
                !(excluding && odd_sum(el, i, j)))
              want.emplace_back(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
        EXPECT_FALSE(want.empty()) << k.describe();
        for (std::int64_t target : hwy::SupportedAndGeneratedTargets())
          for (int threads : {1, 2}) {
            hwy::SetSupportedTargetsForTest(target);
            omp_set_num_threads(threads);
            SCOPED_TRACE(std::string(hwy::TargetName(target)) + ", " + k.describe() + ", " +
                         std::to_string(threads) + " threads" +
                         (domain.any_periodic() ? ", periodic" : "") +
                         (excluding ? ", excluding odd sums" : ""));
            NeighborList nl(kCutoff, kSkin, domain);
            nl.set_kinds(k);
            if (excluding) nl.set_exclusion(odd_sum);
            nl.build(el);
            const std::vector<Pair> got = listed(nl, el);
            EXPECT_EQ(got.size(), want.size());
            EXPECT_TRUE(got == want);
          }
      }
  hwy::SetSupportedTargetsForTest(0);
}

TEST(NeighborList, ExclusionIsRespected) {
  // Straight tube: every pair within range is on one tube within 20 indices, so the vdW-style
  // exclusion empties the list; an "exclude odd i" rule keeps exactly the pairs with even i.
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 60, 0);
  NeighborList nl(kCutoff, kSkin);
  nl.build(el);
  EXPECT_GT(nl.pair_count(), 0u);
  nl.set_exclusion(same_tube_close);
  nl.build(el);
  EXPECT_EQ(nl.pair_count(), 0u);

  const NeighborList::Exclusion odd = [](const Elements&, std::size_t i, std::size_t j) {
    EXPECT_LT(i, j);  // the predicate is asked about (i, j) with i < j
    return i % 2 == 1;
  };
  expect_matches_brute_force(el, odd);
}

TEST(NeighborList, ExclusionThatThrowsMakesBuildThrow) {
  const Elements el = cloud(uniform_box(6000, Vec3(0, 0, 0), Vec3(60, 60, 60), 8));
  NeighborList nl(kCutoff, kSkin);
  nl.set_exclusion([](const Elements&, std::size_t i, std::size_t) -> bool {
    if (i == 4321) throw std::runtime_error("bad pair");
    return false;
  });
  EXPECT_THROW(nl.build(el), std::runtime_error);
  EXPECT_TRUE(nl.needs_rebuild(el));
  nl.set_exclusion([](const Elements&, std::size_t i, std::size_t) -> bool {
    if (i == 10) throw 42;  // not a std::exception
    return false;
  });
  EXPECT_THROW(nl.build(el), std::runtime_error);
}

TEST(NeighborList, SameResultForAnyThreadCount) {
  ThreadGuard guard;
  // Large enough (> 4096 elements) for the threaded path.
  const Elements el = small_film(9, 150, 60, 120);
  ASSERT_GT(el.size(), 8000u);
  std::vector<std::vector<std::uint32_t>> offsets, neighbors;
  // A list built anew at each team size, and one list rebuilt at each (its scratch, sized per
  // thread, reused by teams of other sizes).
  NeighborList reused(kCutoff, kSkin);
  reused.set_exclusion(same_tube_close);
  for (int threads : {1, 2, 3, 1}) {
    omp_set_num_threads(threads);
    NeighborList nl(kCutoff, kSkin);
    nl.set_exclusion(same_tube_close);
    nl.build(el);
    offsets.push_back(nl.offsets());
    neighbors.push_back(nl.neighbors());
    reused.build(el);
    offsets.push_back(reused.offsets());
    neighbors.push_back(reused.neighbors());
  }
  for (std::size_t k = 1; k < offsets.size(); ++k) {
    EXPECT_TRUE(offsets[k] == offsets[0]) << "run " << k;
    EXPECT_TRUE(neighbors[k] == neighbors[0]) << "run " << k;
  }
  omp_set_num_threads(2);
  NeighborList nl(kCutoff, kSkin);
  nl.set_exclusion(same_tube_close);
  nl.build(el);
  const std::vector<Pair> got = listed(nl, el);
  EXPECT_TRUE(got == brute_force(el, kCutoff + kSkin, same_tube_close));
}

TEST(NeighborList, RebuildReusesAndStaysCorrectAfterMoves) {
  ThreadGuard guard;
  omp_set_num_threads(2);
  Elements el = small_film(10, 120, 50, 100);
  NeighborList nl(kCutoff, kSkin);
  std::mt19937_64 rng(11);
  for (int round = 0; round < 4; ++round) {
    nl.build(el);
    EXPECT_TRUE(listed(nl, el) == brute_force(el, kCutoff + kSkin));
    for (Vec3& x : el.x)
      x += Vec3(unit_interval(rng()) - 0.5, unit_interval(rng()) - 0.5, unit_interval(rng()) - 0.5);
  }
  EXPECT_EQ(nl.builds(), 4u);
}

// ---------------------------------------------------------------------------------------------
// Neighbour list: when to rebuild.

TEST(NeighborList, NeedsRebuildFollowsHalfTheSkin) {
  Elements el = cloud(uniform_box(500, Vec3(0, 0, 0), Vec3(30, 30, 30), 12));
  NeighborList nl(kCutoff, kSkin);
  EXPECT_TRUE(nl.needs_rebuild(el)) << "never built";
  EXPECT_TRUE(std::isinf(nl.max_displacement(el)));
  nl.build(el);
  EXPECT_FALSE(nl.needs_rebuild(el));
  EXPECT_EQ(nl.max_displacement(el), 0.0);

  // Every element moves by less than skin/2 in a random direction: no rebuild, and every pair
  // now closer than the cutoff is still in the list (the Verlet-list guarantee).
  std::mt19937_64 rng(13);
  const Elements at_build = el;
  for (Vec3& x : el.x) {
    Vec3 d(unit_interval(rng()) - 0.5, unit_interval(rng()) - 0.5, unit_interval(rng()) - 0.5);
    x += 0.49 * kSkin / 2 * d.normalized() * (0.5 + unit_interval(rng()));
  }
  EXPECT_LT(nl.max_displacement(el), kSkin / 2);
  EXPECT_FALSE(nl.needs_rebuild(el));
  const std::vector<Pair> list = listed(nl, el);
  const std::set<Pair> in_list(list.begin(), list.end());
  for (const Pair& p : brute_force(el, kCutoff))
    EXPECT_TRUE(in_list.count(p)) << "pair (" << p.first << ", " << p.second << ") lost";

  // One element moves by more than skin/2.
  el.x[123] = at_build.x[123] + Vec3(0, 0.26, 0);
  EXPECT_NEAR(nl.max_displacement(el), 0.26, 1e-12);
  EXPECT_TRUE(nl.needs_rebuild(el));
  nl.build(el);
  EXPECT_FALSE(nl.needs_rebuild(el));

  // The element count changes.
  el.add(cnt_segment(Vec3(1, 1, 1), Quat::Identity(), -1, -1));
  EXPECT_TRUE(nl.needs_rebuild(el));

  // Non-finite positions always ask for a rebuild (which then reports the element).
  nl.build(el);
  el.x[7].y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(nl.needs_rebuild(el));
}

// A sub-list checks only the elements that can change it: none when no two elements can form
// one of its kind pairs, only its kinds' elements when they are few or many. The Verlet guarantee
// holds all the same (compared with a fresh build), and a list restored from a checkpoint decides
// as the one that was saved.
TEST(NeighborList, SubListsCheckOnlyTheElementsOfTheirKinds) {
  const ElementKind C = ElementKind::CntSegment, N = ElementKind::Nanoparticle;
  Elements el = cloud(uniform_box(3000, Vec3(0, 0, 0), Vec3(30, 30, 30), 31));
  auto pairs_of = [](const NeighborList& l, const Elements& e) { return listed(l, e); };
  auto fresh = [](KindPairs k, const Elements& e) {
    NeighborList l(kCutoff, kSkin);
    l.set_kinds(k);
    l.build(e);
    return l;
  };

  // NP-CNT without NPs: empty, and no motion of the segments asks for a rebuild.
  NeighborList np_cnt(kCutoff, kSkin);
  np_cnt.set_kinds(KindPairs::of(N, C));
  np_cnt.build(el);
  EXPECT_EQ(np_cnt.pair_count(), 0u);
  for (Vec3& x : el.x) x += Vec3(3, -2, 1);
  EXPECT_FALSE(np_cnt.needs_rebuild(el));
  EXPECT_LT(np_cnt.max_displacement(el), 4.0);  // the displacement itself is still measured
  EXPECT_GT(np_cnt.max_displacement(el), 3.0);
  // One NP added (the count changes): rebuilt, it lists pairs, and segments count again.
  el.add(cnt_segment(Vec3(15, 15, 15), Quat::Identity(), -1, -1));
  el.kind.back() = N;
  EXPECT_TRUE(np_cnt.needs_rebuild(el));
  np_cnt.build(el);
  EXPECT_GT(np_cnt.pair_count(), 0u);
  el.x[10].x() += 0.3;
  EXPECT_TRUE(np_cnt.needs_rebuild(el));
  np_cnt.build(el);

  // NP-NP with 40 NPs among 3000 segments: a segment's motion does not count, an NP's does.
  for (std::size_t i = 0; i < el.size(); i += 75) el.kind[i] = N;
  NeighborList np_np(kCutoff, kSkin);
  np_np.set_kinds(KindPairs::of(N, N));
  np_np.build(el);
  EXPECT_GT(np_np.pair_count(), 0u);
  el.x[1].x() += 5.0;  // a segment
  EXPECT_FALSE(np_np.needs_rebuild(el));
  EXPECT_TRUE(pairs_of(np_np, el) == pairs_of(fresh(KindPairs::of(N, N), el), el));
  el.x[150].y() += 0.26;  // an NP
  EXPECT_TRUE(np_np.needs_rebuild(el));
  // CNT-CNT among the same 40 NPs (most elements are segments): an NP's motion does not count,
  // a segment's does.
  el.x[150].y() -= 0.26;
  NeighborList cnt_cnt(kCutoff, kSkin);
  cnt_cnt.set_kinds(KindPairs::of(C, C));
  cnt_cnt.build(el);
  el.x[75].x() += 5.0;  // an NP
  EXPECT_FALSE(cnt_cnt.needs_rebuild(el));
  EXPECT_TRUE(pairs_of(cnt_cnt, el) == pairs_of(fresh(KindPairs::of(C, C), el), el));
  EXPECT_GT(cnt_cnt.max_displacement(el), 4.9);  // (every element's displacement, as measured)
  el.x[76].x() += 0.26;                          // a segment
  EXPECT_TRUE(cnt_cnt.needs_rebuild(el));
  el.x[76].x() -= 0.26;
  el.x[75].x() -= 5.0;
  el.x[225].z() = std::numeric_limits<double>::quiet_NaN();  // a NaN NP asks for a rebuild
  EXPECT_TRUE(np_np.needs_rebuild(el));
  el.x[225].z() = 1.0;

  // Restored from a checkpoint: the same decisions.
  np_np.build(el);
  StateWriter w;
  np_np.save_state(w);
  NeighborList restored(kCutoff, kSkin);
  restored.set_kinds(KindPairs::of(N, N));
  StateReader r(w.bytes());
  restored.load_state(r, el.size());
  el.x[2].x() += 5.0;  // a segment
  EXPECT_FALSE(np_np.needs_rebuild(el));
  EXPECT_FALSE(restored.needs_rebuild(el));
  el.x[300].x() += 0.3;  // an NP
  EXPECT_TRUE(np_np.needs_rebuild(el));
  EXPECT_TRUE(restored.needs_rebuild(el));
}

// A checkpoint's list may hold a neighbour below its row (a pair of two kinds is listed under the
// rarer kind's element, e.g. an NP after the segments): loaded. An entry naming its own row or an
// element beyond the system is refused before any pair loop could use it.
TEST(NeighborList, CheckpointEntriesMustBeOtherElementsOfTheSystem) {
  const auto saved = [](std::vector<std::uint32_t> offsets, std::vector<std::uint32_t> nb) {
    StateWriter w;
    w.begin("neighbor_list");
    w.put(kCutoff);
    w.put(kSkin);
    w.put(std::uint64_t{1});
    w.put(std::vector<Vec3>(3, Vec3::Zero()));
    w.put(offsets);
    w.put(nb);
    return w.take();
  };
  const auto load = [](const std::string& bytes) {
    NeighborList nl(kCutoff, kSkin);
    StateReader r(bytes);
    nl.load_state(r, 3);
    return nl;
  };
  const NeighborList below = load(saved({0, 0, 0, 2}, {0, 1}));  // row 2 lists 0 and 1
  EXPECT_EQ(below.neighbors(), (std::vector<std::uint32_t>{0, 1}));
  EXPECT_EQ(below.offsets(), (std::vector<std::uint32_t>{0, 0, 0, 2}));
  for (const auto& [offsets, nb] :
       std::vector<std::pair<std::vector<std::uint32_t>, std::vector<std::uint32_t>>>{
           {{0, 1, 1, 1}, {0}},               // element 0 paired with itself
           {{0, 0, 1, 1}, {3}},               // an element past the last
           {{0, 0, 0, 1}, {0xffffffffu}}}) {  // far past it
    try {
      load(saved(offsets, nb));
      ADD_FAILURE() << "entry " << nb[0] << " was loaded";
    } catch (const CheckpointError& e) {
      EXPECT_NE(std::string(e.what()).find("not another element of the 3"), std::string::npos)
          << e.what();
    }
  }
}

TEST(NeighborList, NeedsRebuildInTheThreadedPath) {
  ThreadGuard guard;
  omp_set_num_threads(2);
  Elements el = small_film(14, 150, 60, 120);
  NeighborList nl(kCutoff, kSkin);
  nl.build(el);
  for (Vec3& x : el.x) x += Vec3(0.2, -0.1, 0.05);
  EXPECT_FALSE(nl.needs_rebuild(el));
  el.x[el.size() - 1].x() += 0.3;
  EXPECT_TRUE(nl.needs_rebuild(el));
  el.x[el.size() - 1].x() = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(nl.needs_rebuild(el));
}

TEST(NeighborList, NonFinitePositionThrowsNamingTheElement) {
  for (double bad :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
        -std::numeric_limits<double>::infinity()}) {
    Elements el = small_film(15, 10, 10, 30);
    NeighborList nl(kCutoff, kSkin);
    el.x[37].z() = bad;
    try {
      nl.build(el);
      ADD_FAILURE() << "no exception for " << bad;
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("element 37"), std::string::npos) << what;
      EXPECT_NE(what.find("non-finite"), std::string::npos) << what;
    }
    EXPECT_TRUE(nl.needs_rebuild(el));
  }
}

// The threaded bounding box names the first non-finite element, whichever thread meets it.
TEST(NeighborList, NonFinitePositionInTheThreadedPathNamesTheFirstElement) {
  ThreadGuard guard;
  omp_set_num_threads(2);
  Elements el = small_film(9, 150, 60, 120);
  ASSERT_GT(el.size(), 8000u);
  el.x[7000].x() = std::numeric_limits<double>::quiet_NaN();
  el.x[3001].y() = std::numeric_limits<double>::infinity();
  NeighborList nl(kCutoff, kSkin);
  try {
    nl.build(el);
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("element 3001 "), std::string::npos) << e.what();
  }
}

TEST(NeighborList, RejectsBadParameters) {
  EXPECT_THROW(NeighborList(0.0, 0.5), std::invalid_argument);
  EXPECT_THROW(NeighborList(-1.0, 0.5), std::invalid_argument);
  EXPECT_THROW(NeighborList(5.0, -0.1), std::invalid_argument);
  EXPECT_THROW(NeighborList(std::numeric_limits<double>::quiet_NaN(), 0.5), std::invalid_argument);
  EXPECT_NO_THROW(NeighborList(5.0, 0.0));
}

TEST(NeighborList, LargeFilmBuildsQuickly) {
  // The benchmark film (50 000 segments): reports the build time; the bound is loose so it holds
  // in unoptimised builds too (the optimised single-thread build takes tens of milliseconds).
  Elements el;
  FilmSpec s;
  s.side = 320;
  s.tubes = 500;
  s.segments_per_tube = 100;
  s.seed = 1;
  add_random_film(el, s);
  NeighborList nl(kCutoff, kSkin);
  nl.set_exclusion(same_tube_close);
  nl.build(el);  // warm-up: buffers reach their size
  const auto t0 = std::chrono::steady_clock::now();
  const int reps = 5;
  for (int k = 0; k < reps; ++k) nl.build(el);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() /
      reps;
  std::printf("[ info     ] 50 000-segment film: %zu pairs, %.2f ms per build (%d threads)\n",
              nl.pair_count(), ms, omp_get_max_threads());
  EXPECT_LT(ms, 2000.0);
}

// ---------------------------------------------------------------------------------------------
// Film and bundle generators.

TEST(FilmBuilder, SameSeedSameFilmOtherSeedOtherFilm) {
  const Elements a = small_film(42), b = small_film(42), c = small_film(43);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.x[i], b.x[i]) << i;
    EXPECT_EQ(a.q[i].coeffs(), b.q[i].coeffs()) << i;
  }
  ASSERT_EQ(a.size(), c.size());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < a.size(); ++i) differing += a.x[i] != c.x[i];
  EXPECT_EQ(differing, a.size());
}

TEST(FilmBuilder, GeometryFollowsTheSpec) {
  FilmSpec s;
  s.side = 200;
  s.thickness = 11;
  s.tubes = 120;
  s.segments_per_tube = 37;
  s.seed = 2024;
  Elements el;
  // One tube already present (unbonded): the film's ids continue after it.
  for (int k = 0; k < 3; ++k)
    el.add(cnt_segment(Vec3(k * cnt::kSegmentLength, 0, 50), Quat::Identity(), 4, k));
  const TubeIndices tubes = add_random_film(el, s);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());

  ASSERT_EQ(tubes.size(), 120u);
  EXPECT_EQ(el.size(), 3u + 120u * 37u);
  EXPECT_EQ(bonds->bonds().size(), 120u * 36u);
  const double sin_max = std::sin(2.0 * std::numbers::pi / 180.0);
  double max_z = 0, sum_abs_x = 0, sum_abs_y = 0;
  for (std::size_t t = 0; t < tubes.size(); ++t) {
    const auto& ids = tubes[t];
    ASSERT_EQ(ids.size(), 37u);
    Vec3 centre = Vec3::Zero();
    const Vec3 axis = el.axis(ids[0]);
    for (std::size_t k = 0; k < ids.size(); ++k) {
      const std::size_t i = ids[k];
      EXPECT_EQ(el.tube[i], static_cast<int>(5 + t));
      EXPECT_EQ(el.index[i], static_cast<int>(k));
      EXPECT_EQ(el.kind[i], ElementKind::CntSegment);
      const Vec3 b = el.axis(i);
      EXPECT_NEAR((b - axis).norm(), 0.0, 1e-12) << "straight tube";
      EXPECT_LE(std::abs(b.z()), sin_max + 1e-12) << "tube " << t;
      max_z = std::max(max_z, std::abs(b.z()));
      if (k > 0) {
        const Vec3 step = el.x[i] - el.x[ids[k - 1]];
        EXPECT_NEAR(step.norm(), cnt::kSegmentLength, 1e-9);
        EXPECT_NEAR(step.normalized().dot(b), 1.0, 1e-12);
      }
      centre += el.x[i];
    }
    centre /= static_cast<double>(ids.size());
    EXPECT_LE(std::abs(centre.x()), 100.0 + 1e-9);
    EXPECT_LE(std::abs(centre.y()), 100.0 + 1e-9);
    EXPECT_LE(std::abs(centre.z()), 5.5 + 1e-9);
    sum_abs_x += std::abs(axis.x());
    sum_abs_y += std::abs(axis.y());
  }
  // The tilt is used (not all flat) and the in-plane direction is spread (mean |cos φ| = 2/π).
  EXPECT_GT(max_z, 0.5 * sin_max);
  EXPECT_NEAR(sum_abs_x / 120, 2 / std::numbers::pi, 0.1);
  EXPECT_NEAR(sum_abs_y / 120, 2 / std::numbers::pi, 0.1);
}

TEST(FilmBuilder, FlatFilmAndBadSpecs) {
  FilmSpec s;
  s.side = 50;
  s.tubes = 10;
  s.segments_per_tube = 5;
  s.max_out_of_plane_deg = 0;
  s.thickness = 0;
  s.seed = 1;
  Elements el;
  add_random_film(el, s);
  for (std::size_t i = 0; i < el.size(); ++i) {
    EXPECT_EQ(el.x[i].z(), 0.0);
    EXPECT_NEAR(el.axis(i).z(), 0.0, 1e-15);
  }
  FilmSpec bad = s;
  bad.side = 0;
  EXPECT_THROW(add_random_film(el, bad), std::invalid_argument);
  bad = s;
  bad.tubes = 0;
  EXPECT_THROW(add_random_film(el, bad), std::invalid_argument);
  bad = s;
  bad.segments_per_tube = 0;
  EXPECT_THROW(add_random_film(el, bad), std::invalid_argument);
  bad = s;
  bad.max_out_of_plane_deg = -1;
  EXPECT_THROW(add_random_film(el, bad), std::invalid_argument);
}

TEST(FilmBuilder, SevenTubeBundleIsATriangularLattice) {
  Elements el;
  const TubeIndices tubes = add_seven_tube_bundle(el, 12, 1.7);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  ASSERT_EQ(tubes.size(), 7u);
  EXPECT_EQ(el.size(), 7u * 12u);
  EXPECT_EQ(bonds->bonds().size(), 7u * 11u);
  for (std::size_t t = 0; t < 7; ++t) {
    ASSERT_EQ(tubes[t].size(), 12u);
    for (std::size_t i : tubes[t]) {
      EXPECT_EQ(el.tube[i], static_cast<int>(t));
      EXPECT_NEAR((el.axis(i) - Vec3::UnitX()).norm(), 0.0, 1e-12);
    }
  }
  // Centred on the origin along x.
  EXPECT_NEAR(el.x[tubes[0].front()].x(), -el.x[tubes[0].back()].x(), 1e-12);
  EXPECT_NEAR(el.x[tubes[0].front()].y(), 0.0, 1e-15);
  // Cross-section: centre to each outer tube and each outer tube to the next are 1.7 nm apart.
  auto yz = [&](std::size_t t) { return Vec3(0, el.x[tubes[t][0]].y(), el.x[tubes[t][0]].z()); };
  for (std::size_t t = 1; t < 7; ++t) {
    EXPECT_NEAR((yz(t) - yz(0)).norm(), 1.7, 1e-12);
    const std::size_t next = t == 6 ? 1 : t + 1;
    EXPECT_NEAR((yz(t) - yz(next)).norm(), 1.7, 1e-12);
  }
  EXPECT_THROW(add_seven_tube_bundle(el, 0, 1.7), std::invalid_argument);
  EXPECT_THROW(add_seven_tube_bundle(el, 5, 0.0), std::invalid_argument);
}
