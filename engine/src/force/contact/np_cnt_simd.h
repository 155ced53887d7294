#pragma once
// The vectorised NP–CNT pair law (model.md §5): NpCntKernel's scalar law (np_cnt_contact.cpp,
// whose file comment derives the gradient) over lanes of pairs in structure-of-arrays form, on the
// widest instruction set of the running CPU (Highway's dynamic dispatch, as vdw_simd).
#include <array>
#include <cstddef>

namespace mdem::np_cnt_simd {

// The law's constants, as NpCntKernel holds them.
struct Constants {
  double cutoff2;             // (4T)² (nm²)
  double fc_start, fc_width;  // smoothstep f_c from 3T over T (nm)
  double inv_rho;             // 1/ρ_NC (1/nm)
  std::array<double, 6> delta;  // δ as a polynomial in y = 2cos²θ − 1 (vdw_shape::DeltaPolynomial)
  double four_eps, A, B, alpha, beta, d_min;  // V(D) = 4ε(A D^−α − B D^−β) for D ≥ d_min
  double v_min, dv_min;                       // V(d_min), V'(d_min): the linear branch below
};

// The constants of a contact with parameters P (epsilon, A, B, alpha, beta, d_min and cutoff(), as
// NpCntParams and NpNpParams hold them), its cutoff ramp from fc_start over fc_width, 1/ρ, δ's
// coefficients, and V(d_min), V'(d_min).
template <class P>
Constants constants_of(const P& p, double fc_start, double fc_width, double inv_rho,
                       const std::array<double, 6>& delta, double v_min, double dv_min) {
  return {p.cutoff() * p.cutoff(),
          fc_start,
          fc_width,
          inv_rho,
          delta,
          4.0 * p.epsilon,
          p.A,
          p.B,
          p.alpha,
          p.beta,
          p.d_min,
          v_min,
          dv_min};
}

// Lanes of pairs: inputs d = x_NP − x_seg and the segment's unit axis b; outputs the energy, the
// force on the NP (−f on the segment) and the segment's torque. Every array holds n doubles.
struct Lanes {
  const double *dx, *dy, *dz, *bx, *by, *bz;
  double *e, *fx, *fy, *fz, *tx, *ty, *tz;
};

// The widest vector of doubles dispatched to (AVX-512: 8 lanes).
constexpr std::size_t kMaxLanes = 8;

// Evaluates lanes [0, n), n a multiple of kMaxLanes. A lane beyond the cutoff gets zeros (a NaN
// input propagates, as in the vdW kernel's batch). D^−α and D^−β are exp(−α log D) and
// exp(−β log D) (Highway's Log and Exp, within 4 and 1 ulp), where the scalar law calls pow():
// the two agree to a few ulp times α·|log D|. Returns true when some lane has coincident centres
// (R² < 1e-24): those lanes' outputs are not defined here, and the caller takes them from the
// scalar law.
bool evaluate(const Constants& k, const Lanes& l, std::size_t n);

// The instruction set evaluate() runs on this CPU, e.g. "AVX3", "AVX2", "EMU128".
const char* target_name();

}  // namespace mdem::np_cnt_simd
