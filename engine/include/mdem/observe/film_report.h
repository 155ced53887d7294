#pragma once
// What a generated film is made of, against Table 5-1 (tensile.md §1.1, §3.1): element counts,
// tubes and their pieces, density in the nominal box and porosity.
#include <cstddef>

#include "mdem/core/elements.h"

namespace mdem {

struct FilmReport {
  std::size_t segments = 0;
  std::size_t nanoparticles = 0;
  std::size_t tubes = 0;   // generated tubes: distinct parents (a chain without parent is its own)
  std::size_t pieces = 0;  // chains (tubes as cut where they wrapped)
  std::size_t short_pieces = 0;  // pieces of fewer than 5 segments
  double mean_piece_length = 0;  // nm: segments per piece × T
  double density = 0;            // g/cm³: mass of all elements in side × side × thickness
  double density_pristine = 0;   // g/cm³: the CNT segments' mass alone
  // 1 − density_pristine / 0.85 g/cm³ (tubes as solid cylinders of radius 1.10 nm; the NPs are
  // left out), the definition that reproduces Table 5-1's three porosities (tensile.md §1.1).
  double porosity = 0;
};

inline constexpr double kFilmReferenceDensity = 0.85;  // g/cm³

// Counts over `el` (its chains from el.topology); masses from el.mass. Throws
// std::invalid_argument unless side and thickness are finite and > 0.
FilmReport film_report(const Elements& el, double side, double thickness);

}  // namespace mdem
