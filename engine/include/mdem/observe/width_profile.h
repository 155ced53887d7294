#pragma once
// Necking of a stretched film (tensile.md §3.5): the width of the mid slab, its shrinkage, and the
// width profile along the pulling axis x. Widths are across y: w = P_hi(y) − P_lo(y) with the
// percentile rule of observe/percentile.h (default P99 − P1), and the full extent max(y) − min(y)
// as a second measure. Definitions and tests: docs/tensile.md.
#include <span>
#include <vector>

#include "mdem/core/math.h"

namespace mdem {

struct WidthSettings {
  double lo_percentile = 1;
  double hi_percentile = 99;
};

struct Width {
  double width = 0;   // P_hi(y) − P_lo(y)
  double extent = 0;  // max(y) − min(y)
  std::size_t elements = 0;
};

// The width of the elements with |x − x_mid| < half_slab (tensile.md: x_mid midway between the
// grips, half_slab = L/20). Throws std::invalid_argument for non-finite input, a non-positive
// half_slab, or no element in the slab.
Width mid_width(std::span<const Vec3> positions, double x_mid, double half_slab,
                const WidthSettings& s = {});

// 1 − w/w0 (0.1 for a uniform lateral scaling by 0.9). Throws for a non-positive w0.
double shrinkage(double w, double w0);

struct WidthBin {
  double x_lo = 0, x_hi = 0;
  Width width;  // elements = 0 and widths 0 for an empty bin
};

struct WidthProfile {
  std::vector<WidthBin> bins;
  double min_width = 0;  // least width over the bins with at least two elements
  std::size_t min_bin = 0;
};

// Bins [x_lo + k·bin, x_lo + (k + 1)·bin) covering [x_lo, x_hi) (the last may be shorter), each
// with the width of its elements. Throws std::invalid_argument for non-finite input, x_hi ≤ x_lo,
// a non-positive bin, or no bin with two elements.
WidthProfile width_profile(std::span<const Vec3> positions, double x_lo, double x_hi,
                           double bin = 20.0, const WidthSettings& s = {});

}  // namespace mdem
