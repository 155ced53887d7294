#include "mdem/scene/film_builder.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

#include "mdem/core/cnt.h"
#include "mdem/scene/tube_builder.h"

namespace mdem {

namespace {

int next_tube_id(const Elements& el) {
  std::int32_t id = -1;
  for (std::int32_t t : el.tube) id = std::max(id, t);
  return id + 1;
}

// Adds one generated tube (centre, unit axis b, n segments) cut where it wraps in x or y
// (FilmSpec::periodic_split): each piece a tube of id next_piece++ with parent `parent`.
void add_wrapped_tube(Elements& el, const Vec3& centre, const Vec3& b, int n, double side,
                      std::int32_t parent, std::int32_t& next_piece, TubeIndices& out) {
  const double half = 0.5 * side;
  const Quat q = quat_from_axis(b);
  std::vector<std::size_t> piece;
  std::int32_t id = next_piece++;
  double ix_prev = 0, iy_prev = 0;
  auto close_piece = [&] {
    record_cnt_tube(el, piece, id, false, parent);
    out.push_back(std::move(piece));
    piece.clear();
  };
  for (int j = 0; j < n; ++j) {
    const Vec3 c = centre + (j - 0.5 * (n - 1)) * cnt::kSegmentLength * b;
    // Image counts along x and y: the wrapped coordinate is c − image·side, in [−side/2, side/2).
    double ix = std::floor((c.x() + half) / side), iy = std::floor((c.y() + half) / side);
    double wx = c.x() - ix * side, wy = c.y() - iy * side;
    if (wx >= half) wx -= side, ix += 1;  // rounding just below an image boundary
    if (wy >= half) wy -= side, iy += 1;
    if (j > 0 && (ix != ix_prev || iy != iy_prev)) {
      close_piece();
      id = next_piece++;
    }
    ix_prev = ix;
    iy_prev = iy;
    piece.push_back(
        el.add(cnt_segment(Vec3(wx, wy, c.z()), q, id, static_cast<int>(piece.size()))));
  }
  close_piece();
}

}  // namespace

TubeIndices add_random_film(Elements& el, const FilmSpec& spec) {
  if (!std::isfinite(spec.side) || spec.side <= 0)
    throw std::invalid_argument("film: side must be finite and > 0 nm");
  if (!std::isfinite(spec.thickness) || spec.thickness < 0)
    throw std::invalid_argument("film: thickness must be finite and >= 0 nm");
  if (spec.tubes < 1) throw std::invalid_argument("film: needs at least 1 tube");
  if (spec.segments_per_tube < 1)
    throw std::invalid_argument("film: needs at least 1 segment per tube");
  if (!(spec.max_out_of_plane_deg >= 0 && spec.max_out_of_plane_deg <= 90))
    throw std::invalid_argument("film: max_out_of_plane_deg must be in [0, 90]");

  std::mt19937_64 rng(spec.seed);
  auto uniform = [&rng](double a, double b) { return a + (b - a) * unit_interval(rng()); };

  const double half = 0.5 * spec.side;
  const double half_t = 0.5 * spec.thickness;
  const double max_z = std::sin(spec.max_out_of_plane_deg * std::numbers::pi / 180.0);
  const int n = spec.segments_per_tube;
  const double half_length = 0.5 * (n - 1) * cnt::kSegmentLength;  // centre to end segment
  int id = next_tube_id(el);
  const double tube_span = 0.5 * (n - 1) * cnt::kSegmentLength;  // h = tube_span·|s|
  if (spec.contain && tube_span * max_z > half_t) {
    // Chance that one draw of s fits: P(|s| ≤ half_t / tube_span) = half_t / (tube_span·sin a).
    const double fit = half_t / (tube_span * max_z);
    if (fit < 1e-3)
      throw std::invalid_argument(
          "film: a tube of " + std::to_string(n) + " segments fits a slab of thickness " +
          std::to_string(spec.thickness) + " nm at a tilt <= " +
          std::to_string(spec.max_out_of_plane_deg) + " deg with chance " + std::to_string(fit) +
          " per draw; contain needs >= 0.001 (thicker slab, shorter tubes or a smaller angle)");
  }

  TubeIndices out;
  out.reserve(spec.tubes);
  if (spec.contain || spec.periodic_split) {
    // tensile.md §3.1's draw order and, with periodic_split, its wrap and cut.
    std::int32_t next_piece = id + spec.tubes;
    for (int t = 0; t < spec.tubes; ++t) {
      const double xc = uniform(-half, half), yc = uniform(-half, half);
      const double phi = uniform(0.0, 2.0 * std::numbers::pi);
      double s = uniform(-max_z, max_z);
      if (spec.contain)
        while (tube_span * std::abs(s) > half_t) s = uniform(-max_z, max_z);
      const double zc = spec.contain ? uniform(-(half_t - tube_span * std::abs(s)),
                                               half_t - tube_span * std::abs(s))
                                     : uniform(-half_t, half_t);
      const double rho = std::sqrt(std::max(0.0, 1.0 - s * s));
      const Vec3 b(rho * std::cos(phi), rho * std::sin(phi), s);
      const Vec3 centre(xc, yc, zc);
      if (spec.periodic_split)
        add_wrapped_tube(el, centre, b, n, spec.side, id + t, next_piece, out);
      else
        out.push_back(add_straight_tube(el, centre - half_length * b, b, n, id + t));
    }
    return out;
  }
  for (int t = 0; t < spec.tubes; ++t) {
    // Draw order is part of the film's definition: centre x, y, z, then azimuth, then axis z.
    const Vec3 centre(uniform(-half, half), uniform(-half, half), uniform(-half_t, half_t));
    const double phi = uniform(0.0, 2.0 * std::numbers::pi);
    const double dz = uniform(-max_z, max_z);
    const double rho = std::sqrt(std::max(0.0, 1.0 - dz * dz));
    const Vec3 dir(rho * std::cos(phi), rho * std::sin(phi), dz);
    out.push_back(add_straight_tube(el, centre - half_length * dir, dir, n, id++));
  }
  return out;
}

TubeIndices add_seven_tube_bundle(Elements& el, int segments, double spacing) {
  if (segments < 1) throw std::invalid_argument("bundle: needs at least 1 segment per tube");
  if (!std::isfinite(spacing) || spacing <= 0)
    throw std::invalid_argument("bundle: spacing must be finite and > 0 nm");

  const double x0 = -0.5 * (segments - 1) * cnt::kSegmentLength;
  int id = next_tube_id(el);
  TubeIndices out;
  out.reserve(7);
  out.push_back(add_straight_tube(el, Vec3(x0, 0, 0), Vec3::UnitX(), segments, id++));
  for (int k = 1; k < 7; ++k) {
    const double a = (k - 1) * std::numbers::pi / 3.0;
    const Vec3 start(x0, spacing * std::cos(a), spacing * std::sin(a));
    out.push_back(add_straight_tube(el, start, Vec3::UnitX(), segments, id++));
  }
  return out;
}

}  // namespace mdem
