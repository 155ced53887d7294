#include "mdem/observe/pore_raster.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <stdexcept>

#include "mdem/observe/percentile.h"
#include "mdem/observe/series_checks.h"

namespace mdem {

namespace {

void check_window(const Window2D& w, double pixel, const char* where) {
  const bool finite = std::isfinite(w.x_lo) && std::isfinite(w.x_hi) && std::isfinite(w.y_lo) &&
                      std::isfinite(w.y_hi);
  if (finite && w.x_hi - w.x_lo >= pixel && w.y_hi - w.y_lo >= pixel) return;
  std::ostringstream os;
  os << where << ": window x [" << w.x_lo << ", " << w.x_hi << "], y [" << w.y_lo << ", " << w.y_hi
     << "]; it must be finite and at least one pixel (" << pixel << " nm) on each side";
  throw std::invalid_argument(os.str());
}

void check_points(std::span<const Vec3> p, const char* where, const char* what) {
  for (std::size_t i = 0; i < p.size(); ++i)
    if (!p[i].allFinite()) {
      std::ostringstream os;
      os << where << ": " << what << " " << i << " is not finite; every " << what << " must be";
      throw std::invalid_argument(os.str());
    }
}

// Squared distance from q to the segment [a, b] (2D).
double distance2_to_segment(double qx, double qy, double ax, double ay, double bx, double by) {
  const double dx = bx - ax, dy = by - ay;
  const double len2 = dx * dx + dy * dy;
  double u = len2 > 0 ? ((qx - ax) * dx + (qy - ay) * dy) / len2 : 0.0;
  u = std::clamp(u, 0.0, 1.0);
  const double ex = qx - (ax + u * dx), ey = qy - (ay + u * dy);
  return ex * ex + ey * ey;
}

// Marks material every pixel of r whose centre satisfies `inside`, scanning only the pixels of the
// box [x0, x1] × [y0, y1].
void mark_box(Raster& r, double x0, double x1, double y0, double y1,
              const std::function<bool(double, double)>& inside) {
  const double p = r.pixel;
  // Index of the pixel whose centre is nearest v, clamped to [−1, n] (before the cast, so a far
  // coordinate cannot overflow); one pixel of slack each side keeps the box conservative.
  const auto index = [p](double v, double lo, int n) {
    return static_cast<long>(std::clamp(std::round((v - lo) / p - 0.5), -1.0, double(n)));
  };
  const long ix0 = std::max(0L, index(x0, r.window.x_lo, r.nx) - 1);
  const long ix1 = std::min<long>(r.nx - 1, index(x1, r.window.x_lo, r.nx) + 1);
  const long iy0 = std::max(0L, index(y0, r.window.y_lo, r.ny) - 1);
  const long iy1 = std::min<long>(r.ny - 1, index(y1, r.window.y_lo, r.ny) + 1);
  for (long iy = iy0; iy <= iy1; ++iy) {
    const double cy = r.window.y_lo + (static_cast<double>(iy) + 0.5) * p;
    for (long ix = ix0; ix <= ix1; ++ix) {
      const double cx = r.window.x_lo + (static_cast<double>(ix) + 0.5) * p;
      if (inside(cx, cy)) r.material[static_cast<std::size_t>(iy * r.nx + ix)] = 1;
    }
  }
}

}  // namespace

Window2D percentile_window(std::span<const Vec3> centres, double lo_pct, double hi_pct,
                           double shrink) {
  if (centres.empty())
    throw std::invalid_argument("percentile_window: no centres; the window needs at least one");
  check_points(centres, "percentile_window", "centre");
  if (!(lo_pct >= 0 && lo_pct < hi_pct && hi_pct <= 100 && shrink >= 0 && shrink < 0.5))
    throw std::invalid_argument(
        "percentile_window: needs 0 <= lo_pct < hi_pct <= 100 and 0 <= shrink < 0.5");
  std::vector<double> x, y;
  for (const Vec3& c : centres) {
    x.push_back(c.x());
    y.push_back(c.y());
  }
  Window2D w{percentile(x, lo_pct, "centre x"), percentile(x, hi_pct, "centre x"),
             percentile(y, lo_pct, "centre y"), percentile(y, hi_pct, "centre y")};
  const double sx = shrink * (w.x_hi - w.x_lo), sy = shrink * (w.y_hi - w.y_lo);
  w.x_lo += sx;
  w.x_hi -= sx;
  w.y_lo += sy;
  w.y_hi -= sy;
  if (!(w.x_hi > w.x_lo && w.y_hi > w.y_lo))
    throw std::invalid_argument(
        "percentile_window: the centres' percentile window has no area (all on a line)");
  return w;
}

ProjectedFrame projected_frame(const Elements& el) {
  ProjectedFrame f;
  for (std::size_t i = 0; i < el.size(); ++i) {
    if (el.kind[i] == ElementKind::CntSegment) {
      f.segment_centre.push_back(el.x[i]);
      f.segment_axis.push_back(el.axis(i));
    } else if (el.kind[i] == ElementKind::Nanoparticle) {
      f.np_centre.push_back(el.x[i]);
      f.np_radius.push_back(el.radius[i]);
    }
  }
  return f;
}

Raster rasterize(const ProjectedFrame& frame, const Window2D& window, const RasterSettings& s) {
  constexpr const char* kWhere = "rasterize";
  require_positive(s.pixel, kWhere, "the pixel size");
  require_positive(s.footprint, kWhere, "the footprint r_d");
  require_positive(s.half_length, kWhere, "the segment half length");
  check_window(window, s.pixel, kWhere);
  if (frame.segment_centre.size() != frame.segment_axis.size() ||
      frame.np_centre.size() != frame.np_radius.size())
    throw std::invalid_argument(
        "rasterize: segment centres and axes, and NP centres and radii, must pair up one to one");
  check_points(frame.segment_centre, kWhere, "segment centre");
  check_points(frame.segment_axis, kWhere, "segment axis");
  check_points(frame.np_centre, kWhere, "NP centre");
  for (double rn : frame.np_radius) require_positive(rn, kWhere, "an NP radius");
  Raster r;
  r.window = window;
  r.pixel = s.pixel;
  r.nx = static_cast<int>(std::floor((window.x_hi - window.x_lo) / s.pixel));
  r.ny = static_cast<int>(std::floor((window.y_hi - window.y_lo) / s.pixel));
  r.material.assign(static_cast<std::size_t>(r.nx) * static_cast<std::size_t>(r.ny), 0);
  const double rd = s.footprint, rd2 = rd * rd;
  for (std::size_t k = 0; k < frame.segment_centre.size(); ++k) {
    const Vec3 a = frame.segment_centre[k] - s.half_length * frame.segment_axis[k];
    const Vec3 b = frame.segment_centre[k] + s.half_length * frame.segment_axis[k];
    mark_box(r, std::min(a.x(), b.x()) - rd, std::max(a.x(), b.x()) + rd,
             std::min(a.y(), b.y()) - rd, std::max(a.y(), b.y()) + rd, [&](double x, double y) {
               return distance2_to_segment(x, y, a.x(), a.y(), b.x(), b.y()) <= rd2;
             });
  }
  for (std::size_t k = 0; k < frame.np_centre.size(); ++k) {
    const Vec3& c = frame.np_centre[k];
    const double rn = frame.np_radius[k];
    mark_box(r, c.x() - rn, c.x() + rn, c.y() - rn, c.y() + rn, [&](double x, double y) {
      return (x - c.x()) * (x - c.x()) + (y - c.y()) * (y - c.y()) <= rn * rn;
    });
  }
  return r;
}

PoreStats pore_stats(const Raster& raster, double large_area) {
  require_positive(large_area, "pore_stats", "the large-pore area");
  const int nx = raster.nx, ny = raster.ny;
  if (nx <= 0 || ny <= 0 ||
      raster.material.size() != static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny))
    throw std::invalid_argument("pore_stats: the raster's size does not match its nx × ny pixels");
  PoreStats st;
  const double pixel_area = raster.pixel * raster.pixel;
  std::vector<std::uint8_t> seen(raster.material);  // 1 = material or already in a component
  std::vector<int> stack;
  long void_pixels = 0;
  for (int start = 0; start < nx * ny; ++start) {
    if (seen[start]) continue;
    // Flood one 4-connected void component.
    long count = 0;
    bool edge = false;
    seen[start] = 1;
    stack.assign(1, start);
    while (!stack.empty()) {
      const int p = stack.back();
      stack.pop_back();
      ++count;
      const int ix = p % nx, iy = p / nx;
      edge = edge || ix == 0 || iy == 0 || ix == nx - 1 || iy == ny - 1;
      const auto visit = [&](int q) {
        if (!seen[q]) {
          seen[q] = 1;
          stack.push_back(q);
        }
      };
      if (ix > 0) visit(p - 1);
      if (ix < nx - 1) visit(p + 1);
      if (iy > 0) visit(p - nx);
      if (iy < ny - 1) visit(p + nx);
    }
    void_pixels += count;
    if (edge) {
      ++st.edge_discarded;
      continue;
    }
    st.areas.push_back(static_cast<double>(count) * pixel_area);
  }
  std::sort(st.areas.begin(), st.areas.end(), std::greater<>());
  double sum = 0, sum2 = 0;
  for (double a : st.areas) {
    sum += a;
    sum2 += a * a;
    st.large += a > large_area;
    if (a < kPoreBinLower[0]) {
      ++st.below_first_bin;
      continue;
    }
    const auto bin =
        std::upper_bound(kPoreBinLower.begin(), kPoreBinLower.end(), a) - kPoreBinLower.begin() - 1;
    ++st.histogram[static_cast<std::size_t>(bin)];
  }
  st.weighted_mean_area = sum > 0 ? sum2 / sum : 0.0;
  st.void_fraction = static_cast<double>(void_pixels) / (static_cast<double>(nx) * ny);
  return st;
}

}  // namespace mdem
