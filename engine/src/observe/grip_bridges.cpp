#include "mdem/observe/grip_bridges.h"

#include <cmath>
#include <cstdint>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

#include "mdem/core/elements.h"
#include "mdem/core/units.h"

namespace mdem {

namespace {

// A piece's innermost segment in each grip: the left grip's with the largest x, the right
// grip's with the smallest.
struct Piece {
  std::size_t a = 0, b = 0;
  bool left = false, right = false;
};

void require_positive(const char* what, double v) {
  if (std::isfinite(v) && v > 0) return;
  std::ostringstream m;
  m << "grip_bridges: " << what << " must be finite and > 0, got " << v;
  throw std::invalid_argument(m.str());
}

}  // namespace

GripBridges grip_bridges(const Elements& el, std::span<const std::size_t> left,
                         std::span<const std::size_t> right, double axial_stiffness,
                         const FilmGeometry& film) {
  require_positive("the axial stiffness EA (eV/nm)", axial_stiffness);
  require_positive("the film length L0 (nm)", film.length);
  require_positive("the film width W (nm)", film.width);
  require_positive("the film thickness H (nm)", film.thickness);
  std::map<std::int32_t, Piece> pieces;  // by id: the modulus summed in a fixed order
  auto mark = [&](std::span<const std::size_t> grip, bool is_left) {
    for (std::size_t i : grip) {
      if (i >= el.size())
        throw std::invalid_argument("grip_bridges: grip element index " + std::to_string(i) +
                                    " is out of range (" + std::to_string(el.size()) +
                                    " elements)");
      if (el.kind[i] != ElementKind::CntSegment || el.tube[i] < 0) continue;
      Piece& p = pieces[el.tube[i]];
      if (is_left && (!p.left || el.x[i].x() > el.x[p.a].x())) p.a = i, p.left = true;
      if (!is_left && (!p.right || el.x[i].x() < el.x[p.b].x())) p.b = i, p.right = true;
    }
  };
  mark(left, true);
  mark(right, false);
  GripBridges g;
  double stiffness = 0;  // Σ EA·L0·c²/d (eV/nm)
  for (const auto& [id, p] : pieces) {
    if (!(p.left && p.right)) continue;
    ++g.pieces;
    const Vec3 chord = el.x[p.b] - el.x[p.a];
    const double d = chord.norm();
    if (d <= 0) continue;
    const double c = std::abs(chord.x()) / d;
    stiffness += axial_stiffness * film.length * c * c / d;
  }
  g.affine_modulus = units::to_GPa(stiffness / (film.width * film.thickness));
  return g;
}

}  // namespace mdem
