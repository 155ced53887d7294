// Tensile and cyclic grips (tensile_protocol.h, tensile.md §3.5–3.6).
#include "mdem/protocol/tensile_protocol.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "mdem/core/elements.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/force_model.h"
#include "mdem/integrate/system.h"
#include "mdem/io/state_io.h"
#include "mdem/observe/percentile.h"

namespace mdem {
namespace {

[[noreturn]] void bad_field(std::string_view field, std::string_view range, double got) {
  std::ostringstream m;
  m << "tensile loading " << field << " must be " << range << ", got " << got;
  throw std::invalid_argument(m.str());
}

void require_positive(double v, std::string_view field, std::string_view unit) {
  if (!(std::isfinite(v) && v > 0))
    bad_field(field, "finite and > 0" + std::string(unit.empty() ? "" : " ") + std::string(unit),
              v);
}

// S(τ) = τ³ − τ⁴/2: the ramp's strain over ε̇ t_a (the integral of the smoothstep).
double ramp_integral(double tau) { return tau * tau * tau - 0.5 * tau * tau * tau * tau; }
double smoothstep(double tau) { return tau * tau * (3.0 - 2.0 * tau); }

// Clamps the grip elements ids (x velocity v.x(), y and z velocities 0, rotations fixed), whose
// tags must be tags, in order; false when an index no longer holds its tag (that element is left
// alone). Threaded: a grip of the medium film holds ~4800 elements, written every step.
bool clamp_grip(Elements& el, const std::vector<std::size_t>& ids,
                const std::vector<std::uint64_t>& tags, const Vec3& v) {
  const long n = static_cast<long>(ids.size());
  const std::size_t size = el.size();
  bool ok = true;
#pragma omp parallel for schedule(static) reduction(&& : ok) if (n >= kParallelMinItems)
  for (long k = 0; k < n; ++k) {
    const std::size_t i = ids[k];
    if (i >= size || el.tag[i] != tags[k]) {
      ok = false;
      continue;
    }
    auto& dof = el.dof[i];
    for (int d = 0; d < 3; ++d) {
      dof[d] = DofMode::Prescribed;
      dof[d + 3] = DofMode::Fixed;
    }
    el.v_prescribed[i] = v;
  }
  return ok;
}

}  // namespace

GripSelection select_grips(Elements& el, const GripSettings& s) {
  if (!(std::isfinite(s.min_fraction) && s.min_fraction >= 0 && s.min_fraction < 1))
    throw std::invalid_argument("grip min_fraction must be in [0, 1), got " +
                                std::to_string(s.min_fraction));
  if (!(std::isfinite(s.width) && s.width > 0))
    throw std::invalid_argument("grip width must be finite and > 0 nm, got " +
                                std::to_string(s.width));
  if (el.groups.has(kGripLeft) || el.groups.has(kGripRight))
    throw std::invalid_argument("grips: the groups " + std::string(kGripLeft) + " and " +
                                std::string(kGripRight) + " are declared already");
  std::vector<double> xs;
  for (std::size_t i = 0; i < el.size(); ++i)
    if (el.kind[i] == ElementKind::CntSegment) xs.push_back(el.x[i].x());
  if (xs.empty())
    throw std::invalid_argument("grips: the film has no CNT segment to place them by");
  GripSelection g;
  g.x_lo = percentile(xs, 0.5, "segment-centre x");
  g.x_hi = percentile(xs, 99.5, "segment-centre x");
  const double span = g.x_hi - g.x_lo;
  if (2.0 * s.width >= span) {
    std::ostringstream m;
    m << "grip width must be < half the film's extent in x ((x_hi - x_lo)/2 = " << 0.5 * span
      << " nm, between the 0.5th and 99.5th percentiles of segment-centre x), got " << s.width
      << " nm: the grips would meet";
    throw std::invalid_argument(m.str());
  }
  std::vector<std::uint64_t> left_tags, right_tags;
  for (std::size_t i = 0; i < el.size(); ++i) {
    const double x = el.x[i].x();
    if (x <= g.x_lo + s.width) {
      g.left.push_back(i);
      left_tags.push_back(el.tag[i]);
    } else if (x >= g.x_hi - s.width) {
      g.right.push_back(i);
      right_tags.push_back(el.tag[i]);
    }
  }
  const double need = s.min_fraction * static_cast<double>(el.size());
  for (const auto* side : {&g.left, &g.right}) {
    if (static_cast<double>(side->size()) < need || side->empty()) {
      std::ostringstream m;
      m << "grips: the " << (side == &g.left ? "left" : "right") << " grip holds " << side->size()
        << " of " << el.size() << " elements, fewer than min_fraction = " << s.min_fraction
        << " of them (" << need << "); widen the grips (width " << s.width
        << " nm) or check the film";
      throw std::invalid_argument(m.str());
    }
  }
  el.groups.add(std::string(kGripLeft), std::move(left_tags));
  el.groups.add(std::string(kGripRight), std::move(right_tags));
  return g;
}

TensileProtocol::TensileProtocol(TensileLoading l) : loading_(l) {
  require_positive(l.length, "length", "nm");
  if (l.mode == TensileMode::Monotonic) {
    require_positive(l.monotonic.strain_rate, "strain_rate", "/ps");
    require_positive(l.monotonic.ramp_time, "ramp_time", "ps");
    require_positive(l.monotonic.target_strain, "target_strain", "");
  } else {
    const CyclicLoading& c = l.cyclic;
    if (!(std::isfinite(c.amplitude) && c.amplitude > 0 && c.amplitude < 1))
      bad_field("amplitude", "finite and in (0, 1)", c.amplitude);
    if (!std::isfinite(c.mean_rate) || c.mean_rate < 0)
      bad_field("mean_rate", "finite and > 0 /ps (or 0 when period is given)", c.mean_rate);
    if (!std::isfinite(c.period) || c.period < 0)
      bad_field("period", "finite and > 0 ps (or 0 when mean_rate is given)", c.period);
    if ((c.mean_rate > 0) == (c.period > 0))
      throw std::invalid_argument(
          "tensile loading: exactly one of mean_rate (/ps) and period (ps) must be > 0 for a "
          "cyclic test, "
          "got mean_rate = " +
          std::to_string(c.mean_rate) + " and period = " + std::to_string(c.period));
    if (c.cycles < 1) bad_field("cycles", ">= 1", c.cycles);
  }
}

double TensileProtocol::period() const {
  if (loading_.mode != TensileMode::Cyclic) return 0;
  const CyclicLoading& c = loading_.cyclic;
  return c.period > 0 ? c.period : 2.0 * c.amplitude / c.mean_rate;
}

double TensileProtocol::duration() const {
  if (loading_.mode == TensileMode::Cyclic) return loading_.cyclic.cycles * period();
  return time_to_strain(loading_.monotonic.target_strain);
}

double TensileProtocol::strain_after(double s) const {
  if (!(s > 0)) return 0;
  if (loading_.mode == TensileMode::Cyclic) {
    if (s >= duration()) return 0;
    const double a = loading_.cyclic.amplitude;
    return -0.5 * a * (1.0 - std::cos(2.0 * std::numbers::pi * s / period()));
  }
  const double rate = loading_.monotonic.strain_rate, ta = loading_.monotonic.ramp_time;
  if (s < ta) return rate * ta * ramp_integral(s / ta);
  return rate * (s - 0.5 * ta);
}

double TensileProtocol::strain_rate_after(double s) const {
  if (!(s > 0)) return 0;
  if (loading_.mode == TensileMode::Cyclic) {
    if (s >= duration()) return 0;
    const double a = loading_.cyclic.amplitude, w = 2.0 * std::numbers::pi / period();
    return -0.5 * a * w * std::sin(w * s);
  }
  const double rate = loading_.monotonic.strain_rate, ta = loading_.monotonic.ramp_time;
  return s < ta ? rate * smoothstep(s / ta) : rate;
}

double TensileProtocol::time_to_strain(double strain) const {
  if (loading_.mode == TensileMode::Cyclic) return duration();
  if (!(std::isfinite(strain) && strain > 0))
    throw std::invalid_argument("time_to_strain: strain must be finite and > 0, got " +
                                std::to_string(strain));
  const double rate = loading_.monotonic.strain_rate, ta = loading_.monotonic.ramp_time;
  const double at_ramp_end = 0.5 * rate * ta;
  if (strain >= at_ramp_end) return 0.5 * ta + strain / rate;
  // S is increasing on [0, 1]: bisect S(τ) = ε/(ε̇ t_a) to the last bit.
  const double target = strain / (rate * ta);
  double lo = 0, hi = 1;
  for (int k = 0; k < 80 && hi - lo > 0; ++k) {
    const double mid = 0.5 * (lo + hi);
    (ramp_integral(mid) < target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi) * ta;
}

double TensileProtocol::grip_velocity(double s, double dt) const {
  if (dt > 0) return 0.5 * loading_.length * (strain_after(s + dt) - strain_after(s)) / dt;
  return 0.5 * loading_.length * strain_rate_after(s);
}

void TensileProtocol::start(System& sys) {
  start_ = sys.time();
  started_ = true;
  apply(sys, sys.time());
}

void TensileProtocol::apply(System& sys, double t) {
  if (!started_) {
    start_ = t;
    started_ = true;
  }
  Elements& el = sys.elements();
  double dt = sys.dt();
  if (!(dt > 0) && sys.settings().dt) dt = *sys.settings().dt;
  const double v = grip_velocity(elapsed(t), dt);
  const std::vector<std::uint64_t>* tags[2] = {&el.groups.get(kGripLeft),
                                               &el.groups.get(kGripRight)};
  // The indices kept from the step before, each checked against its tag as it is used: found
  // anew when any is stale (the first step, another system, elements reordered behind the
  // protocol's back). Clamping is idempotent, so a partly done first try does no harm.
  for (int attempt = 0; attempt < 2; ++attempt) {
    bool ok = true;
    for (int g = 0; g < 2; ++g)
      ok = grip_[g].size() == tags[g]->size() &&
           clamp_grip(el, grip_[g], *tags[g], Vec3(g == 0 ? -v : v, 0, 0)) && ok;
    if (ok) return;
    for (int g = 0; g < 2; ++g) grip_[g] = el.group_indices(g == 0 ? kGripLeft : kGripRight);
  }
}

void TensileProtocol::reorder(std::span<const std::uint32_t> old_to_new) {
  for (auto& ids : grip_)
    for (std::size_t& i : ids)
      if (i < old_to_new.size()) i = old_to_new[i];  // out of range: stale, found anew
}

std::string TensileProtocol::phase(double t) const {
  const double s = elapsed(t);
  if (loading_.mode == TensileMode::Monotonic)
    return s < loading_.monotonic.ramp_time ? "ramp" : "straining";
  const int n = loading_.cyclic.cycles;
  if (s >= duration()) return "done";
  const int k = std::min(n, static_cast<int>(std::floor(std::max(s, 0.0) / period())) + 1);
  return "cycle " + std::to_string(k) + "/" + std::to_string(n);
}

std::string TensileProtocol::explain_runaway(const System& sys, std::size_t i) const {
  const auto* bonds = sys.find<ParallelBond>();
  if (!bonds) return {};
  const Elements& el = sys.elements();
  const Bond* worst = nullptr;
  double gap = 0, rest = 0;  // the bond points' separation (0 at rest) and the rest length (nm)
  for (const Bond& b : bonds->bonds()) {
    if (b.i != i && b.j != i) continue;
    const BondDeformation d = bond_deformation(b, el.x[b.i], el.q[b.i], el.x[b.j], el.q[b.j]);
    const double g = std::hypot(d.u_n, d.u_s.norm());
    if (g > gap) worst = &b, gap = g, rest = b.ci.norm() + b.cj.norm();
  }
  if (!worst || !(gap > rest)) return {};
  const BondResult r =
      bond_eval(*worst, el.x[worst->i], el.q[worst->i], el.x[worst->j], el.q[worst->j]);
  std::ostringstream m;
  m << "its bond to element " << (worst->i == i ? worst->j : worst->i) << " is drawn out by " << gap
    << " nm (" << gap / rest << " x its rest length " << rest << " nm) under "
    << units::to_nN(r.fi.norm()) << " nN at " << 100 * strain(sys.time())
    << " % strain: the model's bonds never break, so past the film's failure a piece held by "
       "both grips is stretched far beyond a CNT's failure strain, and the bond's load stiffens "
       "its rotation (force x lever arm) past the step picked at the test's start. Results past "
       "the film's failure are outside the model: lower the target strain (or lower safety to "
       "follow it further)";
  return m.str();
}

void TensileProtocol::save_state(StateWriter& w) const {
  w.begin("tensile_protocol");
  const TensileLoading& l = loading_;
  w.put(l.mode);
  w.put(l.length);
  w.put(l.monotonic.strain_rate);
  w.put(l.monotonic.ramp_time);
  w.put(l.monotonic.target_strain);
  w.put(l.cyclic.amplitude);
  w.put(l.cyclic.mean_rate);
  w.put(l.cyclic.period);
  w.put(l.cyclic.cycles);
  w.put(started_);
  w.put(start_);
}

void TensileProtocol::load_state(StateReader& r) {
  r.begin("tensile_protocol");
  // The loading comes from the job's spec; a checkpoint of another loading would continue a
  // different experiment.
  TensileLoading s;
  s.mode = r.get<TensileMode>("mode");
  s.length = r.get<double>("length");
  s.monotonic.strain_rate = r.get<double>("strain_rate");
  s.monotonic.ramp_time = r.get<double>("ramp_time");
  s.monotonic.target_strain = r.get<double>("target_strain");
  s.cyclic.amplitude = r.get<double>("amplitude");
  s.cyclic.mean_rate = r.get<double>("mean_rate");
  s.cyclic.period = r.get<double>("period");
  s.cyclic.cycles = r.get<int>("cycles");
  const TensileLoading& l = loading_;
  if (s.mode != l.mode || s.length != l.length ||
      s.monotonic.strain_rate != l.monotonic.strain_rate ||
      s.monotonic.ramp_time != l.monotonic.ramp_time ||
      s.monotonic.target_strain != l.monotonic.target_strain ||
      s.cyclic.amplitude != l.cyclic.amplitude || s.cyclic.mean_rate != l.cyclic.mean_rate ||
      s.cyclic.period != l.cyclic.period || s.cyclic.cycles != l.cyclic.cycles)
    r.fail("loading",
           "the checkpoint's tensile loading (mode, length, rates, ramp, target, amplitude, "
           "period or cycles) differs from this job's");
  started_ = r.get_bool("started");
  start_ = r.get<double>("start");
}

}  // namespace mdem
