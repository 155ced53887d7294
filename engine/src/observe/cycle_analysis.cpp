#include "mdem/observe/cycle_analysis.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "mdem/observe/linear_fit.h"
#include "mdem/observe/series_checks.h"

namespace mdem {

namespace {

constexpr const char* kWhere = "analyse_cycles";

struct Frame {
  double t, e, s;
};

// The frame at time `at` (t[0] ≤ at ≤ t.back()), linearly interpolated between its neighbours.
Frame frame_at(std::span<const double> t, std::span<const double> e, std::span<const double> s,
               double at) {
  const std::size_t j = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), at) -
                                                 t.begin());  // first t > at
  if (j == 0) return {t[0], e[0], s[0]};
  if (j >= t.size()) return {t.back(), e.back(), s.back()};
  const double u = (at - t[j - 1]) / (t[j] - t[j - 1]);
  return {at, e[j - 1] + u * (e[j] - e[j - 1]), s[j - 1] + u * (s[j] - s[j - 1])};
}

// The cycle's frames: the interpolated start, every frame strictly inside, the interpolated end.
std::vector<Frame> cycle_frames(std::span<const double> t, std::span<const double> e,
                                std::span<const double> s, double a, double b) {
  std::vector<Frame> f{frame_at(t, e, s, a)};
  for (std::size_t i = 0; i < t.size(); ++i)
    if (t[i] > a && t[i] < b) f.push_back({t[i], e[i], s[i]});
  f.push_back(frame_at(t, e, s, b));
  return f;
}

double loop_area(const std::vector<Frame>& f) {
  double w = 0;
  for (std::size_t i = 1; i <= f.size(); ++i) {
    const Frame& p = f[i - 1];
    const Frame& q = f[i % f.size()];  // the last term is the closing chord
    w += 0.5 * (p.s + q.s) * (q.e - p.e);
  }
  return w;
}

// First-harmonic phase of σ minus that of ε, in fractions of the period, in (−½, ½].
double phase_lead(const std::vector<Frame>& f, double t0, double period) {
  const double omega = 2.0 * std::numbers::pi / period;
  std::complex<double> ce = 0, cs = 0;
  for (std::size_t i = 1; i < f.size(); ++i) {
    const double dt = f[i].t - f[i - 1].t;
    const std::complex<double> w0 = std::polar(1.0, -omega * (f[i - 1].t - t0));
    const std::complex<double> w1 = std::polar(1.0, -omega * (f[i].t - t0));
    ce += 0.5 * dt * (f[i - 1].e * w0 + f[i].e * w1);
    cs += 0.5 * dt * (f[i - 1].s * w0 + f[i].s * w1);
  }
  double lead = (std::arg(cs) - std::arg(ce)) / (2.0 * std::numbers::pi);
  lead -= std::ceil(lead - 0.5);  // into (−½, ½]
  return lead;
}

}  // namespace

std::vector<CycleResult> analyse_cycles(std::span<const double> t, std::span<const double> strain,
                                        std::span<const double> stress, const CycleSettings& s) {
  require_same_length(t, strain, kWhere, "t", "strain");
  require_same_length(t, stress, kWhere, "t", "stress");
  require_finite_series(t, kWhere, "t");
  require_finite_series(strain, kWhere, "strain");
  require_finite_series(stress, kWhere, "stress");
  require_positive(s.period, kWhere, "the period");
  require_increasing(t, kWhere, "t");
  if (!(std::isfinite(s.t0) && s.t0 >= t.front())) {
    std::ostringstream os;
    os << kWhere << ": t0 = " << s.t0 << "; it must be finite and not before the first frame ("
       << t.front() << ")";
    throw std::invalid_argument(os.str());
  }
  const long n_cycles = static_cast<long>(std::floor((t.back() - s.t0) / s.period * (1 + 1e-12)));
  if (n_cycles < 1) {
    std::ostringstream os;
    os << kWhere << ": the frames span " << t.back() - s.t0 << " ps from t0, less than one period ("
       << s.period << " ps); at least one complete cycle is needed";
    throw std::invalid_argument(os.str());
  }
  std::vector<CycleResult> out;
  for (long k = 0; k < n_cycles; ++k) {
    const double a = s.t0 + static_cast<double>(k) * s.period;
    const double b = std::min(a + s.period, t.back());
    const std::vector<Frame> f = cycle_frames(t, strain, stress, a, b);
    CycleResult r;
    r.cycle = static_cast<int>(k);
    r.loop_area = loop_area(f);
    r.loop_area_j_per_cm3 = 1000.0 * r.loop_area;
    r.phase_lead = phase_lead(f, a, s.period);
    const auto [lo, hi] = std::minmax_element(
        f.begin(), f.end(), [](const Frame& p, const Frame& q) { return p.s < q.s; });
    r.peak_tension = hi->s;
    r.peak_compression = lo->s;
    const auto least = std::min_element(f.begin(), f.end(),
                                        [](const Frame& p, const Frame& q) { return p.e < q.e; });
    std::vector<double> e, sg;
    for (auto it = least; it != f.end(); ++it)
      if (it->e >= s.modulus_lo && it->e <= s.modulus_hi) {
        e.push_back(it->e);
        sg.push_back(it->s);
      }
    if (e.size() < 2) {
      std::ostringstream os;
      os << kWhere << ": cycle " << k << " has " << e.size()
         << " frame(s) on its returning half with strain in [" << s.modulus_lo << ", "
         << s.modulus_hi << "]; the modulus needs at least 2";
      throw std::invalid_argument(os.str());
    }
    const LineFit fit = fit_line(e, sg, kWhere);
    r.modulus = fit.slope;
    r.modulus_samples = fit.samples;
    out.push_back(r);
  }
  return out;
}

}  // namespace mdem
