#include "mdem/observe/series_checks.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace mdem {

void require_finite_series(std::span<const double> values, std::string_view where,
                           std::string_view what) {
  if (values.empty())
    throw std::invalid_argument(std::string(where) + ": " + std::string(what) +
                                " is empty; at least one sample is needed");
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (std::isfinite(values[i])) continue;
    std::ostringstream os;
    os << where << ": " << what << "[" << i << "] is " << values[i]
       << "; every sample must be finite";
    throw std::invalid_argument(os.str());
  }
}

void require_same_length(std::span<const double> a, std::span<const double> b,
                         std::string_view where, std::string_view what_a, std::string_view what_b) {
  if (a.size() == b.size()) return;
  std::ostringstream os;
  os << where << ": " << what_a << " has " << a.size() << " samples but " << what_b << " has "
     << b.size() << "; they must have one sample each per frame";
  throw std::invalid_argument(os.str());
}

namespace {

// Throws unless every step values[i − 1] → values[i] passes `ok`, naming the first that fails.
template <class Ok>
void require_steps(std::span<const double> values, std::string_view where, std::string_view what,
                   Ok ok, std::string_view rule) {
  for (std::size_t i = 1; i < values.size(); ++i) {
    if (ok(values[i - 1], values[i])) continue;
    std::ostringstream os;
    os << where << ": " << what << "[" << i << "] = " << values[i] << " after " << what << "["
       << i - 1 << "] = " << values[i - 1] << "; " << what << " must " << rule;
    throw std::invalid_argument(os.str());
  }
}

}  // namespace

void require_non_decreasing(std::span<const double> values, std::string_view where,
                            std::string_view what) {
  require_steps(
      values, where, what, [](double a, double b) { return b >= a; }, "not decrease");
}

void require_increasing(std::span<const double> values, std::string_view where,
                        std::string_view what) {
  require_steps(
      values, where, what, [](double a, double b) { return b > a; }, "increase");
}

void require_positive(double value, std::string_view where, std::string_view what) {
  if (std::isfinite(value) && value > 0) return;
  std::ostringstream os;
  os << where << ": " << what << " is " << value << "; it must be finite and positive";
  throw std::invalid_argument(os.str());
}

}  // namespace mdem
