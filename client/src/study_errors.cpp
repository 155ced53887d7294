// Errors of a study's results against Richardson's extrapolation or the most accurate run.
#include "study_errors.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

namespace mdem::cli {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Refinement ratios that differ by less than this (relative) count as constant.
constexpr double kRatioTolerance = 1e-3;

// The successful runs, most accurate (most element-steps) first.
std::vector<std::size_t> by_accuracy(const std::vector<StudyRun>& runs) {
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < runs.size(); ++i)
    if (runs[i].succeeded) idx.push_back(i);
  std::stable_sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
    return runs[a].element_steps > runs[b].element_steps;
  });
  return idx;
}

// The three most accurate runs as coarse, mid, fine and their ratio, when their varied values
// are in a constant ratio; else the reason in `note`.
void pick_richardson(const std::vector<std::size_t>& order, const std::vector<double>& varied,
                     StudyErrors& out) {
  if (varied.empty()) {
    out.note = "Richardson needs one varied setting; the reference is the most accurate run";
    return;
  }
  if (order.size() < 3) {
    out.note = "Richardson needs three successful runs; the reference is the most accurate run";
    return;
  }
  const double fine = varied[order[0]], mid = varied[order[1]], coarse = varied[order[2]];
  // h may grow or shrink towards accuracy: the ratio is taken >= 1 either way.
  auto ratio = [](double a, double b) { return std::max(a / b, b / a); };
  const bool same_sign = fine * mid > 0 && mid * coarse > 0;
  const bool monotone = (coarse - mid) * (mid - fine) > 0;
  const double r1 = same_sign ? ratio(coarse, mid) : kNaN, r2 = same_sign ? ratio(mid, fine) : kNaN;
  if (!same_sign || !monotone || !(std::abs(r1 - r2) <= kRatioTolerance * r2) || !(r2 > 1)) {
    out.note =
        "Richardson needs the three most accurate runs at a constant refinement ratio (e.g. "
        "0.6, 0.3, 0.15); the reference is the most accurate run";
    return;
  }
  out.richardson_runs = {order[2], order[1], order[0]};
  out.ratio = r2;
}

}  // namespace

std::optional<Richardson> richardson(double f_coarse, double f_mid, double f_fine, double r) {
  if (!std::isfinite(f_coarse) || !std::isfinite(f_mid) || !std::isfinite(f_fine) ||
      !std::isfinite(r) || !(r > 1))
    return std::nullopt;
  const double d1 = f_coarse - f_mid, d2 = f_mid - f_fine;
  if (d1 == 0 || d2 == 0 || (d1 > 0) != (d2 > 0)) return std::nullopt;
  const double p = std::log(d1 / d2) / std::log(r);
  const double denom = std::pow(r, p) - 1;
  return Richardson{p, denom != 0 ? f_fine - d2 / denom : kNaN};
}

StudyErrors study_errors(const std::vector<StudyRun>& runs, const std::vector<double>& varied,
                         const std::vector<SummaryField>& results, ReferenceMode mode) {
  const std::vector<std::size_t> order = by_accuracy(runs);
  if (order.empty()) throw std::invalid_argument("no run of the study succeeded: no reference");
  StudyErrors out;
  out.finest = order.front();
  if (mode == ReferenceMode::Auto)
    pick_richardson(order, varied.size() == runs.size() ? varied : std::vector<double>{}, out);
  else
    out.note = "the reference is the most accurate run (--reference finest)";
  for (const SummaryField& f : results) {
    ResultError e;
    e.field = f;
    e.order = kNaN;
    auto value = [&](std::size_t i) {
      const auto it = runs[i].results.find(f.key);
      return it == runs[i].results.end() ? kNaN : it->second;
    };
    e.reference = value(out.finest);
    if (out.richardson_runs.size() == 3) {
      const auto& rr = out.richardson_runs;
      if (const auto rich = richardson(value(rr[0]), value(rr[1]), value(rr[2]), out.ratio)) {
        e.order = rich->order;
        // A count's reference stays a count; an order <= 0 extrapolates nothing.
        if (f.type == SummaryField::Type::Real && rich->order > 0 && std::isfinite(rich->limit)) {
          e.reference = rich->limit;
          e.extrapolated = true;
        }
      }
    }
    for (std::size_t i = 0; i < runs.size(); ++i) {
      const double v = runs[i].succeeded ? value(i) : kNaN;
      const double err = std::abs(v - e.reference);
      e.error.push_back(err);
      e.relative.push_back(e.reference != 0 ? err / std::abs(e.reference) : kNaN);
    }
    out.results.push_back(std::move(e));
  }
  return out;
}

}  // namespace mdem::cli
