#pragma once
// The vectorised CNT contact dashpot (viscous_contact_damping.h): the scalar kernel's force
// −c·(n·v_rel)·n along the centre line, c = 2ψ√(m_eff k), evaluated over lanes of pairs in
// structure-of-arrays form on the widest instruction set of the running CPU (Google Highway's
// dynamic dispatch, as vdw_simd.h).
#include <cstddef>

namespace mdem::dashpot_simd {

// Lanes of pairs: r = x2 − x1, the relative velocity u = v2 − v1 and the masses m1, m2; output
// the force f on element 1 (−f on element 2). Every array holds n doubles.
struct Lanes {
  const double *rx, *ry, *rz, *ux, *uy, *uz, *m1, *m2;
  double *fx, *fy, *fz;
};

// The widest vector of doubles dispatched to (AVX-512: 8 lanes).
constexpr std::size_t kMaxLanes = 8;

// f = 2ψ√(k m1 m2/(m1 + m2)) (r·u) r / |r|² on lanes [0, n), n a multiple of kMaxLanes, with
// ratio = ψ and stiffness = k, or with shear f = 2ψ√(k m1 m2/(m1 + m2)) u; a lane with r = 0
// gets zeros (no centre line), a NaN propagates.
void evaluate(double ratio, double stiffness, bool shear, const Lanes& l, std::size_t n);

// The instruction set evaluate() runs on this CPU, e.g. "AVX3", "AVX2", "EMU128".
const char* target_name();

}  // namespace mdem::dashpot_simd
