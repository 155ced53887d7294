#pragma once
// Building blocks for CNT scenes: one (10,10) segment, and a straight tube of bonded segments.
#include <cstddef>
#include <vector>

#include "mdem/core/elements.h"
#include "mdem/force/bond/parallel_bond.h"

namespace mdem {

// Unit quaternion that turns body x onto `axis` (any non-zero vector) with the least rotation.
Quat quat_from_axis(const Vec3& axis);

// A (10,10) segment: mass, isotropic hoop inertia m r², radius r (model.md §2).
ElementInit cnt_segment(const Vec3& x, const Quat& q, int tube, int index);

// Appends a straight tube of n segments, centres first_centre + k·T·dir, all with axis dir, and
// (when bonds is not null) the n−1 intra-tube parallel bonds. Returns the element indices.
std::vector<std::size_t> add_straight_tube(Elements& el, ParallelBond* bonds,
                                           const Vec3& first_centre, const Vec3& dir, int n,
                                           int tube_id);

}  // namespace mdem
