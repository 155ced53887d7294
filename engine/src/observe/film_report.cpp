#include "mdem/observe/film_report.h"

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

#include "mdem/core/cnt.h"
#include "mdem/core/units.h"

namespace mdem {

FilmReport film_report(const Elements& el, double side, double thickness) {
  if (!std::isfinite(side) || !(side > 0))
    throw std::invalid_argument("film report: side must be finite and > 0 nm, got " +
                                std::to_string(side));
  if (!std::isfinite(thickness) || !(thickness > 0))
    throw std::invalid_argument("film report: thickness must be finite and > 0 nm, got " +
                                std::to_string(thickness));
  FilmReport r;
  double mass = 0, mass_cnt = 0;  // eV·ps²/nm²
  for (std::size_t i = 0; i < el.size(); ++i) {
    mass += el.mass[i];
    if (el.kind[i] == ElementKind::CntSegment) {
      ++r.segments;
      mass_cnt += el.mass[i];
    } else if (el.kind[i] == ElementKind::Nanoparticle) {
      ++r.nanoparticles;
    }
  }
  std::set<std::int32_t> parents;
  std::size_t in_pieces = 0;
  for (const Chain& c : el.topology.chains()) {
    ++r.pieces;
    in_pieces += c.tags.size();
    if (c.tags.size() < 5) ++r.short_pieces;
    parents.insert(c.parent >= 0 ? c.parent : c.tube);
  }
  r.tubes = parents.size();
  if (r.pieces > 0)
    r.mean_piece_length = static_cast<double>(in_pieces) / r.pieces * cnt::kSegmentLength;
  const double volume = side * side * thickness;  // nm³
  const double per_g_cm3 = 1.0 / (units::kAmu * units::kGramPerCm3InAmuPerNm3 * volume);
  r.density = mass * per_g_cm3;
  r.density_pristine = mass_cnt * per_g_cm3;
  r.porosity = 1.0 - r.density_pristine / kFilmReferenceDensity;
  return r;
}

}  // namespace mdem
