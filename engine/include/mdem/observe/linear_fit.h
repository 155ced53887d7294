#pragma once
// Least-squares line y = slope·x + intercept (ordinary least squares with intercept), shared by
// the tensile modulus (tensile.md §3.5) and the per-cycle modulus (§3.6).
#include <cstddef>
#include <span>
#include <string_view>

namespace mdem {

struct LineFit {
  double slope = 0;
  double intercept = 0;
  std::size_t samples = 0;
};

// Throws std::invalid_argument (naming `where`) for series of different length, fewer than two
// samples, a non-finite value, or x without spread (all equal).
LineFit fit_line(std::span<const double> x, std::span<const double> y, std::string_view where);

}  // namespace mdem
