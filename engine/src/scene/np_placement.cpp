#include "mdem/scene/np_placement.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

#include "mdem/core/cnt.h"
#include "mdem/core/np.h"
#include "mdem/force/contact/np_np_contact.h"
#include "mdem/scene/film_builder.h"
#include "mdem/scene/nanoparticle.h"

namespace mdem {

namespace {

// A 2D cell grid over x, y (the film is thin: a column holds the whole thickness).
class ColumnGrid {
 public:
  ColumnGrid(double lo, double hi, double cell)
      : lo_(lo),
        cell_(cell),
        n_(std::max(1, static_cast<int>(std::ceil((hi - lo) / cell)))),
        cells_(static_cast<std::size_t>(n_) * n_) {}
  // Whether x, y lies within one cell of the grid (farther points cannot be neighbours).
  bool near(const Vec3& x) const {
    const double hi = lo_ + n_ * cell_;
    return x.x() >= lo_ - cell_ && x.x() < hi + cell_ && x.y() >= lo_ - cell_ && x.y() < hi + cell_;
  }
  void insert(const Vec3& x, std::uint32_t id) { cells_[cell(ix(x.x()), ix(x.y()))].push_back(id); }
  // Calls f(id) for every id in the 3×3 block of columns around x.
  template <class F>
  bool all_around(const Vec3& x, F&& f) const {
    const int cx = ix(x.x()), cy = ix(x.y());
    for (int a = std::max(0, cx - 1); a <= std::min(n_ - 1, cx + 1); ++a)
      for (int b = std::max(0, cy - 1); b <= std::min(n_ - 1, cy + 1); ++b)
        for (std::uint32_t id : cells_[cell(a, b)])
          if (!f(id)) return false;
    return true;
  }

 private:
  int ix(double c) const {
    return std::clamp(static_cast<int>(std::floor((c - lo_) / cell_)), 0, n_ - 1);
  }
  std::size_t cell(int a, int b) const { return static_cast<std::size_t>(a) * n_ + b; }
  double lo_, cell_;
  int n_;
  std::vector<std::vector<std::uint32_t>> cells_;
};

[[noreturn]] void refuse(const std::string& what) {
  throw std::invalid_argument("nanoparticles: " + what);
}

}  // namespace

std::mt19937_64 np_stream(std::uint64_t seed) {
  std::seed_seq s{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                  static_cast<std::uint32_t>('n'), static_cast<std::uint32_t>('p')};
  return std::mt19937_64(s);
}

double np_min_spacing() { return NpNpKernel().equilibrium_distance(); }

double np_min_axis_distance() { return np::kRadius + cnt::kRadius; }

double distance_to_segment_axis(const Vec3& p, const Vec3& c, const Vec3& b) {
  const double half = 0.5 * cnt::kSegmentLength;
  const double t = std::clamp((p - c).dot(b), -half, half);
  return (p - c - t * b).norm();
}

NpPlacement place_nanoparticles(Elements& el, const NpPlacementSpec& spec) {
  if (spec.count < 0 || spec.count > 10'000'000)
    refuse("count must be in [0, 10000000], got " + std::to_string(spec.count));
  if (!std::isfinite(spec.side) || !(spec.side > 0))
    refuse("side must be finite and > 0 nm, got " + std::to_string(spec.side));
  if (!std::isfinite(spec.thickness) || !(spec.thickness > 0))
    refuse("thickness must be finite and > 0 nm, got " + std::to_string(spec.thickness));
  const NpCntKernel contact(spec.contact);
  const double spacing = np_min_spacing();
  const double axis_gap = np_min_axis_distance();
  NpPlacement out;
  if (spec.count == 0) return out;

  // Disjoint balls of diameter `spacing` about the centres lie in the slab widened by spacing/2
  // on every side: no more than 6V/(π s³) of them fit, whatever the tubes.
  const double s = spacing;
  const double volume = (spec.side + s) * (spec.side + s) * (spec.thickness + s);
  const double most = 6.0 * volume / (std::numbers::pi * s * s * s);
  if (spec.count > most) {
    std::ostringstream m;
    m << spec.count << " cannot fit: NP centres at least " << s << " nm apart in a " << spec.side
      << " x " << spec.side << " x " << spec.thickness << " nm film number at most "
      << static_cast<long>(most) << " (placed 0)";
    refuse(m.str());
  }

  const double half = 0.5 * spec.side, half_t = 0.5 * spec.thickness;
  const double reach = std::max({spacing, contact.cutoff(), axis_gap + 0.5 * cnt::kSegmentLength});
  ColumnGrid segs(-half, half, reach), nps(-half, half, reach);
  std::vector<Vec3> np_x;  // NPs already in el, then the accepted ones
  for (std::size_t i = 0; i < el.size(); ++i) {
    if (!segs.near(el.x[i])) continue;
    if (el.kind[i] == ElementKind::CntSegment) {
      segs.insert(el.x[i], static_cast<std::uint32_t>(i));
    } else if (el.kind[i] == ElementKind::Nanoparticle) {
      nps.insert(el.x[i], static_cast<std::uint32_t>(np_x.size()));
      np_x.push_back(el.x[i]);
    }
  }
  const std::size_t first_new = np_x.size();
  std::vector<Vec3> axes(el.size());
  for (std::size_t i = 0; i < el.size(); ++i)
    if (el.kind[i] == ElementKind::CntSegment) axes[i] = el.axis(i);

  std::mt19937_64 rng = np_stream(spec.seed);
  auto uniform = [&rng](double a, double b) { return a + (b - a) * unit_interval(rng()); };
  const long cap = 1000L * spec.count;
  const double spacing2 = spacing * spacing;
  int placed = 0;
  while (placed < spec.count) {
    if (out.candidates >= cap) {
      std::ostringstream m;
      m << "placed " << placed << " of " << spec.count << " after " << out.candidates
        << " candidates (the cap is 1000 per NP asked for); the film has no room for more: ask "
           "for fewer";
      refuse(m.str());
    }
    ++out.candidates;
    const double x = uniform(-half, half), y = uniform(-half, half);
    const Vec3 p(x, y, uniform(-half_t, half_t));
    // (a) NP spacing, (b) clear of every segment's axis, then (c) the NP–CNT energy.
    if (!nps.all_around(p,
                        [&](std::uint32_t k) { return (np_x[k] - p).squaredNorm() >= spacing2; }))
      continue;
    if (!segs.all_around(p, [&](std::uint32_t i) {
          return distance_to_segment_axis(p, el.x[i], axes[i]) >= axis_gap;
        }))
      continue;
    double energy = 0;
    segs.all_around(p, [&](std::uint32_t i) {
      energy += contact.evaluate(p, el.x[i], axes[i]).energy;
      return true;
    });
    if (energy > 0) continue;
    nps.insert(p, static_cast<std::uint32_t>(np_x.size()));
    np_x.push_back(p);
    ++placed;
  }
  out.indices.reserve(spec.count);
  for (std::size_t k = first_new; k < np_x.size(); ++k)
    out.indices.push_back(el.add(nanoparticle(np_x[k])));
  return out;
}

}  // namespace mdem
