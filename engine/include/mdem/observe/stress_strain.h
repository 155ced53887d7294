#pragma once
// What a tensile stress–strain curve reports (tensile.md §3.5): the Young's modulus fit, the
// 0.2 %-offset yield strain, the aligned-pair onset (second yield indicator), the toughness and
// the failure strain. Every function takes the frames as two series of one sample per frame,
// strain ε (dimensionless) and stress σ (any unit; the tensile job uses GPa), and throws
// std::invalid_argument naming what is wrong for empty or non-finite series, series of different
// length, or a window that holds too few samples. Definitions and tests: docs/tensile.md.
#include <optional>
#include <span>
#include <vector>

#include "mdem/observe/linear_fit.h"

namespace mdem {

// Least-squares σ = E·ε + σ0 over the frames with lo ≤ ε ≤ hi (tensile.md §3.5: 1 % to 2 %).
LineFit modulus_fit(std::span<const double> strain, std::span<const double> stress,
                    double lo = 0.01, double hi = 0.02);

// σ smoothed by a centred moving average over a strain window: the mean of σ_j over the frames
// with |ε_j − ε_i| ≤ window/2. Strain must not decrease.
std::vector<double> moving_average(std::span<const double> strain, std::span<const double> stress,
                                   double window = 0.002);

// The 0.2 %-offset yield strain: the first ε > `after` at which the smoothed σ (moving average
// over `smooth_window`) falls below fit.slope·(ε − offset) + fit.intercept. Returned at the
// crossing, linearly interpolated between the first frame below the offset line and the frame
// before it (that frame's ε when the crossing would lie at or before `after`, or when the frame
// before is below too); empty when σ never falls below the line. Strain must not decrease.
std::optional<double> offset_yield_strain(std::span<const double> strain,
                                          std::span<const double> stress, const LineFit& fit,
                                          double offset = 0.002, double smooth_window = 0.002,
                                          double after = 0.02);

// The aligned-pair onset: with m and s the mean and sample standard deviation (n − 1) of the
// count over the frames with ε ≤ baseline_max (at least two), the first frame's ε whose count
// exceeds m + n_sigma·s; empty when none does.
std::optional<double> count_onset_strain(std::span<const double> strain,
                                         std::span<const double> count, double baseline_max = 0.01,
                                         double n_sigma = 5);

// ∫σ dε along the frames in their order (trapezoid rule); GJ/m³ when σ is in GPa.
double toughness(std::span<const double> strain, std::span<const double> stress);

// The failure strain: after the (first) peak of σ, the ε where σ first drops below ½ σ_peak,
// linearly interpolated between that frame and the one before it; empty when σ never drops that
// far, or the peak is not positive.
std::optional<double> failure_strain(std::span<const double> strain,
                                     std::span<const double> stress);

}  // namespace mdem
