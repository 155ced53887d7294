#pragma once
// The fraction of tubes in tension (tensile.md §3.5), from per-bond axial forces. Each bond names
// its tube piece (a tube as split at the generation wrap), that piece's parent (the generated
// tube), its axial force (kn·A·(gap·n), positive when stretched; the caller time-averages it, or
// passes F(ε) − F(0) for the incremental version) and whether it lies wholly inside a grip.
// Definitions and tests: docs/tensile.md.
#include <cstdint>
#include <span>

#include "mdem/core/units.h"

namespace mdem {

struct BondAxialForce {
  std::int32_t piece = -1;
  std::int32_t parent = -1;
  double force = 0;  // eV/nm, positive in tension
  bool in_grip = false;
};

struct TubeTension {
  std::size_t pieces = 0;           // pieces with at least one bond outside the grips
  std::size_t parents = 0;          // parents with at least one such bond
  double fraction_pieces = 0;       // pieces with F̄ > 0
  double fraction_parents = 0;      // parents whose bond-count-weighted F̄ > 0
  double fraction_tension = 0;      // pieces with F̄ > threshold
  double fraction_compression = 0;  // pieces with F̄ < −threshold
};

// F̄ of a piece is the mean force over its bonds not wholly inside a grip; a piece without such
// bonds is left out. A parent's F̄ is the mean of its pieces' F̄ weighted by their bond counts
// (the length weight: bonds share one rest length). Throws std::invalid_argument for a negative
// piece or parent id, a piece named with two parents, a non-finite force or threshold, or no
// bond outside the grips.
TubeTension tube_tension(std::span<const BondAxialForce> bonds, double threshold = units::nN(0.01));

}  // namespace mdem
