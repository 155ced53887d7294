// Bond topology held with the elements (core/topology.h): validation, the intra-tube exclusion
// around a ring's seam, a free ring's energy conservation and closure, checkpoints, and bonds
// made from the topology against bonds made pair by pair.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>

#include "mdem/core/cnt.h"
#include "mdem/core/topology.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/integrate/system.h"
#include "mdem/io/state_io.h"
#include "mdem/scene/bundle_scene.h"
#include "mdem/scene/grain.h"
#include "mdem/scene/hex_rope.h"
#include "mdem/scene/tube_builder.h"

using namespace mdem;

namespace {

constexpr double kT = cnt::kSegmentLength;

// The message of the std::invalid_argument fn throws ("" when it throws none).
template <class Fn>
std::string invalid(Fn&& fn) {
  try {
    fn();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

bool has(const std::string& s, const char* part) { return s.find(part) != std::string::npos; }

// Three free CNT segments of tube 0 (indices 0, 1, 2) and one grain, no topology.
Elements loose_segments() {
  Elements el;
  for (int k = 0; k < 3; ++k) el.add(cnt_segment(Vec3(k * kT, 0, 0), Quat::Identity(), 0, k));
  el.add(grain_element(Vec3(0, 5, 0), 1.0, gold()));
  return el;
}

}  // namespace

TEST(Topology, RefusesBadBondsAndChainsNamingTheProblem) {
  Elements el = loose_segments();
  Topology& t = el.topology;
  EXPECT_TRUE(has(invalid([&] { t.add_bond(el, 0, 9, BondType::Cnt); }), "tag 9 names no element"));
  EXPECT_TRUE(has(invalid([&] { t.add_bond(el, 1, 1, BondType::Cnt); }), "bonded to itself"));
  EXPECT_TRUE(has(invalid([&] { t.add_bond(el, 0, 3, BondType::Cnt); }), "two CNT segments"));
  t.add_bond(el, 0, 1, BondType::Cnt);
  EXPECT_TRUE(has(invalid([&] { t.add_bond(el, 0, 1, BondType::Cnt); }), "bonded already"));
  EXPECT_TRUE(has(invalid([&] { t.add_bond(el, 1, 0, BondType::Cnt); }), "bonded already"));
  EXPECT_EQ(t.bonds().size(), 1u);  // the refused ones left nothing behind

  Chain two{0, {0, 1}, true, -1};
  EXPECT_TRUE(has(invalid([&] { t.add_chain(el, two); }), "a ring needs at least 3 segments"));
  Chain swapped{0, {1, 0, 2}, false, -1};
  EXPECT_TRUE(has(invalid([&] { t.add_chain(el, swapped); }), "position 1 must hold"));
  Chain grain{0, {0, 1, 2, 3}, false, -1};
  EXPECT_TRUE(has(invalid([&] { t.add_chain(el, grain); }), "is no CNT segment"));
  Chain unknown{0, {0, 1, 7}, false, -1};
  EXPECT_TRUE(has(invalid([&] { t.add_chain(el, unknown); }), "tag 7 names no element"));
  Chain wrong_tube{1, {0, 1, 2}, false, -1};
  EXPECT_TRUE(
      has(invalid([&] { t.add_chain(el, wrong_tube); }), "must hold the CNT segment of tube 1"));
  Chain negative{-1, {0}, false, -1};
  EXPECT_TRUE(has(invalid([&] { t.add_chain(el, negative); }), "tube id must be >= 0"));
  Chain own_parent{0, {0, 1, 2}, false, 0};
  EXPECT_TRUE(has(invalid([&] { t.add_chain(el, own_parent); }), "parent must be -1"));
  // A bonded ring whose bond 0-1 exists already: refused whole, nothing recorded.
  Chain ring{0, {0, 1, 2}, true, -1};
  EXPECT_TRUE(has(invalid([&] { t.add_bonded_chain(el, ring, BondType::Cnt); }), "bonded already"));
  EXPECT_EQ(t.bonds().size(), 1u);
  EXPECT_EQ(t.chain(0), nullptr);
  EXPECT_EQ(t.ring_length(0), 0);

  t.add_chain(el, ring);
  ASSERT_NE(t.chain(0), nullptr);
  EXPECT_EQ(t.ring_length(0), 3);
  EXPECT_TRUE(has(invalid([&] { t.add_chain(el, ring); }), "tube 0 has a chain already"));

  // The builders check before adding: a refused tube adds no element.
  Elements built;
  add_straight_tube(built, Vec3::Zero(), Vec3::UnitX(), 4, 0);
  EXPECT_TRUE(has(invalid([&] { add_ring_tube(built, Vec3::Zero(), Vec3::UnitZ(), 12, 0); }),
                  "tube id 0 is taken"));
  EXPECT_TRUE(has(invalid([&] { add_ring_tube(built, Vec3::Zero(), Vec3::UnitZ(), 2, 1); }),
                  "at least 3 segments"));
  EXPECT_TRUE(
      has(invalid([&] { add_ring_tube(built, Vec3::Zero(), Vec3::Zero(), 12, 1); }), "normal"));
  EXPECT_EQ(built.size(), 4u);
}

TEST(Topology, RingExclusionReachesAcrossTheSeamAsInTheMiddle) {
  const int n = 50, exclusion = 20;
  Elements ring;
  const auto ids = add_ring_tube(ring, Vec3(1, 2, 3), Vec3(0.3, -0.2, 1), n, 0);
  ASSERT_EQ(ring.topology.bonds().size(), static_cast<std::size_t>(n));
  EXPECT_EQ(ring.topology.bonds().back(), (TopologyBond{ring.tag[ids[n - 1]], ring.tag[ids[0]]}));
  // The geometry: every neighbour pair, the seam included, is T apart.
  for (int k = 0; k < n; ++k)
    EXPECT_NEAR((ring.x[ids[(k + 1) % n]] - ring.x[ids[k]]).norm(), kT, 1e-12);

  Elements open;
  add_straight_tube(open, Vec3::Zero(), Vec3::UnitX(), n, 0);
  const AnisotropicVdw vdw;  // its exclusion is the default intra-tube one, 20
  for (int k = 0; k < n; ++k)
    for (int d = 1; d < n; ++d) {
      const std::size_t i = ids[k], j = ids[(k + d) % n];
      const bool expect = std::min(d, n - d) < exclusion;
      EXPECT_EQ(ring.cnt_pair_excluded(i, j, exclusion), expect) << k << " + " << d;
      EXPECT_EQ(vdw.excludes(ring, i, j), expect) << k << " + " << d;
      const int di = std::abs(k - (k + d) % n);
      EXPECT_EQ(open.cnt_pair_excluded(i, j, exclusion), di < exclusion) << k << " + " << d;
    }
  // Segments 0 and n−1: neighbours on the ring, far apart on the open tube.
  EXPECT_TRUE(ring.cnt_pair_excluded(ids[0], ids[n - 1], exclusion));
  EXPECT_FALSE(open.cnt_pair_excluded(0, n - 1, exclusion));
}

namespace {

// The deviation from T of the centre distance of segments a and b, its largest over a run.
struct GapWatch {
  std::size_t a, b;
  double worst = 0;
  void look(const Elements& el) {
    worst = std::max(worst, std::abs((el.x[b] - el.x[a]).norm() - kT));
  }
};

}  // namespace

TEST(Topology, FreeRingConservesEnergyAndStaysClosedAtItsSeam) {
  // A 60-segment ring vibrating at about 800 K (bundle scene's rms speeds), undamped, bonds from
  // the topology, vdW on. Declared closed, its seam is an ordinary bond and the exclusion spans
  // it: no pair of the ring is within vdW reach outside the exclusion, the total energy stays
  // put and the seam bond stays within 1 % of T. The same elements declared as an open chain
  // (no seam bond; its ends meet by vdW alone) open at the seam.
  const int n = 60;
  Elements ring;
  const auto ids = add_ring_tube(ring, Vec3::Zero(), Vec3::UnitZ(), n, 0);
  randomize_motion(ring, 0.05, 0.08, 3);
  Elements open = ring;
  open.topology = Topology{};
  record_cnt_tube(open, ids, 0, false);
  ASSERT_EQ(open.topology.bonds().size(), static_cast<std::size_t>(n - 1));

  // Undamped at the default (auto) step: the energy record's drift is the mean of its last
  // quarter less that of its first (Verlet's bounded O(dt²) oscillation averages out).
  struct Run {
    GapWatch seam;
    double vdw0 = 0, ke_scale = 0, drift = 0, balance = 0, dt = 0;
  };
  auto run = [&](const Elements& el) {
    Run out{{ids[n - 1], ids[0]}};
    System sys{Elements(el)};
    sys.add(ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness()));
    sys.add(std::make_unique<AnisotropicVdw>());
    sys.initialize();
    out.vdw0 = sys.energy().potential.stored[static_cast<int>(EnergyTerm::Vdw)];
    const int samples = 200, quarter = samples / 4;
    double first = 0, last = 0;
    for (int k = 0; k < samples; ++k) {
      sys.run(100);
      out.seam.look(sys.elements());
      const double e = sys.energy().total();
      if (k < quarter) first += e / quarter;
      if (k >= samples - quarter) last += e / quarter;
      out.ke_scale += sys.energy().kinetic() / samples;
    }
    out.drift = std::abs(last - first);
    out.balance = sys.energy_balance_error();
    out.dt = sys.dt();
    return out;
  };
  const Run closed = run(ring), opened = run(open);
  std::printf(
      "20000 steps of %.1f fs: ring energy drift %.3g eV (kinetic scale %.3g eV), seam |d − T| ≤ "
      "%.3g nm; open chain end gap |d − T| ≤ %.3g nm, its vdW at start %.3g eV\n",
      closed.dt * 1e3, closed.drift, closed.ke_scale, closed.seam.worst, opened.seam.worst,
      opened.vdw0);

  EXPECT_EQ(closed.vdw0, 0.0);            // every ring pair within reach is within the exclusion
  EXPECT_GT(std::abs(opened.vdw0), 1.0);  // the open chain's ends meet by vdW (end to end)
  // Energy: test_cnt_bundle's NVE bounds (drift < 1e-3 of the kinetic scale, balance < 5 %).
  EXPECT_LT(closed.drift, 1e-3 * closed.ke_scale);
  EXPECT_LT(closed.balance, 5e-2);
  EXPECT_LT(closed.seam.worst, 0.01 * kT);
  EXPECT_GT(opened.seam.worst, 3 * closed.seam.worst);
}

TEST(Topology, SurvivesACheckpointAndResumesBitIdentically) {
  Elements el;
  add_ring_tube(el, Vec3::Zero(), Vec3::UnitZ(), 40, 0);
  add_straight_tube(el, Vec3(-20, 0, 3), Vec3::UnitX(), 30, 1);
  el.groups.add("ring.first", {0, 1, 2});
  randomize_motion(el, 0.05, 0.08, 7);
  auto make = [](Elements e, const Elements& bonded_as) {
    System sys(std::move(e));
    sys.add(ParallelBond::from_topology(bonded_as, BondType::Cnt, cnt_bond_stiffness()));
    sys.add(std::make_unique<AnisotropicVdw>());
    sys.initialize();
    return sys;
  };
  System a = make(el, el);
  a.run(300);
  StateWriter w;
  write_header(w);
  a.save_state(w);

  // Loaded into the same elements without topology or groups: both come back from the file.
  Elements bare = el;
  bare.topology = Topology{};
  bare.groups = Groups{};
  System b = make(bare, el);
  StateReader r(w.bytes());
  read_header(r);
  b.load_state(r);
  r.expect_end();
  const Elements& ea = a.elements();
  const Elements& eb = b.elements();
  EXPECT_TRUE(eb.topology == ea.topology);
  EXPECT_EQ(eb.topology.ring_length(0), 40);
  EXPECT_EQ(eb.topology.ring_length(1), 0);
  EXPECT_EQ(eb.groups.names(), ea.groups.names());
  EXPECT_EQ(eb.group_indices("ring.first"), ea.group_indices("ring.first"));
  for (std::size_t i = 0; i < ea.size(); ++i)
    for (std::size_t j = 0; j < ea.size(); ++j)
      ASSERT_EQ(eb.cnt_pair_excluded(i, j, 20), ea.cnt_pair_excluded(i, j, 20)) << i << ", " << j;
  a.run(300);
  b.run(300);
  for (std::size_t i = 0; i < ea.size(); ++i) {
    ASSERT_EQ(a.elements().x[i], b.elements().x[i]) << i;
    ASSERT_EQ(a.elements().q[i].coeffs(), b.elements().q[i].coeffs()) << i;
  }

  // A checkpoint whose topology names an element this job lacks is refused, naming the section
  // and field: the first bond's first tag (just after the section name) made 999 999.
  std::string bad = w.bytes();
  const std::size_t at = bad.find("topology");
  ASSERT_NE(at, std::string::npos);
  const std::uint64_t stranger = 999999;
  std::memcpy(&bad[at + 8 + sizeof(std::uint64_t)], &stranger, sizeof stranger);
  System c = make(bare, el);
  StateReader rc(bad);
  read_header(rc);
  try {
    c.load_state(rc);
    FAIL() << "a checkpoint naming an unknown element was loaded";
  } catch (const CheckpointError& e) {
    EXPECT_TRUE(has(e.what(), "section 'topology', field 'bonds'")) << e.what();
    EXPECT_TRUE(has(e.what(), "tag 999999 names no element")) << e.what();
  }
}

TEST(Topology, HexRopeBondsFromTopologyEqualBondsMadePairByPair) {
  Elements el;
  RopeSpec spec;
  spec.layers = 3;
  spec.segments = 12;
  spec.spacing = 1.72;
  spec.missing = {4};
  spec.lines = {LineDefect{30, 1, 0.5}};
  const Rope rope = build_hex_rope(el, spec);
  const BondStiffness k = cnt_bond_stiffness();
  // The old way: make_bond on each tube's consecutive segments, tube by tube.
  std::vector<Bond> expected;
  for (const RopeTube& t : rope.tubes)
    for (std::size_t s = 0; s + 1 < t.elements.size(); ++s)
      expected.push_back(make_bond(el, static_cast<std::uint32_t>(t.elements[s]),
                                   static_cast<std::uint32_t>(t.elements[s + 1]), k));
  const auto model = ParallelBond::from_topology(el, BondType::Cnt, k);
  ASSERT_EQ(model->bonds().size(), expected.size());
  ASSERT_GT(rope.tubes.size(), 18u);  // the partial line defect cut tubes in two
  for (std::size_t b = 0; b < expected.size(); ++b) {
    const Bond& x = model->bonds()[b];
    const Bond& y = expected[b];
    EXPECT_EQ(x.i, y.i);
    EXPECT_EQ(x.j, y.j);
    EXPECT_EQ(x.ci, y.ci);
    EXPECT_EQ(x.cj, y.cj);
    EXPECT_EQ(x.ni, y.ni);
    EXPECT_EQ(x.nj, y.nj);
    EXPECT_EQ(x.q_rel0.coeffs(), y.q_rel0.coeffs());
  }
  // One open chain per rope tube, with the rope's tube ids and element order.
  ASSERT_EQ(el.topology.chains().size(), rope.tubes.size());
  for (const RopeTube& t : rope.tubes) {
    const Chain* c = el.topology.chain(t.id);
    ASSERT_NE(c, nullptr);
    EXPECT_FALSE(c->closed);
    ASSERT_EQ(c->tags.size(), t.elements.size());
    for (std::size_t s = 0; s < t.elements.size(); ++s)
      EXPECT_EQ(c->tags[s], el.tag[t.elements[s]]);
  }
}
