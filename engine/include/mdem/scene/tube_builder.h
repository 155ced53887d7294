#pragma once
// Building blocks for CNT scenes: one (10,10) segment, a straight tube of bonded segments and a
// closed ring. The builders record their tubes and intra-tube bonds in el.topology (BondType::Cnt);
// the bond model is made from it (ParallelBond::from_topology).
#include <cstddef>
#include <vector>

#include "mdem/core/elements.h"

namespace mdem {

// Unit quaternion that turns body x onto `axis` (any non-zero vector) with the least rotation.
Quat quat_from_axis(const Vec3& axis);

// A (10,10) segment: mass, isotropic hoop inertia m r², radius r (model.md §2).
ElementInit cnt_segment(const Vec3& x, const Quat& q, int tube, int index);

// Appends a straight tube of n segments, centres first_centre + k·T·dir, all with axis dir, and
// records it in el.topology as an open chain with its n−1 intra-tube bonds. Returns the element
// indices. Throws std::invalid_argument for n < 1, a zero axis, or a tube id that is negative or
// has a chain already.
std::vector<std::size_t> add_straight_tube(Elements& el, const Vec3& first_centre, const Vec3& dir,
                                           int n, int tube_id);

// Radius of the circle through the centres of a ring of n segments T apart: T / (2 sin(π/n)).
double ring_radius(int n);

// Appends a closed planar ring of n segments about `centre` in the plane normal to `normal`:
// segment k at angle 2πk/n (from an arbitrary fixed direction in the plane, counter-clockwise
// about `normal`) on the circle of ring_radius(n), so neighbouring centres are T apart, its axis
// tangent to the circle. Records it in el.topology as a closed chain with its n bonds, the last
// (the seam) from segment n−1 to segment 0. Returns the element indices. Throws
// std::invalid_argument for n < 3, a non-finite centre, a zero or non-finite normal, or a tube id
// that is negative or has a chain already.
std::vector<std::size_t> add_ring_tube(Elements& el, const Vec3& centre, const Vec3& normal, int n,
                                       int tube_id);

// Records the tube made of elements `ids` (segment k is ids[k]) in el.topology with its CNT bonds:
// the chain of tube `tube_id`, open or closed, split from tube `parent` (-1: none; Chain::parent).
// What the builders above call.
void record_cnt_tube(Elements& el, const std::vector<std::size_t>& ids, int tube_id, bool closed,
                     int parent = -1);

}  // namespace mdem
