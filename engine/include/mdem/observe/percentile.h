#pragma once
// The one percentile rule of the observables (tensile.md §3.4 window, §3.5 necking widths):
// linear interpolation between order statistics. With the n values sorted, v[0] ≤ … ≤ v[n−1],
// the p-th percentile (p in [0, 100]) sits at position h = (n − 1)·p/100 and is
// v[⌊h⌋] + (h − ⌊h⌋)·(v[⌊h⌋ + 1] − v[⌊h⌋]) (Hyndman & Fan type 7, numpy's default). So P0 is the
// minimum, P100 the maximum and P50 the median, and scaling every value by s > 0 scales the
// percentile by s.
#include <span>
#include <string_view>

namespace mdem {

// Throws std::invalid_argument (naming `what`) for no values, a non-finite value, or p outside
// [0, 100].
double percentile(std::span<const double> values, double p, std::string_view what = "values");

}  // namespace mdem
