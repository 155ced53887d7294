#include "mdem/observe/percentile.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/observe/series_checks.h"

namespace mdem {

double percentile(std::span<const double> values, double p, std::string_view what) {
  require_finite_series(values, "percentile", what);
  if (!(p >= 0 && p <= 100)) {
    std::ostringstream os;
    os << "percentile: p = " << p << " for " << what << "; p must lie in [0, 100]";
    throw std::invalid_argument(os.str());
  }
  std::vector<double> v(values.begin(), values.end());
  const double h = static_cast<double>(v.size() - 1) * p / 100.0;
  const std::size_t k = std::min(static_cast<std::size_t>(std::floor(h)), v.size() - 1);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  const double lo = v[k];
  if (k + 1 >= v.size()) return lo;
  const double hi = *std::min_element(v.begin() + static_cast<std::ptrdiff_t>(k) + 1, v.end());
  return lo + (h - static_cast<double>(k)) * (hi - lo);
}

}  // namespace mdem
