#pragma once
// Rigid 6-DOF elements stored as a structure of arrays: one contiguous array per field, so a
// kernel touches only the fields it names (positions and orientations for forces, velocities for
// the integrator).
#include <array>
#include <cstdint>
#include <cstdlib>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "mdem/core/groups.h"
#include "mdem/core/math.h"
#include "mdem/core/topology.h"

namespace mdem {

// Wall: a rigid flat platen (granular scenes): its plane passes through x with unit normal body
// z (q * UnitZ), pointing towards the material; it moves only as prescribed.
enum class ElementKind : std::uint8_t { CntSegment = 0, Nanoparticle = 1, Grain = 2, Wall = 3 };

// How one degree of freedom moves. Translational DOFs are world x, y, z; rotational DOFs are
// rotations about world x, y, z.
enum class DofMode : std::uint8_t {
  Free = 0,        // integrated from forces (plus any external load)
  Fixed = 1,       // never moves
  Prescribed = 2,  // moves at the prescribed velocity, whatever the forces
};

// What a caller gives to create one element. All quantities in internal units (units.h).
struct ElementInit {
  ElementKind kind = ElementKind::CntSegment;
  Vec3 x = Vec3::Zero();
  Quat q = Quat::Identity();
  Vec3 v = Vec3::Zero();
  Vec3 w = Vec3::Zero();        // angular velocity, world frame (rad/ps)
  double mass = 0;              // eV·ps²/nm²
  Vec3 inertia = Vec3::Zero();  // principal moments in the body frame (eV·ps²)
  double radius = 0;            // nm
  std::int32_t tube = -1;       // tube id for CNT segments, -1 otherwise
  std::int32_t index = -1;      // index along the tube
};

struct Elements {
  // Identity: a global id given by add() (0, 1, 2, ... in order of creation) that stays with the
  // element if the arrays are ever reordered; outputs and groups name elements by tag.
  std::vector<std::uint64_t> tag;
  // Named sets of elements (by tag), declared by the scene or job that built them.
  Groups groups;
  // Bonds (as pairs of tags) and the ordered segments of each CNT tube, open or closed (a ring),
  // recorded by the scene builders; the bond models are made from it.
  Topology topology;
  // State.
  std::vector<Vec3> x;  // centre position (nm)
  std::vector<Quat> q;  // orientation, unit quaternion, body -> world; a CNT axis is body x
  std::vector<Vec3> v;  // velocity (nm/ps)
  std::vector<Vec3> w;  // angular velocity, world frame (rad/ps)
  // Properties.
  std::vector<double> mass;
  std::vector<double> inv_mass;
  std::vector<Vec3> inertia;  // principal, body frame
  std::vector<double> radius;
  std::vector<ElementKind> kind;
  std::vector<std::int32_t> tube;
  std::vector<std::int32_t> index;
  // Degrees of freedom: [0..2] translation x,y,z; [3..5] rotation about x,y,z (world).
  std::vector<std::array<DofMode, 6>> dof;
  std::vector<Vec3> v_prescribed;  // used where a translational DOF is Prescribed
  std::vector<Vec3> w_prescribed;  // used where a rotational DOF is Prescribed
  std::vector<Vec3> f_ext;         // external force (eV/nm), acts on Free DOFs
  std::vector<Vec3> t_ext;         // external torque (eV), acts on Free DOFs
  // Interaction results of the last force evaluation (internal forces only, no external load).
  std::vector<Vec3> f;
  std::vector<Vec3> t;
  // The tag add() gives next (one past the largest given so far).
  std::uint64_t next_tag = 0;

  std::size_t size() const { return x.size(); }

  // Appends one element with the next tag; returns its index. Throws std::invalid_argument on a
  // non-finite or non-positive mass, inertia or radius, or a non-finite position, orientation or
  // velocity.
  std::size_t add(const ElementInit& e);

  // Current index of the element tagged `tag`: O(1) through a tag -> index map that add() and
  // reorder() keep; should a caller have edited `tag` by hand, it falls back to a search, so the
  // answer is always that of the arrays. Throws std::out_of_range for an unknown tag.
  std::size_t index_of(std::uint64_t tag) const;

  // Reorders the elements (memory order only: every per-element array moves, tags with their
  // elements, so groups and topology, which hold tags, are unaffected): the element at index
  // new_to_old[k] moves to index k. Throws std::invalid_argument, changing nothing, unless
  // new_to_old is a permutation of 0 .. size()-1.
  void reorder(std::span<const std::uint32_t> new_to_old);
  // The indices of the elements in ascending tag order (the order outputs and checkpoints are
  // written in); the identity for elements never reordered.
  std::vector<std::uint32_t> tag_order() const;
  // Current indices of a group's elements, in tag order. Throws std::invalid_argument naming the
  // known groups when there is no group `name`.
  std::vector<std::size_t> group_indices(std::string_view name) const;

  // Axis of a CNT segment (body x in world frame): q[i] * Vec3::UnitX(), which Eigen evaluates
  // as toRotationMatrix() times (1, 0, 0), written out in scalars as its first column (the same
  // doubles in the portable build: the product's R(k,1)·0 and R(k,2)·0 terms change at most the
  // sign of a zero; with -march=native the compiler may fuse either form's multiply-adds).
  // Through Eigen, GCC stored the matrix's entries one by one and loaded them back in pairs, which
  // the store buffer cannot forward: 45 % of the NP–CNT batch's time went to those stalls.
  Vec3 axis(std::size_t i) const {
    const double w = q[i].w(), x = q[i].x(), y = q[i].y(), z = q[i].z();
    const double ty = 2.0 * y, tz = 2.0 * z;
    return Vec3(1.0 - (ty * y + tz * z), ty * x + tz * w, tz * x - ty * w);
  }

  bool is_isotropic(std::size_t i) const {
    const Vec3& I = inertia[i];
    return std::abs(I.x() - I.y()) <= 1e-12 * I.x() && std::abs(I.x() - I.z()) <= 1e-12 * I.x();
  }

  void fix_all(std::size_t i) { dof[i].fill(DofMode::Fixed); }

  // Whether a CNT-CNT pair model leaves (i, j) out: not both CNT segments, or segments of one
  // tube fewer than `exclusion` indices apart (model.md §4's intra-tube exclusion). Around a ring
  // (a closed chain of n segments in `topology`) the distance is min(|Δindex|, n − |Δindex|), so
  // the exclusion reaches across the seam as it does anywhere else on the ring.
  bool cnt_pair_excluded(std::size_t i, std::size_t j, int exclusion) const {
    if (kind[i] != ElementKind::CntSegment || kind[j] != ElementKind::CntSegment) return true;
    if (tube[i] < 0 || tube[i] != tube[j]) return false;
    const int d = std::abs(index[i] - index[j]);
    if (d < exclusion) return true;
    const int ring = topology.ring_length(tube[i]);
    return ring > 0 && ring - d < exclusion;
  }

 private:
  // index_of_tag_[t]: the index of the element tagged t (tags are 0 .. next_tag-1, dense).
  std::vector<std::uint32_t> index_of_tag_;
};

// Whether new_to_old is a permutation of 0 .. n-1 (what Elements::reorder accepts).
bool is_permutation_of(std::span<const std::uint32_t> new_to_old, std::size_t n);
// Whether the reordering leaves every element in place.
bool is_identity_order(std::span<const std::uint32_t> new_to_old);
// old_to_new of a reordering given as new_to_old (a permutation): old_to_new[new_to_old[k]] = k.
std::vector<std::uint32_t> invert_permutation(std::span<const std::uint32_t> new_to_old);
// Applies a reordering to one per-element array: a[k] becomes the old a[new_to_old[k]]. Throws
// std::invalid_argument when the sizes differ.
template <class T>
void permute(std::vector<T>& a, std::span<const std::uint32_t> new_to_old) {
  if (a.size() != new_to_old.size())
    throw std::invalid_argument("permute: array of " + std::to_string(a.size()) +
                                " entries, reordering of " + std::to_string(new_to_old.size()));
  std::vector<T> out;
  out.reserve(a.size());
  for (std::uint32_t i : new_to_old) out.push_back(std::move(a[i]));
  a = std::move(out);
}

}  // namespace mdem
