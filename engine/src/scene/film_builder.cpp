#include "mdem/scene/film_builder.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "mdem/core/cnt.h"
#include "mdem/scene/tube_builder.h"

namespace mdem {

namespace {

int next_tube_id(const Elements& el) {
  std::int32_t id = -1;
  for (std::int32_t t : el.tube) id = std::max(id, t);
  return id + 1;
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

  TubeIndices out;
  out.reserve(spec.tubes);
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
