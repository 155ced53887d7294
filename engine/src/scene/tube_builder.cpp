#include "mdem/scene/tube_builder.h"

#include <stdexcept>

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

std::vector<std::size_t> add_straight_tube(Elements& el, ParallelBond* bonds,
                                           const Vec3& first_centre, const Vec3& dir, int n,
                                           int tube_id) {
  if (n < 1) throw std::invalid_argument("a tube needs at least 1 segment");
  const Quat q = quat_from_axis(dir);
  const Vec3 step = cnt::kSegmentLength * dir.normalized();
  std::vector<std::size_t> ids;
  ids.reserve(n);
  for (int k = 0; k < n; ++k)
    ids.push_back(el.add(cnt_segment(first_centre + k * step, q, tube_id, k)));
  if (bonds) {
    const BondStiffness k = cnt_bond_stiffness();
    for (int s = 0; s + 1 < n; ++s)
      bonds->add(make_bond(el, static_cast<std::uint32_t>(ids[s]),
                           static_cast<std::uint32_t>(ids[s + 1]), k));
  }
  return ids;
}

}  // namespace mdem
