#include "mdem/observe/width_profile.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "mdem/observe/percentile.h"
#include "mdem/observe/series_checks.h"

namespace mdem {

namespace {

void check_positions(std::span<const Vec3> positions, const char* where) {
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (!positions[i].allFinite()) {
      std::ostringstream os;
      os << where << ": position " << i << " is not finite; every position must be";
      throw std::invalid_argument(os.str());
    }
}

Width width_of(const std::vector<double>& y, const WidthSettings& s, const char* what) {
  Width w;
  w.elements = y.size();
  w.width = percentile(y, s.hi_percentile, what) - percentile(y, s.lo_percentile, what);
  const auto [lo, hi] = std::minmax_element(y.begin(), y.end());
  w.extent = *hi - *lo;
  return w;
}

}  // namespace

Width mid_width(std::span<const Vec3> positions, double x_mid, double half_slab,
                const WidthSettings& s) {
  check_positions(positions, "mid_width");
  require_positive(half_slab, "mid_width", "the slab's half width");
  if (!std::isfinite(x_mid)) throw std::invalid_argument("mid_width: x_mid must be finite");
  std::vector<double> y;
  for (const Vec3& p : positions)
    if (std::abs(p.x() - x_mid) < half_slab) y.push_back(p.y());
  if (y.empty()) {
    std::ostringstream os;
    os << "mid_width: no element has |x - " << x_mid << "| < " << half_slab
       << "; the mid slab must hold at least one";
    throw std::invalid_argument(os.str());
  }
  return width_of(y, s, "mid-slab y");
}

double shrinkage(double w, double w0) {
  require_positive(w0, "shrinkage", "the initial width w0");
  if (!std::isfinite(w)) throw std::invalid_argument("shrinkage: the width w must be finite");
  return 1.0 - w / w0;
}

WidthProfile width_profile(std::span<const Vec3> positions, double x_lo, double x_hi, double bin,
                           const WidthSettings& s) {
  check_positions(positions, "width_profile");
  require_positive(bin, "width_profile", "the bin length");
  if (!(std::isfinite(x_lo) && std::isfinite(x_hi) && x_lo < x_hi)) {
    std::ostringstream os;
    os << "width_profile: range [" << x_lo << ", " << x_hi
       << "]; it must be finite with x_lo < x_hi";
    throw std::invalid_argument(os.str());
  }
  const std::size_t n = static_cast<std::size_t>(std::ceil((x_hi - x_lo) / bin));
  std::vector<std::vector<double>> y(n);
  for (const Vec3& p : positions) {
    if (!(p.x() >= x_lo && p.x() < x_hi)) continue;
    const std::size_t k = std::min(n - 1, static_cast<std::size_t>((p.x() - x_lo) / bin));
    y[k].push_back(p.y());
  }
  WidthProfile out;
  bool found = false;
  for (std::size_t k = 0; k < n; ++k) {
    WidthBin b;
    b.x_lo = x_lo + static_cast<double>(k) * bin;
    b.x_hi = std::min(x_hi, b.x_lo + bin);
    if (!y[k].empty()) b.width = width_of(y[k], s, "bin y");
    if (y[k].size() >= 2 && (!found || b.width.width < out.min_width)) {
      out.min_width = b.width.width;
      out.min_bin = k;
      found = true;
    }
    out.bins.push_back(b);
  }
  if (!found)
    throw std::invalid_argument(
        "width_profile: no bin holds two elements; the profile needs at least one such bin");
  return out;
}

}  // namespace mdem
