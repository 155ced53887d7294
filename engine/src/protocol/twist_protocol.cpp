#include "mdem/protocol/twist_protocol.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "mdem/core/elements.h"
#include "mdem/core/units.h"
#include "mdem/integrate/system.h"
#include "mdem/io/state_io.h"

namespace mdem {
namespace {

// Moment of inertia of element i about the world direction n.
double inertia_about(const Elements& el, std::size_t i, const Vec3& n) {
  const Vec3 nb = el.q[i].conjugate() * n;
  return nb.dot(el.inertia[i].cwiseProduct(nb));
}

}  // namespace

std::string_view twist_phase_name(TwistPhase p) {
  switch (p) {
    case TwistPhase::Loading:
      return "loading";
    case TwistPhase::Holding:
      return "holding";
    case TwistPhase::Unloading:
      return "unloading";
    case TwistPhase::Relaxing:
      return "relaxing";
    case TwistPhase::Done:
      return "done";
  }
  return "?";
}

Vec3 mass_centroid(const Elements& el, const std::vector<std::size_t>& ids) {
  Vec3 c = Vec3::Zero();
  double m = 0;
  for (std::size_t i : ids) {
    c += el.mass[i] * el.x[i];
    m += el.mass[i];
  }
  return m > 0 ? Vec3(c / m) : c;
}

double grip_reaction_moment(const Elements& el, const std::vector<std::size_t>& grip,
                            const Vec3& axis) {
  const Vec3 n = axis.normalized(), c = mass_centroid(el, grip);
  double m = 0;
  for (std::size_t i : grip) m += n.dot((el.x[i] - c).cross(el.f[i]) + el.t[i]);
  return m;
}

TwistProtocol::TwistProtocol(TwistLoading l, std::vector<std::size_t> a, std::vector<std::size_t> b,
                             Vec3 axis)
    : loading_(l), grip_a_(std::move(a)), grip_b_(std::move(b)) {
  if (!(std::isfinite(l.torque_max) && l.torque_max > 0))
    throw std::invalid_argument("twist torque must be finite and > 0");
  if (!(std::isfinite(l.rate) && l.rate > 0))
    throw std::invalid_argument("twist torque rate must be finite and > 0");
  if (!(std::isfinite(l.hold) && l.hold >= 0 && std::isfinite(l.unload_hold) && l.unload_hold >= 0))
    throw std::invalid_argument("twist hold times must be finite and >= 0");
  if (grip_a_.empty() || grip_b_.empty())
    throw std::invalid_argument("twist grips must hold at least one element each");
  if (!(axis.allFinite() && axis.norm() > 0))
    throw std::invalid_argument("twist axis must be a finite non-zero vector");
  if (l.grip_hold == GripHold::PositionsAndSpins && l.boundary != TwistBoundary::TwistRelaxation)
    throw std::invalid_argument(
        "twist grip hold 'positions and spins' needs the twist-relaxation boundary (under a "
        "constant moment the grips are loaded, not held)");
  axis_ = axis.normalized();
}

double TwistProtocol::duration() const {
  double t = ramp_time() + loading_.hold;
  if (loading_.unload) {
    if (loading_.boundary == TwistBoundary::ConstantMoment) t += ramp_time();
    t += loading_.unload_hold;
  }
  return t;
}

TwistPhase TwistProtocol::phase_at(double t) const {
  const double t1 = ramp_time(), t2 = t1 + loading_.hold;
  if (t < t1) return TwistPhase::Loading;
  if (t < t2) return TwistPhase::Holding;
  if (!loading_.unload) return TwistPhase::Done;
  const double t3 = t2 + (loading_.boundary == TwistBoundary::ConstantMoment ? t1 : 0.0);
  if (t < t3) return TwistPhase::Unloading;
  if (t < t3 + loading_.unload_hold) return TwistPhase::Relaxing;
  return TwistPhase::Done;
}

double TwistProtocol::torque_at(double t) const {
  const TwistPhase p = phase_at(t);
  const double Tm = loading_.torque_max;
  if (p == TwistPhase::Loading) return loading_.rate * std::max(t, 0.0);
  const bool cm = loading_.boundary == TwistBoundary::ConstantMoment;
  if (p == TwistPhase::Holding || (p == TwistPhase::Done && !loading_.unload)) return cm ? Tm : 0;
  if (p == TwistPhase::Unloading)
    return std::max(0.0, Tm - loading_.rate * (t - ramp_time() - loading_.hold));
  return 0;
}

void TwistProtocol::load_grip(Elements& el, const std::vector<std::size_t>& grip,
                              double torque) const {
  if (loading_.grip_load == GripLoad::PerElement) {
    for (std::size_t i : grip) {
      el.f_ext[i].setZero();
      el.t_ext[i] = torque * axis_;
    }
    return;
  }
  const Vec3 c = mass_centroid(el, grip);
  double J = 0;
  for (std::size_t i : grip)
    J += el.mass[i] * perpendicular(el.x[i] - c, axis_).squaredNorm() + inertia_about(el, i, axis_);
  const double lambda = torque / J;
  for (std::size_t i : grip) {
    el.f_ext[i] = lambda * el.mass[i] * axis_.cross(perpendicular(el.x[i] - c, axis_));
    el.t_ext[i] = lambda * inertia_about(el, i, axis_) * axis_;
  }
}

void TwistProtocol::hold_grip(Elements& el, const std::vector<std::size_t>& grip) const {
  const bool spins = loading_.grip_hold == GripHold::PositionsAndSpins;
  for (std::size_t i : grip) {
    for (int k = 0; k < 3; ++k) el.dof[i][k] = DofMode::Prescribed;
    el.v_prescribed[i].setZero();
    if (spins) {
      for (int k = 3; k < 6; ++k) el.dof[i][k] = DofMode::Prescribed;
      el.w_prescribed[i].setZero();
    }
    el.f_ext[i].setZero();
    el.t_ext[i].setZero();
  }
}

void TwistProtocol::release_grip(Elements& el, const std::vector<std::size_t>& grip) const {
  for (std::size_t i : grip) {
    el.dof[i].fill(DofMode::Free);
    el.f_ext[i].setZero();
    el.t_ext[i].setZero();
  }
}

void TwistProtocol::apply(System& sys, double t) {
  Elements& el = sys.elements();
  const TwistPhase p = phase_at(t);
  const bool relax_bc = loading_.boundary == TwistBoundary::TwistRelaxation;
  if (relax_bc && p != last_phase_) {
    if (p == TwistPhase::Holding) {
      hold_grip(el, grip_a_);
      hold_grip(el, grip_b_);
    } else if (p == TwistPhase::Relaxing || (p == TwistPhase::Done && loading_.unload)) {
      release_grip(el, grip_a_);
      release_grip(el, grip_b_);
    }
  }
  last_phase_ = p;
  if (relax_bc && p != TwistPhase::Loading) return;
  const double torque = torque_at(t);
  load_grip(el, grip_a_, -torque);
  load_grip(el, grip_b_, torque);
}

std::optional<SpunUpGrip> TwistProtocol::spun_up_grip(const System& sys, int tube) const {
  const Elements& el = sys.elements();
  const double limit = spin_up_limit(sys);
  std::optional<SpunUpGrip> worst;
  for (const auto* grip : {&grip_a_, &grip_b_})
    for (std::size_t i : *grip) {
      if (tube >= 0 && el.tube[i] != tube) continue;
      const double m = axis_.dot(el.t_ext[i]);
      if (m == 0) continue;  // not loaded
      const double spin = (m > 0 ? 1.0 : -1.0) * axis_.dot(el.w[i]);
      if (spin > limit && (!worst || spin > worst->spin))
        worst = SpunUpGrip{i, el.tube[i], el.index[i], std::abs(m), spin};
    }
  return worst;
}

std::string TwistProtocol::explain_runaway(const System& sys, std::size_t i) const {
  const Elements& el = sys.elements();
  if (i >= el.size() || el.tube[i] < 0) return {};
  const std::optional<SpunUpGrip> g = spun_up_grip(sys, el.tube[i]);
  if (!g) return {};
  std::ostringstream m;
  m << "an applied moment of " << units::to_nNnm(g->moment) << " nN·nm on element " << g->element
    << " (tube " << g->tube << ", segment " << g->segment << ") is no longer resisted: it spins at "
    << g->spin
    << " rad/ps in the sense of the moment (its tube has unwound/separated); this is the "
       "over-twist separation the thesis reports, not a time-step problem";
  return m.str();
}

void TwistProtocol::save_state(StateWriter& w) const {
  w.begin("twist_protocol");
  const TwistLoading& l = loading_;
  w.put(l.torque_max);
  w.put(l.rate);
  w.put(l.hold);
  w.put(l.boundary);
  w.put(l.unload);
  w.put(l.unload_hold);
  w.put(l.grip_load);
  w.put(l.grip_hold);
  w.put(last_phase_);
}

void TwistProtocol::load_state(StateReader& r) {
  r.begin("twist_protocol");
  // The loading comes from the job's spec; a checkpoint of another loading would continue a
  // different experiment.
  TwistLoading s;
  s.torque_max = r.get<double>("torque_max");
  s.rate = r.get<double>("rate");
  s.hold = r.get<double>("hold");
  s.boundary = r.get<TwistBoundary>("boundary");
  s.unload = r.get_bool("unload");
  s.unload_hold = r.get<double>("unload_hold");
  s.grip_load = r.get<GripLoad>("grip_load");
  s.grip_hold = r.get<GripHold>("grip_hold");
  const TwistLoading& l = loading_;
  if (s.torque_max != l.torque_max || s.rate != l.rate || s.hold != l.hold ||
      s.boundary != l.boundary || s.unload != l.unload || s.unload_hold != l.unload_hold ||
      s.grip_load != l.grip_load || s.grip_hold != l.grip_hold)
    r.fail("loading",
           "the checkpoint's twist loading (torque, rate, hold times, boundary, grip load or "
           "grip hold) differs from this job's");
  const auto phase = r.get<TwistPhase>("last phase");
  if (static_cast<int>(phase) < 0 || static_cast<int>(phase) > static_cast<int>(TwistPhase::Done))
    r.fail("last phase", "holds an unknown phase " + std::to_string(static_cast<int>(phase)));
  last_phase_ = phase;
}

}  // namespace mdem
