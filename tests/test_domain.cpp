// The domain (box and periodic axes): minimum-image displacements, the periodic neighbour list
// against an O(N²) minimum-image reference, a vdW pair across the boundary against the same pair
// shifted next to each other, and energy conservation of two tubes drifting through a boundary.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "hwy/targets.h"
#include "mdem/core/cnt.h"
#include "mdem/core/domain.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/integrate/system.h"
#include "mdem/neighbor/neighbor_list.h"
#include "mdem/scene/tube_builder.h"

using namespace mdem;

namespace {

using Pair = std::pair<std::uint32_t, std::uint32_t>;

// Minimum image written independently of Domain::delta: the shortest of the 27 images.
Vec3 shortest_image(const Vec3& xi, const Vec3& xj, const Vec3& L, std::array<bool, 3> per) {
  Vec3 best = xj - xi;
  for (int a = -1; a <= 1; ++a)
    for (int b = -1; b <= 1; ++b)
      for (int c = -1; c <= 1; ++c) {
        const int k[3] = {a, b, c};
        Vec3 d = xj - xi;
        bool ok = true;
        for (int ax = 0; ax < 3; ++ax) {
          if (k[ax] != 0 && !per[ax]) ok = false;
          // Bring the raw difference within one box first, so three images suffice.
          if (per[ax]) d[ax] -= L[ax] * std::round(d[ax] / L[ax]);
          d[ax] += k[ax] * L[ax] * (per[ax] ? 1 : 0);
        }
        if (ok && d.squaredNorm() < best.squaredNorm()) best = d;
      }
  return best;
}

std::vector<Pair> listed(const NeighborList& nl, std::size_t n) {
  std::vector<Pair> out;
  const auto& off = nl.offsets();
  const auto& nb = nl.neighbors();
  EXPECT_EQ(off.size(), n + 1);
  for (std::size_t i = 0; i < n; ++i)
    for (std::uint32_t m = off[i]; m < off[i + 1]; ++m) {
      EXPECT_GT(nb[m], i);
      if (m > off[i]) {
        EXPECT_LT(nb[m - 1], nb[m]);
      }
      out.emplace_back(static_cast<std::uint32_t>(i), nb[m]);
    }
  return out;
}

Elements cloud(const std::vector<Vec3>& xs) {
  Elements el;
  for (std::size_t i = 0; i < xs.size(); ++i)
    el.add(cnt_segment(xs[i], Quat::Identity(), static_cast<int>(i), 0));
  return el;
}

}  // namespace

TEST(Domain, OpenDomainIsThePlainDifference) {
  const Domain d;
  const Vec3 a(1e6, -3.5, 0.25), b(-2e6, 7.0, 1.0);
  EXPECT_EQ(d.delta(a, b), b - a);  // bit for bit
  EXPECT_FALSE(d.any_periodic());
  EXPECT_TRUE(d.check_reach(1e9).empty());
}

TEST(Domain, MinimumImageAndWrap) {
  const Domain d(Vec3(0, -5, 0), Vec3(10, 5, 1), {true, true, false});
  // Across the x boundary: 9.5 → 0.5 is +1 nm, not −9 nm; z is open.
  const Vec3 r = d.delta(Vec3(9.5, 4.0, 0.0), Vec3(0.5, -4.5, 30.0));
  EXPECT_NEAR(r.x(), 1.0, 1e-12);
  EXPECT_NEAR(r.y(), 1.5, 1e-12);
  EXPECT_EQ(r.z(), 30.0);
  // Far images (positions many boxes away) reduce to the same displacement.
  const Vec3 far = d.delta(Vec3(9.5 + 70, 4.0 - 30, 0.0), Vec3(0.5 - 40, -4.5, 30.0));
  EXPECT_NEAR((far - r).norm(), 0.0, 1e-9);
  // Antisymmetric, and never longer than half a box along a periodic axis.
  std::mt19937_64 g(3);
  std::uniform_real_distribution<double> u(-100, 100);
  for (int k = 0; k < 1000; ++k) {
    const Vec3 a(u(g), u(g), u(g)), b(u(g), u(g), u(g));
    const Vec3 ab = d.delta(a, b), ba = d.delta(b, a);
    EXPECT_NEAR((ab + ba).norm(), 0.0, 1e-9);
    EXPECT_LE(std::abs(ab.x()), 5.0 + 1e-12);
    EXPECT_LE(std::abs(ab.y()), 5.0 + 1e-12);
    EXPECT_NEAR(ab.squaredNorm(),
                shortest_image(a, b, d.length(), {true, true, false}).squaredNorm(), 1e-8);
    const Vec3 w = d.wrap(a);
    EXPECT_GE(w.x(), 0.0);
    EXPECT_LT(w.x(), 10.0);
    EXPECT_GE(w.y(), -5.0);
    EXPECT_LT(w.y(), 5.0);
    EXPECT_EQ(w.z(), a.z());
    EXPECT_NEAR(d.delta(w, a).norm(), 0.0, 1e-9);  // the same point
  }
}

TEST(Domain, BadBoxesAreRefusedWithTheReason) {
  try {
    Domain(Vec3(0, 0, 0), Vec3(-1, 1, 1), {true, false, false});
    FAIL() << "hi < lo on a periodic axis was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("axis x"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Domain(Vec3(0, 0, 0), Vec3(1, INFINITY, 1), {false, true, false}),
               std::invalid_argument);
  // An open axis may have any corners.
  EXPECT_NO_THROW(Domain(Vec3(0, 0, 0), Vec3(-1, 1, 1), {false, true, true}));

  // A periodic axis shorter than 2·(cutoff + skin): the list and the system refuse it.
  const Domain small(Vec3::Zero(), Vec3(11, 50, 50), {true, true, false});
  EXPECT_FALSE(small.check_reach(5.924).empty());
  EXPECT_THROW(NeighborList(5.424, 0.5, small), std::invalid_argument);
  EXPECT_NO_THROW(NeighborList(5.424, 0.05, small));  // 2·5.474 ≤ 11

  Elements el;
  add_straight_tube(el, Vec3(1, 1, 1), Vec3::UnitY(), 3, 0);
  System sys(std::move(el));
  sys.add(std::make_unique<AnisotropicVdw>());
  sys.set_domain(small);
  try {
    sys.initialize();
    FAIL() << "a box shorter than twice the vdW reach was accepted";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("anisotropic_vdw"), std::string::npos) << m;
    EXPECT_NE(m.find("periodic axis x"), std::string::npos) << m;
    EXPECT_NE(m.find("11.848"), std::string::npos) << m;  // the minimum length
  }
}

// Periodic random clouds (positions also outside the box: nothing wraps them) against the O(N²)
// minimum-image list, for grids of 2, 3 and many cells along the periodic axes.
TEST(Domain, PeriodicNeighbourListEqualsBruteForceMinimumImage) {
  const double cutoff = 2.0, skin = 0.3, range = cutoff + skin;
  struct Case {
    Vec3 box;
    std::array<bool, 3> periodic;
    std::size_t n;
  };
  const std::vector<Case> cases = {
      {Vec3(2 * range, 2 * range + 0.1, 7 * range), {true, true, true}, 200},  // 2 cells, exact
      {Vec3(3.2 * range, 12, 30), {true, true, false}, 600},                   // 3 cells
      {Vec3(40, 25, 9), {true, false, true}, 1500},                            // many cells
      {Vec3(40, 40, 40), {false, false, false}, 2000},                         // open
  };
  // On every instruction set the build's candidate test is compiled for (the same pairs).
  for (std::int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    ASSERT_STREQ(neighbor_scan_target(), hwy::TargetName(target));
    for (const Case& c : cases) {
      const Vec3 lo(-3, 1, 2);
      const Domain d(lo, lo + c.box, c.periodic);
      std::mt19937_64 g(7 + c.n);
      std::uniform_real_distribution<double> u(-0.3, 1.3);  // 30 % beyond the box on each side
      std::vector<Vec3> xs(c.n);
      for (auto& x : xs)
        for (int a = 0; a < 3; ++a) x[a] = lo[a] + c.box[a] * u(g);
      const Elements el = cloud(xs);
      std::vector<Pair> want;
      for (std::size_t i = 0; i < c.n; ++i)
        for (std::size_t j = i + 1; j < c.n; ++j)
          if (shortest_image(xs[i], xs[j], c.box, c.periodic).squaredNorm() < range * range)
            want.emplace_back(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
      ASSERT_GT(want.size(), c.n / 10);
      NeighborList nl(cutoff, skin, d);
      nl.build(el);
      EXPECT_EQ(listed(nl, c.n), want)
          << "box " << c.box.transpose() << ", " << hwy::TargetName(target);
    }
  }
  hwy::SetSupportedTargetsForTest(0);
}

// Two crossed segments across the x boundary of a periodic box interact exactly as the same pair
// shifted next to each other in an open box.
TEST(Domain, VdwPairAcrossTheBoundaryEqualsTheShiftedPair) {
  const double L = 20;
  const Vec3 b1 = Vec3(0.3, 1, 0.2).normalized(), b2 = Vec3(1, -0.4, 0.5).normalized();
  auto system = [&](const Vec3& x1, const Vec3& x2, const Domain& d) {
    Elements el;
    el.add(cnt_segment(x1, quat_from_axis(b1), 0, 0));
    el.add(cnt_segment(x2, quat_from_axis(b2), 1, 0));
    IntegratorSettings s;
    s.dt = 0.001;  // the open pair has no contact to derive a step from
    System sys(std::move(el), s);
    sys.add(std::make_unique<AnisotropicVdw>());
    sys.set_domain(d);
    sys.initialize();
    return sys;
  };
  const Vec3 x1(0.4, 3.0, 1.0), x2(L - 1.8, 4.6, 0.2);  // 2.2 nm apart in x through the boundary
  System periodic = system(x1, x2, Domain(Vec3::Zero(), Vec3(L, L, L), {true, false, false}));
  System shifted = system(x1, x2 - Vec3(L, 0, 0), Domain());
  System open = system(x1, x2, Domain());
  const auto vdw = [](const System& s) {
    return s.energy().potential.stored[static_cast<int>(EnergyTerm::Vdw)];
  };
  ASSERT_GT(std::abs(vdw(shifted)), 0.05);  // a real contact
  EXPECT_EQ(vdw(open), 0.0);                // 18 nm apart without the box
  EXPECT_NEAR(vdw(periodic), vdw(shifted), 1e-12 * std::abs(vdw(shifted)));
  for (int i = 0; i < 2; ++i) {
    const double scale = shifted.elements().f[i].norm();
    EXPECT_NEAR((periodic.elements().f[i] - shifted.elements().f[i]).norm(), 0.0, 1e-12 * scale);
    EXPECT_NEAR((periodic.elements().t[i] - shifted.elements().t[i]).norm(), 0.0, 1e-12 * scale);
  }
  EXPECT_EQ(periodic.neighbors()->pair_count(), 1u);
  EXPECT_EQ(open.neighbors()->pair_count(), 0u);
}

// Two bonded tubes side by side across the periodic x boundary, drifting through it while they
// vibrate: undamped, the total energy stays put.
TEST(Domain, TubePairDriftingThroughAPeriodicBoundaryConservesEnergy) {
  const double L = 16;
  const int n = 12;
  Elements el;
  // Tubes along y at x = 0.6 and x = L − 1.2 (1.8 nm apart through the boundary).
  add_straight_tube(el, Vec3(0.6, 0, 0), Vec3::UnitY(), n, 0);
  add_straight_tube(el, Vec3(L - 1.2, 0.3, 0.1), Vec3::UnitY(), n, 1);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  std::mt19937_64 g(5);
  std::normal_distribution<double> thermal(0.0, 0.3);
  for (std::size_t i = 0; i < el.size(); ++i) {
    el.v[i] = Vec3(2.0 + thermal(g), thermal(g), thermal(g));  // drift 2 nm/ps through x
    el.w[i] = Vec3(thermal(g), thermal(g), thermal(g));
  }
  IntegratorSettings s;
  s.dt = 0.01;
  System sys(std::move(el), s);
  sys.add(std::move(bonds));
  sys.add(std::make_unique<AnisotropicVdw>());
  sys.set_domain(Domain(Vec3::Zero(), Vec3(L, 60, 60), {true, false, false}));
  sys.initialize();
  const double vdw0 = sys.energy().potential.stored[static_cast<int>(EnergyTerm::Vdw)];
  ASSERT_LT(vdw0, -5.0);  // the tubes adhere through the boundary
  const double e0 = sys.energy().total(), k0 = sys.energy().kinetic();
  const double x0 = sys.elements().x[0].x();
  double worst = 0;
  for (int k = 0; k < 40; ++k) {
    sys.run(50);
    worst = std::max(worst, std::abs(sys.energy().total() - e0));
    EXPECT_LT(sys.energy().potential.stored[static_cast<int>(EnergyTerm::Vdw)], 0.5 * vdw0);
  }
  // 2000 steps of 10 fs: the tubes drift 40 nm, through the boundary 2-3 times.
  EXPECT_GT(sys.elements().x[0].x() - x0, 2 * L);
  EXPECT_LT(worst, 2e-3 * k0) << "kinetic " << k0 << " eV";
}

// A bonded tube straddling the periodic boundary, with its positions wrapped into the box (so its
// bonded neighbours sit a box length apart): bonds and vdW see the same minimum images, and
// energy, forces and torques are those of the unwrapped tube.
TEST(Domain, WrappedPositionsGiveTheSameForcesAsUnwrapped) {
  const double L = 18;
  Elements el;
  add_straight_tube(el, Vec3(L - 4, 1, 1), Vec3(1, 0.02, 0).normalized(), 6, 0);
  add_straight_tube(el, Vec3(L - 5, 2.75, 1.1), Vec3(1, 0, 0.02).normalized(), 6, 1);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  std::mt19937_64 g(9);
  std::normal_distribution<double> jiggle(0.0, 0.01);
  for (std::size_t i = 0; i < el.size(); ++i) {
    el.x[i] += Vec3(jiggle(g), jiggle(g), jiggle(g));
    el.q[i] = (quat_exp(Vec3(jiggle(g), jiggle(g), jiggle(g))) * el.q[i]).normalized();
  }
  const Domain box(Vec3::Zero(), Vec3(L, L, 40), {true, true, false});
  Elements wrapped = el;
  int moved = 0;
  for (auto& x : wrapped.x) {
    const Vec3 w = box.wrap(x);
    moved += (w - x).norm() > 1.0;
    x = w;
  }
  ASSERT_GE(moved, 4);  // part of each tube was moved by a box length
  auto evaluate = [&](Elements e) {
    IntegratorSettings s;
    s.dt = 0.001;
    System sys(std::move(e), s);
    sys.add(std::make_unique<ParallelBond>(*bonds));
    sys.add(std::make_unique<AnisotropicVdw>());
    sys.set_domain(box);
    sys.initialize();
    return sys;
  };
  const System a = evaluate(el), b = evaluate(wrapped);
  const auto& ea = a.energy().potential.stored;
  const auto& eb = b.energy().potential.stored;
  ASSERT_LT(ea[static_cast<int>(EnergyTerm::Vdw)], -1.0);
  ASSERT_GT(ea[static_cast<int>(EnergyTerm::BondBending)], 1e-4);
  for (int k = 0; k < kEnergyTermCount; ++k)
    EXPECT_NEAR(eb[k], ea[k], 1e-9 * std::max(1.0, std::abs(ea[k]))) << kEnergyTermNames[k];
  double fs = 0;
  for (std::size_t i = 0; i < el.size(); ++i) fs = std::max(fs, a.elements().f[i].norm());
  for (std::size_t i = 0; i < el.size(); ++i) {
    EXPECT_LT((a.elements().f[i] - b.elements().f[i]).norm(), 1e-9 * fs) << i;
    EXPECT_LT((a.elements().t[i] - b.elements().t[i]).norm(), 1e-9 * fs) << i;
  }
}
