#include "mdem/observe/linear_fit.h"

#include <stdexcept>
#include <string>

#include "mdem/observe/series_checks.h"

namespace mdem {

LineFit fit_line(std::span<const double> x, std::span<const double> y, std::string_view where) {
  require_same_length(x, y, where, "x", "y");
  require_finite_series(x, where, "x");
  require_finite_series(y, where, "y");
  const std::size_t n = x.size();
  if (n < 2)
    throw std::invalid_argument(std::string(where) + ": " + std::to_string(n) +
                                " sample(s) in the fit window; a line needs at least 2");
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < n; ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= static_cast<double>(n);
  my /= static_cast<double>(n);
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  if (!(sxx > 0))
    throw std::invalid_argument(std::string(where) +
                                ": every x in the fit window is the same; a slope needs x to vary");
  LineFit f;
  f.slope = sxy / sxx;
  f.intercept = my - f.slope * mx;
  f.samples = n;
  return f;
}

}  // namespace mdem
