#include "mdem/observe/rope_observables.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <unordered_map>

#include "mdem/core/cnt.h"
#include "mdem/io/state_io.h"
#include "mdem/protocol/twist_protocol.h"

namespace mdem {
namespace {

double point_segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double L2 = ab.squaredNorm();
  const double t = L2 > 0 ? std::clamp((p - a).dot(ab) / L2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

double point_polyline_distance(const Vec3& p, const std::vector<Vec3>& line) {
  if (line.size() == 1) return (p - line[0]).norm();
  double d = INFINITY;
  for (std::size_t k = 0; k + 1 < line.size(); ++k)
    d = std::min(d, point_segment_distance(p, line[k], line[k + 1]));
  return d;
}

// Where the tube at a site crosses the plane h = 0 (h the signed distance along the axis), found
// from the middle of the tube outward; the index of the segment just below the crossing, or −1.
long crossing_index(const std::vector<long>& seg, const std::vector<double>& h) {
  const long S = static_cast<long>(seg.size());
  for (long off = 0; off < S; ++off)
    for (long k : {S / 2 - 1 - off, S / 2 - 1 + off}) {
      if (k < 0 || k + 1 >= S || seg[k] < 0 || seg[k + 1] < 0) continue;
      const double h0 = h[seg[k]], h1 = h[seg[k + 1]];
      if ((h0 <= 0 && h1 > 0) || (h0 >= 0 && h1 < 0)) return k;
    }
  return -1;
}

struct UnionFind {
  std::vector<int> parent;
  explicit UnionFind(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int a) { return parent[a] == a ? a : parent[a] = find(parent[a]); }
  void join(int a, int b) { parent[find(a)] = find(b); }
};

// Groups of tubes whose segment centres come within `reach` of each other (cell-list search).
int contact_clusters(const Elements& el, const Rope& rope, double reach) {
  UnionFind uf(static_cast<int>(rope.tubes.size()));
  std::vector<int> tube_of(el.size(), -1);
  for (std::size_t t = 0; t < rope.tubes.size(); ++t)
    for (std::size_t e : rope.tubes[t].elements) tube_of[e] = static_cast<int>(t);
  auto key = [&](const Vec3& x, int dx, int dy, int dz) {
    const auto c = [&](double v, int o) {
      return static_cast<long long>(std::floor(v / reach)) + o;
    };
    return ((c(x.x(), dx) & 0x1FFFFF) << 42) | ((c(x.y(), dy) & 0x1FFFFF) << 21) |
           (c(x.z(), dz) & 0x1FFFFF);
  };
  std::unordered_map<long long, std::vector<std::size_t>> cells;
  for (std::size_t i = 0; i < el.size(); ++i)
    if (tube_of[i] >= 0) cells[key(el.x[i], 0, 0, 0)].push_back(i);
  const double r2 = reach * reach;
  for (std::size_t i = 0; i < el.size(); ++i) {
    if (tube_of[i] < 0) continue;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto it = cells.find(key(el.x[i], dx, dy, dz));
          if (it == cells.end()) continue;
          for (std::size_t j : it->second)
            if (tube_of[j] != tube_of[i] && (el.x[i] - el.x[j]).squaredNorm() < r2)
              uf.join(tube_of[i], tube_of[j]);
        }
  }
  int groups = 0;
  for (std::size_t t = 0; t < rope.tubes.size(); ++t)
    if (uf.find(static_cast<int>(t)) == static_cast<int>(t)) ++groups;
  return groups;
}

}  // namespace

RopeAxis rope_axis(const Elements& el, const Rope&) {
  const Vec3 a = mass_centroid(el, el.group_indices(kRopeGripA)),
             b = mass_centroid(el, el.group_indices(kRopeGripB));
  RopeAxis ax;
  ax.origin = 0.5 * (a + b);
  ax.length = (b - a).norm();
  if (ax.length > 0) ax.dir = (b - a) / ax.length;
  return ax;
}

double charge_neighbor_distance(double spacing) { return 0.5 * (1.0 + std::sqrt(3.0)) * spacing; }

SectionCharge topological_charge(const std::vector<Vec3>& centres,
                                 const std::vector<std::vector<Vec3>>& tubes,
                                 const std::vector<bool>& internal, double neighbor_distance) {
  SectionCharge out;
  const std::size_t n = centres.size();
  out.coordination.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j)
      if (j != i && !tubes[j].empty() &&
          point_polyline_distance(centres[i], tubes[j]) < neighbor_distance)
        ++out.coordination[i];
    if (internal[i]) out.charge += 6 - out.coordination[i];
  }
  return out;
}

SectionCharge rope_topological_charge(const Elements& el, const Rope& rope, const RopeAxis& axis) {
  std::vector<double> h(el.size(), 0.0);
  for (std::size_t i = 0; i < el.size(); ++i) h[i] = (el.x[i] - axis.origin).dot(axis.dir);
  // Polylines reach this many segments either side of the crossing: about ±8 nm, enough to find
  // the closest approach of two tubes tilted by up to ~75°, local enough to ignore far contacts.
  const long window = 6;
  std::vector<Vec3> centres;
  std::vector<std::vector<Vec3>> lines;
  std::vector<bool> internal;
  for (std::size_t s = 0; s < rope.site_elements.size(); ++s) {
    const auto& seg = rope.site_elements[s];
    const long k = crossing_index(seg, h);
    if (k < 0) continue;
    const double h0 = h[seg[k]], h1 = h[seg[k + 1]];
    const double t = h0 == h1 ? 0.5 : h0 / (h0 - h1);
    centres.push_back(el.x[seg[k]] + t * (el.x[seg[k + 1]] - el.x[seg[k]]));
    std::vector<Vec3> line;
    for (long j = k; j >= std::max(0L, k - window) && seg[j] >= 0; --j)
      line.insert(line.begin(), el.x[seg[j]]);
    for (long j = k + 1; j < static_cast<long>(seg.size()) && j <= k + 1 + window && seg[j] >= 0;
         ++j)
      line.push_back(el.x[seg[j]]);
    lines.push_back(std::move(line));
    internal.push_back(rope.internal[s]);
  }
  return topological_charge(centres, lines, internal,
                            charge_neighbor_distance(rope.lattice.spacing));
}

std::string_view morphology_name(Morphology m) {
  switch (m) {
    case Morphology::Straight:
      return "straight";
    case Morphology::Spindle:
      return "spindle";
    case Morphology::BirdCage:
      return "bird cage";
    case Morphology::Helix:
      return "helix";
    case Morphology::Separated:
      return "separated";
  }
  return "?";
}

RopeShape rope_shape(const Elements& el, const Rope& rope, const RopeAxis& axis) {
  RopeShape out;
  const double quarter = 0.25 * axis.length, half = 0.5 * axis.length;
  auto h_of = [&](std::size_t i) { return (el.x[i] - axis.origin).dot(axis.dir); };
  auto r_of = [&](std::size_t i) { return perpendicular(el.x[i] - axis.origin, axis.dir); };

  // Twist angle: tilt of the outer tubes' chords over the central half.
  double sum = 0;
  long count = 0;
  for (int s : rope.outer_sites) {
    const auto& seg = rope.site_elements[s];
    for (std::size_t k = 0; k + 1 < seg.size(); ++k) {
      if (seg[k] < 0 || seg[k + 1] < 0) continue;
      if (std::abs(h_of(seg[k])) > quarter || std::abs(h_of(seg[k + 1])) > quarter) continue;
      const Vec3 t = el.x[seg[k + 1]] - el.x[seg[k]];
      sum += std::acos(std::min(1.0, std::abs(t.dot(axis.dir)) / t.norm()));
      ++count;
    }
  }
  out.twist_angle_deg = count ? sum / count * 180.0 / std::numbers::pi : 0.0;

  // Cross-sections two segments thick: centroid (local axis), radius and empty core.
  const double bin = 2.0 * cnt::kSegmentLength;
  const int nbins = std::max(1, static_cast<int>(std::ceil(axis.length / bin)));
  std::vector<Vec3> csum(nbins, Vec3::Zero());
  std::vector<int> ccount(nbins, 0);
  std::vector<std::vector<std::size_t>> members(nbins);
  for (const RopeTube& t : rope.tubes)
    for (std::size_t i : t.elements) {
      const double h = h_of(i);
      if (std::abs(h) <= quarter) out.radius = std::max(out.radius, r_of(i).norm());
      if (std::abs(h) > half) continue;
      const int b = std::clamp(static_cast<int>((h + half) / bin), 0, nbins - 1);
      csum[b] += el.x[i];
      ++ccount[b];
      members[b].push_back(i);
    }
  for (int b = 0; b < nbins; ++b) {
    if (ccount[b] < 3) continue;
    const Vec3 c = csum[b] / ccount[b];
    out.axis_deviation =
        std::max(out.axis_deviation, perpendicular(c - axis.origin, axis.dir).norm());
    const double hc = (c - axis.origin).dot(axis.dir);
    if (std::abs(hc) > quarter) continue;
    double empty = INFINITY;
    for (std::size_t i : members[b])
      empty = std::min(empty, perpendicular(el.x[i] - c, axis.dir).norm());
    out.core_void_radius = std::max(out.core_void_radius, empty);
  }
  out.clusters = contact_clusters(el, rope, charge_neighbor_distance(rope.lattice.spacing));
  return out;
}

Morphology classify_morphology(const RopeShape& shape, const Rope& rope) {
  const double d = rope.lattice.spacing;
  if (shape.clusters > 1) return Morphology::Separated;
  if (shape.axis_deviation > std::max(0.5 * rope.initial_radius, 2.0 * d)) return Morphology::Helix;
  if (shape.core_void_radius > 1.2 * d) return Morphology::BirdCage;
  if (shape.twist_angle_deg >= 5.0) return Morphology::Spindle;
  return Morphology::Straight;
}

ShiftAngle::ShiftAngle(const Elements& ref, const Rope&) {
  const Vec3 z = Vec3::UnitZ();
  const std::vector<std::size_t> a = ref.group_indices(kRopeGripA),
                                 b = ref.group_indices(kRopeGripB);
  const Vec3 ca = mass_centroid(ref, a), cb = mass_centroid(ref, b);
  for (std::size_t i : a) ref_a_.push_back(perpendicular(ref.x[i] - ca, z));
  for (std::size_t i : b) ref_b_.push_back(perpendicular(ref.x[i] - cb, z));
}

double ShiftAngle::grip_rotation(const Elements& el, const std::vector<std::size_t>& grip,
                                 const std::vector<Vec3>& ref, const RopeAxis& axis) const {
  const Vec3 c = mass_centroid(el, grip);
  double s = 0, co = 0;
  for (std::size_t k = 0; k < grip.size(); ++k) {
    const Vec3 r = perpendicular(el.x[grip[k]] - c, axis.dir);
    s += axis.dir.dot(ref[k].cross(r));
    co += ref[k].dot(r);
  }
  return std::atan2(s, co);
}

double ShiftAngle::update(const Elements& el, const RopeAxis& axis) {
  const double rel = grip_rotation(el, el.group_indices(kRopeGripB), ref_b_, axis) -
                     grip_rotation(el, el.group_indices(kRopeGripA), ref_a_, axis);
  angle_ += std::remainder(rel - angle_, 2.0 * std::numbers::pi);
  return angle_;
}

void ShiftAngle::save_state(StateWriter& w) const {
  w.begin("shift_angle");
  w.put(angle_);
}

void ShiftAngle::load_state(StateReader& r) {
  r.begin("shift_angle");
  angle_ = r.get<double>("angle");
}

ShiftAngleSampler::ShiftAngleSampler(const Elements& reference, const Rope& rope, long every)
    : shift_(reference, rope), rope_(&rope), every_(every) {
  if (every < 1) throw std::invalid_argument("shift angle sampling interval must be >= 1 step");
}

double ShiftAngleSampler::sample(const Elements& el) {
  value_ = shift_.update(el, rope_axis(el, *rope_));
  return value_;
}

void ShiftAngleSampler::apply(System& s, double) {
  if (s.steps() % every_ == 0) sample(s.elements());
}

void ShiftAngleSampler::save_state(StateWriter& w) const {
  shift_.save_state(w);
  w.begin("shift_angle_sample");
  w.put(value_);
}

void ShiftAngleSampler::load_state(StateReader& r) {
  shift_.load_state(r);
  r.begin("shift_angle_sample");
  value_ = r.get<double>("value");
}

}  // namespace mdem
