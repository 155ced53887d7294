#pragma once
// The largest vibration frequency of a system's current state, and from it the critical step of
// the velocity Verlet integrator, 2/ω_max — the true limit that System's automatic step bounds
// from below (compute_critical_dt: a Gershgorin bound over each element's summed stiffness
// bounds). A diagnostic: how much margin a safety factor leaves on a given state.
//
// ω_max² is the largest eigenvalue of the mass-weighted stiffness matrix M^-1/2 K M^-1/2 over the
// free degrees of freedom (translations in world x, y, z; rotations about the principal body axes,
// weighted by the principal moments), found by Lanczos iteration (no reorthogonalisation: the
// largest Ritz value converges first, lost orthogonality only repeats it). K v comes from central
// differences of the conservative forces and torques at x ± h·v: one pair of force evaluations per
// iteration, no second derivatives from any model. A rotation's generalised force is the torque
// with the second-order correction −½ φ × τ of the rotation group, so the differenced matrix is the
// Hessian of the stored energy (symmetric) also away from equilibrium. Damping is left out: the
// undamped limit. The difference quotient needs forces that are smooth at the scale of the
// displacement: a force that jumps where a pair crosses some distance (a kink in its energy) has
// no stiffness there to speak of, and the estimate then grows as the displacement shrinks —
// check_smoothness reports it.
#include <cstdint>

namespace mdem {

class System;

struct SpectrumSettings {
  int max_iterations = 150;  // Lanczos steps (two force evaluations each), [2, 10000]
  // Converged when the top Ritz pair's residual |β_k s_k| is below tolerance × the Ritz value
  // (then an eigenvalue lies within that distance of it), (0, 1).
  double tolerance = 1e-4;
  // Largest displacement of any element's point (nm; a rotation counts at the element's radius)
  // in the difference quotient, (0, 0.01].
  double displacement = 1e-5;
  std::uint64_t seed = 1;  // the random start vector
  // Run Lanczos a second time at a tenth of the displacement (same start): for smooth forces the
  // two agree; a force that jumps (a kink in a pair energy, where a pair may also sit pinned)
  // adds a stiffness of ~jump / move to the difference quotient, which grows tenfold.
  bool check_smoothness = true;
};

struct SpectrumEstimate {
  double omega_max = 0;    // rad/ps, the largest Ritz frequency (a lower bound of the true ω_max)
  double critical_dt = 0;  // ps, 2/ω_max (infinite for a state with no positive stiffness)
  double residual = 0;     // (rad/ps)², |β_k s_k| of the top Ritz pair
  int iterations = 0;
  bool converged = false;
  long force_evaluations = 0;
  // With check_smoothness: ω_max at a tenth of the displacement, and whether it is within
  // max(100 × tolerance, 1e-6) of omega_max relative (if not, the forces are not smooth at this
  // state at the scale of the displacement and 2/ω_max is not a step limit: see spectrum.h's top).
  double omega_fine = 0;
  bool smooth = true;
};

// Estimates the system's largest frequency at its current state (initialising the system first if
// needed). Leaves the state as it was, also when a force evaluation throws: positions and
// orientations are restored and the forces recomputed (bit for bit the same, unless a displaced
// state moved an element far enough to rebuild a neighbour list, which reorders sums). Throws
// std::invalid_argument for settings out of range.
SpectrumEstimate largest_frequency(System& sys, const SpectrumSettings& s = {});

}  // namespace mdem
