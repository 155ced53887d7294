#include "mdem/core/domain.h"

#include <sstream>
#include <stdexcept>

namespace mdem {

Domain::Domain(const Vec3& lo, const Vec3& hi, std::array<bool, 3> periodic)
    : lo_(lo), hi_(hi), periodic_(periodic) {
  static constexpr char kAxis[] = "xyz";
  for (int a = 0; a < 3; ++a) {
    if (!periodic_[a]) continue;
    if (!std::isfinite(lo[a]) || !std::isfinite(hi[a]) || !(hi[a] > lo[a])) {
      std::ostringstream m;
      m << "domain: periodic axis " << kAxis[a]
        << " needs finite corners with hi > lo, got lo = " << lo[a] << " nm, hi = " << hi[a]
        << " nm";
      throw std::invalid_argument(m.str());
    }
    length_[a] = hi[a] - lo[a];
    inv_length_[a] = 1.0 / length_[a];
    any_periodic_ = true;
  }
}

std::string Domain::check_reach(double reach) const {
  static constexpr char kAxis[] = "xyz";
  for (int a = 0; a < 3; ++a) {
    if (!periodic_[a] || length_[a] >= 2.0 * reach) continue;
    std::ostringstream m;
    m << "periodic axis " << kAxis[a] << " is " << length_[a]
      << " nm long, shorter than twice the pair search reach (cutoff + skin = " << reach
      << " nm): the box must be at least " << 2.0 * reach
      << " nm along every periodic axis (or use a smaller skin)";
    return m.str();
  }
  return {};
}

}  // namespace mdem
