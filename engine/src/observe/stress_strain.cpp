#include "mdem/observe/stress_strain.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "mdem/observe/series_checks.h"

namespace mdem {

namespace {

void check_curve(std::span<const double> strain, std::span<const double> stress, const char* where,
                 const char* what = "stress") {
  require_same_length(strain, stress, where, "strain", what);
  require_finite_series(strain, where, "strain");
  require_finite_series(stress, where, what);
}

// ε where the line through (e0, d0) and (e1, d1) crosses d = 0 (d0 ≥ 0 > d1).
double crossing(double e0, double d0, double e1, double d1) {
  return e0 + (e1 - e0) * d0 / (d0 - d1);
}

}  // namespace

LineFit modulus_fit(std::span<const double> strain, std::span<const double> stress, double lo,
                    double hi) {
  check_curve(strain, stress, "modulus_fit");
  if (!(std::isfinite(lo) && std::isfinite(hi) && lo < hi)) {
    std::ostringstream os;
    os << "modulus_fit: strain window [" << lo << ", " << hi << "]; it must be finite with lo < hi";
    throw std::invalid_argument(os.str());
  }
  std::vector<double> e, s;
  for (std::size_t i = 0; i < strain.size(); ++i)
    if (strain[i] >= lo && strain[i] <= hi) {
      e.push_back(strain[i]);
      s.push_back(stress[i]);
    }
  if (e.size() < 2) {
    std::ostringstream os;
    os << "modulus_fit: " << e.size() << " frame(s) with strain in [" << lo << ", " << hi
       << "]; the fit needs at least 2 (the curve spans [" << strain.front() << ", "
       << strain.back() << "])";
    throw std::invalid_argument(os.str());
  }
  return fit_line(e, s, "modulus_fit");
}

std::vector<double> moving_average(std::span<const double> strain, std::span<const double> stress,
                                   double window) {
  check_curve(strain, stress, "moving_average");
  require_non_decreasing(strain, "moving_average", "strain");
  require_positive(window, "moving_average", "the strain window");
  const std::size_t n = strain.size();
  std::vector<double> out(n);
  const double half = 0.5 * window;
  std::size_t lo = 0, hi = 0;  // frames [lo, hi) lie within ±half of frame i
  double sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (hi < n && strain[hi] - strain[i] <= half) sum += stress[hi++];
    while (strain[i] - strain[lo] > half) sum -= stress[lo++];
    out[i] = sum / static_cast<double>(hi - lo);
  }
  return out;
}

std::optional<double> offset_yield_strain(std::span<const double> strain,
                                          std::span<const double> stress, const LineFit& fit,
                                          double offset, double smooth_window, double after) {
  check_curve(strain, stress, "offset_yield_strain");
  if (!(std::isfinite(fit.slope) && std::isfinite(fit.intercept) && std::isfinite(offset) &&
        std::isfinite(after)))
    throw std::invalid_argument(
        "offset_yield_strain: the fit, the offset and the start strain must be finite");
  const std::vector<double> smooth = moving_average(strain, stress, smooth_window);
  auto excess = [&](std::size_t i) {  // smoothed σ above the offset line
    return smooth[i] - (fit.slope * (strain[i] - offset) + fit.intercept);
  };
  for (std::size_t i = 0; i < strain.size(); ++i) {
    if (!(strain[i] > after) || excess(i) >= 0) continue;
    if (i == 0 || excess(i - 1) < 0) return strain[i];  // already below: no bracket
    const double e = crossing(strain[i - 1], excess(i - 1), strain[i], excess(i));
    return e > after ? e : strain[i];
  }
  return std::nullopt;
}

std::optional<double> count_onset_strain(std::span<const double> strain,
                                         std::span<const double> count, double baseline_max,
                                         double n_sigma) {
  check_curve(strain, count, "count_onset_strain", "count");
  double sum = 0, sum2 = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < strain.size(); ++i)
    if (strain[i] <= baseline_max) {
      sum += count[i];
      ++n;
    }
  if (n < 2) {
    std::ostringstream os;
    os << "count_onset_strain: " << n << " frame(s) with strain <= " << baseline_max
       << "; the baseline needs at least 2";
    throw std::invalid_argument(os.str());
  }
  const double mean = sum / static_cast<double>(n);
  for (std::size_t i = 0; i < strain.size(); ++i)
    if (strain[i] <= baseline_max) sum2 += (count[i] - mean) * (count[i] - mean);
  const double sigma = std::sqrt(sum2 / static_cast<double>(n - 1));
  const double threshold = mean + n_sigma * sigma;
  for (std::size_t i = 0; i < strain.size(); ++i)
    if (count[i] > threshold) return strain[i];
  return std::nullopt;
}

double toughness(std::span<const double> strain, std::span<const double> stress) {
  check_curve(strain, stress, "toughness");
  double w = 0;
  for (std::size_t i = 1; i < strain.size(); ++i)
    w += 0.5 * (stress[i] + stress[i - 1]) * (strain[i] - strain[i - 1]);
  return w;
}

std::optional<double> failure_strain(std::span<const double> strain,
                                     std::span<const double> stress) {
  check_curve(strain, stress, "failure_strain");
  const std::size_t peak =
      static_cast<std::size_t>(std::max_element(stress.begin(), stress.end()) - stress.begin());
  const double half = 0.5 * stress[peak];
  if (!(stress[peak] > 0)) return std::nullopt;
  for (std::size_t i = peak + 1; i < stress.size(); ++i)
    if (stress[i] < half)
      return crossing(strain[i - 1], stress[i - 1] - half, strain[i], stress[i] - half);
  return std::nullopt;
}

}  // namespace mdem
