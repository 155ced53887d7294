// The tube pieces both grips of a tensile test hold, and their affine modulus
// (mdem/observe/grip_bridges.h): counted and summed by hand on pieces of known geometry. That the
// affine modulus is what a test measures for a lone straight tube is checked in
// TensileGripStress.QuasiStaticBalanceAndTheTubeModulus (tests/test_tensile_protocol.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/core/cnt.h"
#include "mdem/core/elements.h"
#include "mdem/core/units.h"
#include "mdem/observe/grip_bridges.h"
#include "mdem/scene/tube_builder.h"

using namespace mdem;

namespace {

const double kEA = cnt::kBondKn * cnt::kBondArea * cnt::kSegmentLength;  // eV/nm
const FilmGeometry kFilm{100.0, 50.0, 11.0};                             // L0, W, H (nm)

}  // namespace

TEST(GripBridges, CountsPiecesInBothGripsAndSumsTheirChords) {
  Elements el;
  const double T = cnt::kSegmentLength;
  const double pi = std::acos(-1.0);
  // Piece 0 along x; piece 1 at 60° to x in the xy plane; piece 2 along x, held by the left grip
  // only; piece 3 in neither grip; an NP in the right grip.
  const auto p0 = add_straight_tube(el, Vec3(0, 0, 0), Vec3::UnitX(), 20, 0);
  const auto p1 =
      add_straight_tube(el, Vec3(0, 5, 0), Vec3(std::cos(pi / 3), std::sin(pi / 3), 0), 20, 1);
  const auto p2 = add_straight_tube(el, Vec3(0, -5, 0), Vec3::UnitX(), 10, 2);
  add_straight_tube(el, Vec3(0, -10, 0), Vec3::UnitX(), 10, 3);
  ElementInit np;
  np.kind = ElementKind::Nanoparticle;
  np.x = Vec3(40, 0, 0);
  np.mass = 1;
  np.inertia = Vec3(1, 1, 1);
  np.radius = 2.5;
  const std::size_t inp = el.add(np);
  // The grips by hand: piece 0's first 3 and last 3 segments, piece 1's first 2 and last 2,
  // piece 2's first 4; the NP on the right.
  const std::vector<std::size_t> left = {p0[0], p0[1], p0[2], p1[0], p1[1],
                                         p2[0], p2[1], p2[2], p2[3]};
  const std::vector<std::size_t> right = {p0[17], p0[18], p0[19], p1[18], p1[19], inp};

  const GripBridges g = grip_bridges(el, left, right, kEA, kFilm);
  EXPECT_EQ(g.pieces, 2u);
  // Piece 0: chord from segment 2 to 17, d = 15 T, c = 1. Piece 1: from 1 to 18, d = 17 T,
  // c = cos 60° = 1/2.
  const double k0 = kEA * kFilm.length / (15 * T);
  const double k1 = kEA * kFilm.length * 0.25 / (17 * T);
  const double expected = units::to_GPa((k0 + k1) / (kFilm.width * kFilm.thickness));
  EXPECT_NEAR(g.affine_modulus / expected, 1.0, 1e-12) << g.affine_modulus << " GPa";

  // The order of the grips' indices does not matter; no piece in both grips gives zero.
  const std::vector<std::size_t> left_rev(left.rbegin(), left.rend());
  EXPECT_NEAR(grip_bridges(el, left_rev, right, kEA, kFilm).affine_modulus, g.affine_modulus,
              1e-12 * g.affine_modulus);
  const GripBridges none = grip_bridges(el, left, std::vector<std::size_t>{inp}, kEA, kFilm);
  EXPECT_EQ(none.pieces, 0u);
  EXPECT_EQ(none.affine_modulus, 0.0);
}

TEST(GripBridges, BadInputIsNamed) {
  Elements el;
  const auto p = add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 5, 0);
  const std::vector<std::size_t> left = {p[0]}, right = {p[4]};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  auto message = [&](double ea, FilmGeometry f, std::vector<std::size_t> r) {
    try {
      grip_bridges(el, left, r, ea, f);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(0, kFilm, right).find("axial stiffness EA"), std::string::npos);
  EXPECT_NE(message(nan, kFilm, right).find("axial stiffness EA"), std::string::npos);
  EXPECT_NE(message(kEA, {inf, 50, 11}, right).find("film length L0"), std::string::npos);
  EXPECT_NE(message(kEA, {100, -1, 11}, right).find("film width W"), std::string::npos);
  EXPECT_NE(message(kEA, {100, 50, nan}, right).find("film thickness H"), std::string::npos);
  EXPECT_NE(message(kEA, kFilm, {p[4], 99}).find("index 99 is out of range (5 elements)"),
            std::string::npos);
}
