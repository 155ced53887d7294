#pragma once
// The tube pieces a tensile test's grips both hold (docs/tensile.md, "What differs"). Such a
// piece is stretched by the grips themselves, not through junctions with other tubes. Between its
// innermost segments a (in the left grip) and b (in the right), a chord of length d at angle φ
// to x (c = cos φ), the grips' relative x displacement L0·ε lengthens the chord by L0·ε·c; taut
// and straight, the piece carries F = EA·L0·ε·c/d along it, F·c along x, so that alone
//   E_b = Σ EA·L0·c² / (d·W·H)
// over the pieces (L0 the nominal film length, W, H its width and thickness, as the stress's).
// A single straight tube along x gives kn·A·L0/(n·W·H), n the free bonds: the modulus the test
// measures for it (tests/test_tensile_protocol.cpp). A wavy piece must straighten before it pulls,
// so E_b bounds what the pieces carry from above.
#include <cstddef>
#include <span>

namespace mdem {

struct Elements;

struct GripBridges {
  std::size_t pieces = 0;     // tube pieces with a segment in each grip
  double affine_modulus = 0;  // E_b (GPa)
};

struct FilmGeometry {
  double length = 0;     // L0 (nm), the strain's reference length
  double width = 0;      // W (nm)
  double thickness = 0;  // H (nm)
};

// left, right: the grips' element indices (non-CNT elements in them are ignored). EA (eV/nm):
// the tube's axial stiffness (kn·A times the bond's rest length). Throws std::invalid_argument
// for an EA, L0, W or H that is not finite and > 0, or an index out of range.
GripBridges grip_bridges(const Elements& el, std::span<const std::size_t> left,
                         std::span<const std::size_t> right, double axial_stiffness,
                         const FilmGeometry& film);

}  // namespace mdem
