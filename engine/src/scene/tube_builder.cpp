#include "mdem/scene/tube_builder.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "mdem/core/cnt.h"

namespace mdem {

Quat quat_from_axis(const Vec3& axis) {
  if (!axis.allFinite() || axis.norm() == 0)
    throw std::invalid_argument("tube axis must be a finite, non-zero vector");
  const Vec3 a = axis.normalized();
  const double c = a.x();                         // cos of the angle between body x and a
  if (c < -1.0 + 1e-12) return Quat(0, 0, 0, 1);  // half turn about z
  // Half-angle form: q = (1 + x·a, x × a) normalised.
  const Vec3 v = Vec3::UnitX().cross(a);
  return Quat(1.0 + c, v.x(), v.y(), v.z()).normalized();
}

ElementInit cnt_segment(const Vec3& x, const Quat& q, int tube, int index) {
  ElementInit e;
  e.kind = ElementKind::CntSegment;
  e.x = x;
  e.q = q;
  e.mass = cnt::kMass;
  e.inertia = Vec3::Constant(cnt::kInertia);
  e.radius = cnt::kRadius;
  e.tube = tube;
  e.index = index;
  return e;
}

namespace {
// Checked before a builder adds any element, so a refused tube leaves the elements unchanged.
void require_new_tube(const Elements& el, int tube_id) {
  if (tube_id < 0)
    throw std::invalid_argument("tube id must be >= 0, got " + std::to_string(tube_id));
  if (el.topology.chain(tube_id))
    throw std::invalid_argument("tube id " + std::to_string(tube_id) + " is taken already");
}
}  // namespace

void record_cnt_tube(Elements& el, const std::vector<std::size_t>& ids, int tube_id, bool closed,
                     int parent) {
  Chain c;
  c.tube = tube_id;
  c.closed = closed;
  c.parent = parent;
  c.tags.reserve(ids.size());
  for (std::size_t i : ids) c.tags.push_back(el.tag[i]);
  el.topology.add_bonded_chain(el, std::move(c), BondType::Cnt);
}

std::vector<std::size_t> add_straight_tube(Elements& el, const Vec3& first_centre, const Vec3& dir,
                                           int n, int tube_id) {
  if (n < 1) throw std::invalid_argument("a tube needs at least 1 segment");
  require_new_tube(el, tube_id);
  const Quat q = quat_from_axis(dir);
  const Vec3 step = cnt::kSegmentLength * dir.normalized();
  std::vector<std::size_t> ids;
  ids.reserve(n);
  for (int k = 0; k < n; ++k)
    ids.push_back(el.add(cnt_segment(first_centre + k * step, q, tube_id, k)));
  record_cnt_tube(el, ids, tube_id, false);
  return ids;
}

double ring_radius(int n) {
  if (n < 3)
    throw std::invalid_argument("a ring needs at least 3 segments, got " + std::to_string(n));
  return cnt::kSegmentLength / (2.0 * std::sin(std::numbers::pi / n));
}

std::vector<std::size_t> add_ring_tube(Elements& el, const Vec3& centre, const Vec3& normal, int n,
                                       int tube_id) {
  const double r = ring_radius(n);
  if (!centre.allFinite()) throw std::invalid_argument("ring centre must be finite");
  if (!normal.allFinite() || normal.norm() == 0)
    throw std::invalid_argument("ring normal must be a finite, non-zero vector");
  require_new_tube(el, tube_id);
  const Vec3 nz = normal.normalized();
  const Vec3 e1 = nz.unitOrthogonal();
  const Vec3 e2 = nz.cross(e1);
  std::vector<std::size_t> ids;
  ids.reserve(n);
  for (int k = 0; k < n; ++k) {
    const double phi = 2.0 * std::numbers::pi * k / n;
    const Vec3 radial = std::cos(phi) * e1 + std::sin(phi) * e2;
    const Vec3 tangent = -std::sin(phi) * e1 + std::cos(phi) * e2;
    ids.push_back(el.add(cnt_segment(centre + r * radial, quat_from_axis(tangent), tube_id, k)));
  }
  record_cnt_tube(el, ids, tube_id, true);
  return ids;
}

}  // namespace mdem
