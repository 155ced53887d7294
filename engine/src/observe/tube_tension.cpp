#include "mdem/observe/tube_tension.h"

#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

namespace mdem {

namespace {

struct Sum {
  double force = 0;
  std::size_t bonds = 0;
  std::int32_t parent = -1;
  double mean() const { return force / static_cast<double>(bonds); }
};

}  // namespace

TubeTension tube_tension(std::span<const BondAxialForce> bonds, double threshold) {
  if (!(std::isfinite(threshold) && threshold >= 0))
    throw std::invalid_argument("tube_tension: the threshold must be finite and not negative");
  std::map<std::int32_t, Sum> pieces;
  for (std::size_t k = 0; k < bonds.size(); ++k) {
    const BondAxialForce& b = bonds[k];
    if (b.piece < 0 || b.parent < 0 || !std::isfinite(b.force)) {
      std::ostringstream os;
      os << "tube_tension: bond " << k << " has piece " << b.piece << ", parent " << b.parent
         << " and force " << b.force << "; ids must be >= 0 and the force finite";
      throw std::invalid_argument(os.str());
    }
    Sum& s = pieces[b.piece];
    if (s.parent >= 0 && s.parent != b.parent) {
      std::ostringstream os;
      os << "tube_tension: bond " << k << " names piece " << b.piece << " with parent " << b.parent
         << ", but an earlier bond gave it parent " << s.parent << "; a piece has one parent";
      throw std::invalid_argument(os.str());
    }
    s.parent = b.parent;
    if (b.in_grip) continue;
    s.force += b.force;
    ++s.bonds;
  }
  TubeTension r;
  std::map<std::int32_t, Sum> parents;  // Σ over pieces of bonds·F̄ = Σ of their forces
  std::size_t up = 0, tension = 0, compression = 0;
  for (const auto& [id, s] : pieces) {
    if (s.bonds == 0) continue;  // wholly inside a grip
    ++r.pieces;
    const double f = s.mean();
    up += f > 0;
    tension += f > threshold;
    compression += f < -threshold;
    Sum& p = parents[s.parent];
    p.force += s.force;
    p.bonds += s.bonds;
  }
  if (r.pieces == 0)
    throw std::invalid_argument(
        "tube_tension: every bond lies inside a grip; at least one outside is needed");
  std::size_t parents_up = 0;
  for (const auto& [id, p] : parents) parents_up += p.mean() > 0;
  r.parents = parents.size();
  const double np = static_cast<double>(r.pieces);
  r.fraction_pieces = static_cast<double>(up) / np;
  r.fraction_tension = static_cast<double>(tension) / np;
  r.fraction_compression = static_cast<double>(compression) / np;
  r.fraction_parents = static_cast<double>(parents_up) / static_cast<double>(r.parents);
  return r;
}

}  // namespace mdem
