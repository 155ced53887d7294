#pragma once
// The vectorised parallel bond (parallel_bond.h): the scalar kinematics and loads of
// parallel_bond.cpp evaluated over lanes of bonds, with the bonds' rest state in
// structure-of-arrays form and the two bodies' positions and orientations gathered per lane, on
// the widest instruction set of the running CPU (Google Highway's dynamic dispatch, as
// vdw_simd.h). Lanes outside the small-angle series of the rotation log (|θ| ≥ ~0.1 rad) and at
// a 180° bend (no bond axis) are flagged for the caller to finish with the scalar code.
#include <cstddef>
#include <cstdint>

namespace mdem::bond_simd {

// The widest vector of doubles dispatched to (AVX-512: 8 lanes).
constexpr std::size_t kMaxLanes = 8;
// Bonds per call of evaluate(): the outputs of one chunk stay in L1 until they are scattered.
constexpr std::size_t kChunk = 64;

// The bonds' rest state in blocks of kMaxLanes bonds, every field of a block contiguous (a
// vector's load is one contiguous read, and the bond loop streams through one array): for block
// b and lane l, field f of bond kMaxLanes·b + l is field[(b·kFields + f)·kMaxLanes + l], its
// element indices index[(2b + 0)·kMaxLanes + l] (i) and index[(2b + 1)·kMaxLanes + l] (j). The
// fields: c, n the body-frame arms (centre → bond point) and bond directions of bodies i and j;
// p = q_rel0⁻¹ (w, x, y, z); the four stiffnesses of BondStiffness. A last partial block is
// padded with any valid element indices and finite values.
enum Field {
  kCix,
  kCiy,
  kCiz,
  kCjx,
  kCjy,
  kCjz,
  kNix,
  kNiy,
  kNiz,
  kNjx,
  kNjy,
  kNjz,
  kPw,
  kPx,
  kPy,
  kPz,
  kKnArea,
  kKsArea,
  kKnInertia,
  kKsPolar,
  kFields
};
struct Rest {
  const std::int64_t* index;
  const double* field;
};

// The bodies: x holds 3 doubles per element (Vec3's layout), q 4 (x, y, z, w: Eigen's
// quaternion layout). A periodic axis a has length[a] = L and inv_length[a] = 1/L; an open axis
// 0 and 0 (periodic = false skips the image altogether).
struct Bodies {
  const double* x;
  const double* q;
  bool periodic;
  double length[3], inv_length[3];
};

// One chunk's loads: the force on i (−f on j) and the torques on i and j per bond, and the four
// energies summed over the bonds the kernel evaluated (not those it leaves to the scalar code).
struct alignas(64) Out {
  double fx[kChunk], fy[kChunk], fz[kChunk];
  double tix[kChunk], tiy[kChunk], tiz[kChunk];
  double tjx[kChunk], tjy[kChunk], tjz[kChunk];
  double e_tension, e_shear, e_bending, e_torsion;
};

// Evaluates bonds [begin, begin + n) into out (force and torques of bond begin + l at l), n ≤
// kChunk a multiple of kMaxLanes. Returns the lanes (bit l for bond begin + l) whose outputs are
// not defined here: a relative rotation outside the series' range, a bond axis of length ≤ 1e-12
// (the scalar code's 180° fallback), or a NaN in an orientation; the caller takes those from the
// scalar code. A NaN position propagates to the lane's outputs, as in the scalar code.
std::uint64_t evaluate(const Rest& r, const Bodies& b, std::size_t begin, std::size_t n, Out& out);

// The instruction set evaluate() runs on this CPU, e.g. "AVX3", "AVX2", "EMU128".
const char* target_name();

}  // namespace mdem::bond_simd
