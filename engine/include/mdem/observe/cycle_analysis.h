#pragma once
// What each cycle of a cyclic tensile test reports (tensile.md §3.6): the loop area ∮σ dε, the
// modulus on the returning half, the phase lead of stress over strain and the peak stresses.
// Input: frames (t, ε, σ), time in ps, σ in GPa; cycle k spans [t0 + k·P, t0 + (k + 1)·P].
// Definitions and tests: docs/tensile.md.
#include <span>
#include <vector>

namespace mdem {

struct CycleSettings {
  double period = 0;           // P (ps)
  double t0 = 0;               // start of the first cycle (ps)
  double modulus_lo = -0.007;  // the returning half's fit window in ε (−0.7 % … −0.2 %)
  double modulus_hi = -0.002;
};

struct CycleResult {
  int cycle = 0;                    // k, from 0
  double loop_area = 0;             // ∮σ dε (GPa = GJ/m³), positive when energy is dissipated
  double loop_area_j_per_cm3 = 0;   // 1000 × loop_area
  double modulus = 0;               // least-squares slope (GPa) on the returning half's window
  std::size_t modulus_samples = 0;  // frames in that window
  double phase_lead = 0;            // of σ over ε, fraction of P in (−½, ½]
  double peak_tension = 0;          // max σ over the cycle
  double peak_compression = 0;      // min σ over the cycle
};

// One result per complete cycle the frames cover (those with t0 + (k + 1)·P ≤ the last t).
// Frame values at the cycle's ends are linearly interpolated in time, so the loop is closed even
// when no frame falls on a boundary; the loop area is the trapezoid rule along the frames in time
// order plus the closing chord. The returning half runs from the frame of least ε in the cycle to
// its end. The phase comes from the first Fourier harmonic c = ∫ f(t) e^{−iωt} dt (ω = 2π/P,
// trapezoid) of σ and of ε: lead = (arg c_σ − arg c_ε)/2π. Throws std::invalid_argument for
// empty, non-finite or unequal series, time that does not increase, a non-positive period, no
// complete cycle, or a returning half with fewer than two frames in the modulus window.
std::vector<CycleResult> analyse_cycles(std::span<const double> t, std::span<const double> strain,
                                        std::span<const double> stress, const CycleSettings& s);

}  // namespace mdem
