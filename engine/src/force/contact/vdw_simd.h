#pragma once
// The vectorised anisotropic vdW pair kernel (model.md §4): the scalar kernel's mathematics
// (anisotropic_vdw.cpp, eval_pair) evaluated over lanes of pairs in structure-of-arrays form, with
// the widest instruction set of the running CPU chosen at run time (Google Highway's dynamic
// dispatch: AVX-512, AVX2, SSE4, or plain C++).
#include <cstddef>

#include "mdem/force/contact/anisotropic_vdw.h"

namespace mdem::vdw_simd {

// Lanes of pairs: inputs r = x2 − x1 and the unit axes b1 (a), b2 (b); outputs the energy, the
// force f on segment 1 (−f on segment 2) and the torques t1, t2. Every array holds n doubles.
struct Lanes {
  const double *rx, *ry, *rz, *ax, *ay, *az, *bx, *by, *bz;
  double *e, *fx, *fy, *fz, *t1x, *t1y, *t1z, *t2x, *t2y, *t2z;
};

// The widest vector of doubles dispatched to (AVX-512: 8 lanes).
constexpr std::size_t kMaxLanes = 8;

// Evaluates lanes [0, n), n a multiple of kMaxLanes, for parameters with k.fast_lj and k.fast_w
// (no pow). A lane beyond the cutoff gets zeros (a NaN input propagates, as in the scalar
// kernel). Returns true when some lane has coincident centres (R² < 1e-24): those lanes' outputs
// are not defined here, and the caller takes them from the scalar kernel.
bool evaluate(const VdwConstants& k, const Lanes& l, std::size_t n);

// The instruction set evaluate() runs on this CPU, e.g. "AVX3", "AVX2", "EMU128".
const char* target_name();

}  // namespace mdem::vdw_simd
