// The twist scene's pieces, each against something independent: lattice geometry by counting,
// the equilibrium spacing by the energy it minimises, the topological charge on hand-built
// sections whose charge is known, and the grip load by the moment and force it must sum to.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "mdem/core/cnt.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/integrate/system.h"
#include "mdem/observe/rope_observables.h"
#include "mdem/protocol/twist_protocol.h"
#include "mdem/scene/hex_rope.h"

namespace mdem {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(HexLattice, SiteCountsRingsAndNeighbours) {
  for (int N = 1; N <= 8; ++N) {
    const HexLattice L = make_hex_lattice(N, 1.7);
    ASSERT_EQ(static_cast<int>(L.size()), 3 * N * N - 3 * N + 1);
    ASSERT_EQ(hex_site_count(N), 3 * N * N - 3 * N + 1);
    int interior = 0;
    for (std::size_t s = 0; s < L.size(); ++s) {
      // Every site sits at a lattice distance from every other: no two closer than d.
      for (std::size_t t = s + 1; t < L.size(); ++t)
        ASSERT_GT((L.sites[s] - L.sites[t]).norm(), 1.7 * (1 - 1e-9));
      if (L.ring[s] < N - 1) {
        EXPECT_EQ(L.neighbors[s].size(), 6u) << "interior site " << s;
        ++interior;
      } else {
        EXPECT_LT(L.neighbors[s].size(), 6u) << "outer site " << s;
      }
    }
    EXPECT_EQ(interior, N > 1 ? hex_site_count(N - 1) : 0);
  }
  // N = 6 is the thesis's 91-tube rope: corner at 5 d (≈ 8.6 nm at d = 1.71 nm).
  const HexLattice L = make_hex_lattice(6, 1.712);
  double rmax = 0;
  for (const Vec2& p : L.sites) rmax = std::max(rmax, p.norm());
  EXPECT_NEAR(rmax, 5 * 1.712, 1e-12);
}

TEST(HexLattice, RefusesImpossibleInput) {
  EXPECT_THROW(make_hex_lattice(0, 1.7), std::invalid_argument);
  EXPECT_THROW(make_hex_lattice(51, 1.7), std::invalid_argument);
  EXPECT_THROW(make_hex_lattice(3, NAN), std::invalid_argument);
  EXPECT_THROW(make_hex_lattice(3, -1), std::invalid_argument);
}

// The spacing is where the lattice energy is lowest: a parabola through E(d ± h) has its vertex
// at d, and it lies in the thesis's equilibrium range 1.70–1.76 nm.
TEST(HexLattice, EquilibriumSpacingMinimisesTheLatticeEnergy) {
  const double d = lattice_equilibrium_spacing();
  EXPECT_GT(d, 1.68);
  EXPECT_LT(d, 1.76);
  // Independent energy: a seven-tube cross-section's centre tube, long tubes, direct pair sum.
  auto energy = [](double s) {
    double e = 0;
    const VdwParams p;
    const HexLattice L = make_hex_lattice(4, s);
    for (std::size_t t = 1; t < L.size(); ++t)
      for (int k = -6; k <= 6; ++k)
        e += vdw_pair(p, Vec3::Zero(), Vec3::UnitZ(),
                      Vec3(L.sites[t].x(), L.sites[t].y(), k * cnt::kSegmentLength), Vec3::UnitZ())
                 .energy;
    return e;
  };
  const double h = 0.01;
  const double em = energy(d - h), e0 = energy(d), ep = energy(d + h);
  EXPECT_LT(e0, em);
  EXPECT_LT(e0, ep);
  const double vertex = d - h * (ep - em) / (2 * (ep - 2 * e0 + em));
  EXPECT_NEAR(vertex, d, 2e-3);
}

TEST(HexRope, BuildsTubesGripsAndInternalSites) {
  Elements el;
  RopeSpec spec;
  spec.layers = 4;
  spec.segments = 20;
  spec.spacing = 1.72;
  spec.grip_segments = 2;
  const Rope rope = build_hex_rope(el, spec);
  const ParallelBond bonds = *ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  EXPECT_EQ(rope.tubes.size(), 37u);
  EXPECT_EQ(el.size(), 37u * 20);
  EXPECT_EQ(bonds.bonds().size(), 37u * 19);
  const std::vector<std::size_t> grip_a = el.group_indices(kRopeGripA),
                                 grip_b = el.group_indices(kRopeGripB);
  EXPECT_EQ(grip_a.size(), 37u * 2);
  EXPECT_EQ(grip_b.size(), 37u * 2);
  for (std::size_t i : grip_a) EXPECT_LT(el.x[i].z(), 0);
  for (std::size_t i : grip_b) EXPECT_GT(el.x[i].z(), 0);
  int internal = 0;
  for (bool b : rope.internal) internal += b;
  EXPECT_EQ(internal, 19);  // rings 0..2
  EXPECT_EQ(rope.outer_sites.size(), 18u);
  EXPECT_NEAR(rope.initial_radius, 3 * 1.72, 1e-12);
  // Centred on the origin, axis z, consecutive segments one bond length apart.
  double zsum = 0;
  for (const Vec3& x : el.x) zsum += x.z();
  EXPECT_NEAR(zsum, 0, 1e-9);
  EXPECT_NEAR((el.x[1] - el.x[0]).norm(), cnt::kSegmentLength, 1e-12);
  EXPECT_NEAR(el.axis(0).dot(Vec3::UnitZ()), 1.0, 1e-12);
}

TEST(HexRope, PointAndLineDefectsRemoveTheRightTubes) {
  const HexLattice L = make_hex_lattice(6, 1.72);
  // One row along +x from the centre: sites (k d, 0), k = 0..5.
  const std::vector<int> row = line_defect_sites(L, {0.0, 1, 1.0});
  ASSERT_EQ(row.size(), 6u);
  for (int s : row) EXPECT_NEAR(L.sites[s].y(), 0, 1e-12);
  EXPECT_EQ(line_defect_sites(L, {0.0, 2, 1.0}).size(), 11u);  // plus the row above, 5 sites
  EXPECT_EQ(line_defect_sites(L, {60.0, 1, 1.0}).size(), 6u);

  Elements el;
  RopeSpec spec;
  spec.layers = 6;
  spec.segments = 20;
  spec.spacing = 1.72;
  spec.missing = {0, 7};
  spec.lines = {{180.0, 1, 0.5}};  // a short line defect: the middle half of 6 tubes
  const Rope rope = build_hex_rope(el, spec);
  // 91 sites − 2 missing; the 6 row sites each hold two tubes (one per end), but site 0 is
  // missing already: 89 + 5 extra tubes.
  EXPECT_EQ(rope.tubes.size(), 89u + 5u);
  EXPECT_EQ(el.size(), 89u * 20 - 5u * 10);
  // Neighbours of a missing or cut tube are not internal; the two missing sites are not either.
  EXPECT_FALSE(rope.internal[0]);
  EXPECT_FALSE(rope.internal[7]);
  for (int nb : L.neighbors[7]) EXPECT_FALSE(rope.internal[nb]);
  EXPECT_THROW(build_hex_rope(el, RopeSpec{6, 20, 1.72, {91}, {}, 1}), std::invalid_argument);
  EXPECT_THROW(build_hex_rope(el, RopeSpec{2, 20, 1.72, {0, 1, 2, 3, 4, 5, 6}, {}, 1}),
               std::invalid_argument);
  EXPECT_THROW(build_hex_rope(el, RopeSpec{3, 20, 1.72, {}, {}, 11}), std::invalid_argument);
}

// A cross-section as straight tubes through the given in-plane points.
struct Section {
  std::vector<Vec3> centres;
  std::vector<std::vector<Vec3>> tubes;
  std::vector<bool> internal;
  void add(const Vec2& p, bool is_internal) {
    centres.emplace_back(p.x(), p.y(), 0.0);
    tubes.push_back({Vec3(p.x(), p.y(), -2.0), Vec3(p.x(), p.y(), 2.0)});
    internal.push_back(is_internal);
  }
  int charge(double d) const {
    return topological_charge(centres, tubes, internal, charge_neighbor_distance(d)).charge;
  }
};

Section lattice_section(int layers, double d, double scale = 1.0, double angle = 0.0,
                        std::vector<int> skip = {}) {
  const HexLattice L = make_hex_lattice(layers, d);
  const Eigen::Rotation2Dd R(angle);
  Section s;
  for (std::size_t t = 0; t < L.size(); ++t) {
    if (std::find(skip.begin(), skip.end(), static_cast<int>(t)) != skip.end()) continue;
    s.add(scale * (R * L.sites[t]), L.ring[t] < layers - 1);
  }
  return s;
}

TEST(TopologicalCharge, PerfectLatticeHasNone) {
  const double d = 1.713;
  EXPECT_EQ(lattice_section(6, d).charge(d), 0);
  EXPECT_EQ(lattice_section(6, d, 1.0, 0.7).charge(d), 0);   // rotated
  EXPECT_EQ(lattice_section(6, d, 1.05, 0.0).charge(d), 0);  // 5 % dilated: still six each
}

TEST(TopologicalCharge, VacanciesCountTheirMissingBonds) {
  const double d = 1.713;
  // A vacancy at the centre: its six neighbours have five each.
  EXPECT_EQ(lattice_section(6, d, 1.0, 0.0, {0}).charge(d), 6);
  // Two adjacent vacancies (sites 0 and 1): 8 neighbours, two of them lose two bonds.
  EXPECT_EQ(lattice_section(6, d, 1.0, 0.0, {0, 1}).charge(d), 10);
  // Dilated by 1.5: nobody within 1.37 d, every internal tube counts six.
  EXPECT_EQ(lattice_section(6, d, 1.5).charge(d), 6 * hex_site_count(5));
}

TEST(TopologicalCharge, FiveAndSevenFoldSitesCarryPlusAndMinusOne) {
  const double d = 1.713;
  for (int m : {4, 5, 7}) {
    Section s;
    s.add(Vec2::Zero(), true);
    for (int k = 0; k < m; ++k)
      s.add(d * Vec2(std::cos(2 * kPi * k / m), std::sin(2 * kPi * k / m)), false);
    EXPECT_EQ(s.charge(d), 6 - m) << m << "-fold";
  }
}

// Helical tubes: the thesis measures neighbours by the closest approach of the two tubes, so a
// twisted perfect lattice (outer tubes tilted ~20°) still has no charge, although the in-plane
// crossing points of tilted neighbours are farther apart than d.
TEST(TopologicalCharge, TwistedPerfectLatticeHasNone) {
  const double d = 1.713;
  const HexLattice L = make_hex_lattice(6, d);
  const double rate = std::tan(20.0 * kPi / 180.0) / (5 * d);  // rad/nm: 20° at the corner
  Section s;
  for (std::size_t t = 0; t < L.size(); ++t) {
    std::vector<Vec3> line;
    for (int k = -6; k <= 6; ++k) {
      const double z = k * cnt::kSegmentLength;
      const Vec2 p = Eigen::Rotation2Dd(rate * z) * L.sites[t];
      line.emplace_back(p.x(), p.y(), z);
    }
    s.centres.push_back(line[6]);
    s.tubes.push_back(line);
    s.internal.push_back(L.ring[t] < 5);
  }
  EXPECT_EQ(s.charge(d), 0);
}

System rope_system(Rope& rope, int layers, int segments) {
  Elements el;
  RopeSpec spec;
  spec.layers = layers;
  spec.segments = segments;
  spec.spacing = 1.72;
  rope = build_hex_rope(el, spec);
  return System(std::move(el));
}

TEST(TwistProtocol, ScheduleRampsHoldsAndUnloads) {
  TwistLoading l{units::nNnm(10), units::nNnm(1), 20, TwistBoundary::ConstantMoment, true, 5};
  const TwistProtocol p(l, {0}, {1});
  EXPECT_NEAR(p.ramp_time(), 10, 1e-12);
  EXPECT_NEAR(p.duration(), 10 + 20 + 10 + 5, 1e-12);
  EXPECT_EQ(p.phase_at(5), TwistPhase::Loading);
  EXPECT_NEAR(p.torque_at(5), units::nNnm(5), 1e-9);
  EXPECT_EQ(p.phase_at(15), TwistPhase::Holding);
  EXPECT_NEAR(p.torque_at(15), units::nNnm(10), 1e-9);
  EXPECT_EQ(p.phase_at(32), TwistPhase::Unloading);
  EXPECT_NEAR(p.torque_at(32), units::nNnm(8), 1e-9);
  EXPECT_EQ(p.phase_at(42), TwistPhase::Relaxing);
  EXPECT_EQ(p.torque_at(42), 0);
  EXPECT_EQ(p.phase_at(46), TwistPhase::Done);
  l.boundary = TwistBoundary::TwistRelaxation;
  const TwistProtocol r(l, {0}, {1});
  EXPECT_NEAR(r.duration(), 10 + 20 + 5, 1e-12);  // no ramp down: the torque is already off
  EXPECT_EQ(r.torque_at(15), 0);
  EXPECT_THROW(TwistProtocol({0, 1, 1}, {0}, {1}), std::invalid_argument);
  EXPECT_THROW(TwistProtocol({1, NAN, 1}, {0}, {1}), std::invalid_argument);
  EXPECT_THROW(TwistProtocol({1, 1, -1}, {0}, {1}), std::invalid_argument);
  EXPECT_THROW(TwistProtocol({1, 1, 1}, {}, {1}), std::invalid_argument);
}

// The grip load is a pure moment about the axis: it sums to ±T about the axis through each grip's
// centroid, to zero force, and to no moment about the other two axes.
TEST(TwistProtocol, GripLoadIsAPureMomentOfTheSetSize) {
  Rope rope;
  System sys = rope_system(rope, 4, 12);
  const std::vector<std::size_t> grip_a = sys.elements().group_indices(kRopeGripA),
                                 grip_b = sys.elements().group_indices(kRopeGripB);
  TwistLoading l{units::nNnm(30), units::nNnm(1), 10, TwistBoundary::ConstantMoment, false, 0};
  TwistProtocol p(l, grip_a, grip_b);
  // Perturb the grips so the load is not computed on a symmetric layout only.
  Elements& el = sys.elements();
  for (std::size_t k = 0; k < el.size(); ++k)
    el.x[k] += 0.05 * Vec3(std::sin(k), std::cos(3.0 * k), 0);
  p.apply(sys, 35.0);  // holding (ramp 30 ps): T = 30 nN·nm
  for (const auto* grip : {&grip_a, &grip_b}) {
    const Vec3 c = mass_centroid(el, *grip);
    Vec3 force = Vec3::Zero(), moment = Vec3::Zero();
    for (std::size_t i : *grip) {
      force += el.f_ext[i];
      moment += (el.x[i] - c).cross(el.f_ext[i]) + el.t_ext[i];
    }
    const double sign = grip == &grip_b ? 1.0 : -1.0;
    EXPECT_NEAR(moment.z(), sign * units::nNnm(30), 1e-9);
    EXPECT_NEAR(force.norm(), 0, 1e-9);
    EXPECT_NEAR(moment.x(), 0, 1e-9);
    EXPECT_NEAR(moment.y(), 0, 1e-9);
  }
}

TEST(ShiftAngle, FollowsARigidTurnOfOneEndPastHalfATurn) {
  Rope rope;
  System sys = rope_system(rope, 3, 10);
  Elements& el = sys.elements();
  const std::vector<std::size_t> grip_b = el.group_indices(kRopeGripB);
  ShiftAngle shift(el, rope);
  const std::vector<Vec3> x0 = el.x;
  double got = 0;
  for (int k = 1; k <= 40; ++k) {
    const double phi = k * 0.1;  // up to 4 rad > π
    for (std::size_t i : grip_b) {
      const Eigen::AngleAxisd R(phi, Vec3::UnitZ());
      el.x[i] = R * x0[i];
    }
    got = shift.update(el, rope_axis(el, rope));
  }
  EXPECT_NEAR(got, 4.0, 1e-9);
}

}  // namespace
}  // namespace mdem
