#include "mdem/job/twist_job.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "mdem/core/cnt.h"
#include "mdem/core/elements.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/scene/bundle_scene.h"

namespace mdem {
namespace {

System build_system(const TwistJobSpec& spec, IntegratorSettings settings, Rope& rope) {
  Elements el;
  rope = build_hex_rope(el, spec.rope);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  if (spec.temperature_k > 0) {
    // Equipartition: ½ m <v_k²> = ½ kB T per component, likewise for the spins.
    const double kT = units::kBoltzmann * spec.temperature_k;
    randomize_motion(el, std::sqrt(kT / cnt::kMass), std::sqrt(kT / cnt::kInertia), spec.seed);
  }
  System sys(std::move(el), settings);
  sys.add(std::move(bonds));
  sys.add(std::make_unique<AnisotropicVdw>());
  if (spec.vdw_damping_ratio > 0) {
    ContactDampingParams d;
    d.ratio = spec.vdw_damping_ratio;
    sys.add(std::make_unique<ViscousContactDamping>(d));
  }
  return sys;
}

}  // namespace

TwistJob::TwistJob(const TwistJobSpec& spec, IntegratorSettings settings)
    : sys_(build_system(spec, settings, rope_)) {
  protocol_ =
      std::make_shared<TwistProtocol>(spec.loading, sys_.elements().group_indices(kRopeGripA),
                                      sys_.elements().group_indices(kRopeGripB));
  shift_ = std::make_shared<ShiftAngleSampler>(sys_.elements(), rope_);
  peaks_ = std::make_shared<Peaks>();
  SystemStage::Settings stage;
  stage.protocol = protocol_;
  stage.observers = {shift_};
  separation_ = std::make_shared<OverTwistSeparation>(protocol_, sys_.elements());
  stage.stop = StopCondition::after_unless(protocol_->duration(), separation_,
                                           OverTwistSeparation::kCheckEvery);
  add_stage(std::make_unique<SystemStage>("twist", *this, std::move(stage)));
  add_state(peaks_);
}

OverTwistSeparation::OverTwistSeparation(std::shared_ptr<const TwistProtocol> protocol,
                                         const Elements& el)
    : protocol_(std::move(protocol)) {
  grips_ = protocol_->grip_a();
  grips_.insert(grips_.end(), protocol_->grip_b().begin(), protocol_->grip_b().end());
  int tubes = 0;
  for (std::size_t i = 0; i < el.size(); ++i) tubes = std::max(tubes, el.tube[i] + 1);
  for (std::size_t i : grips_)
    if (i >= el.size())
      throw std::invalid_argument("over-twist check: grip element " + std::to_string(i) +
                                  " is not among the " + std::to_string(el.size()) + " elements");
  const std::size_t n = grips_.size(), t = static_cast<std::size_t>(tubes);
  last_x_.assign(n, Vec3::Zero());
  last_f_.assign(n, Vec3::Zero());
  last_t_.assign(n, Vec3::Zero());
  last_q_.assign(n, Quat::Identity());
  work_.assign(t, 0.0);
  kinetic_.assign(t, 0.0);
  ring_work_.assign(t * (kWindowChecks + 1), 0.0);
  ring_kinetic_.assign(t * (kWindowChecks + 1), 0.0);
  ring_bending_.assign(kWindowChecks + 1, 0.0);
  held_.assign(t, 0);
}

int OverTwistSeparation::tube() const {
  if (rule_ == OverTwistRule::UnresistedWork) return unresisted_.tube;
  if (rule_ == OverTwistRule::SpinUp) return grip_.tube;
  return -1;
}

void OverTwistSeparation::book(const System& sys) {
  const Elements& el = sys.elements();
  for (std::size_t g = 0; g < grips_.size(); ++g) {
    const std::size_t i = grips_[g];
    if (checks_ > 0) {
      const int k = el.tube[i];
      // Trapezoid in the loads (exact under a held load, second order on the ramp) times the
      // displacement and the net rotation since the last check. The net rotation is the integral
      // of ω only while the spin axis holds still and the turn stays below pi (10 steps at the
      // backstop's 0.25 rad a step: 2.5 rad); a grip tumbling fast makes the books drift from
      // the integrator's t_ext·ω (docs/twist.md), which the rule's window trend tolerates.
      const Vec3 dx = el.x[i] - last_x_[g];
      const Vec3 dphi = quat_log(el.q[i] * last_q_[g].conjugate());
      const double dw =
          0.5 * ((last_f_[g] + el.f_ext[i]).dot(dx) + (last_t_[g] + el.t_ext[i]).dot(dphi));
      if (k >= 0) work_[static_cast<std::size_t>(k)] += dw;
    }
    last_x_[g] = el.x[i];
    last_q_[g] = el.q[i];
    last_f_[g] = el.f_ext[i];
    last_t_[g] = el.t_ext[i];
  }
  std::fill(kinetic_.begin(), kinetic_.end(), 0.0);
  for (std::size_t i = 0; i < el.size(); ++i) {
    if (el.tube[i] < 0) continue;
    const Vec3 wb = el.q[i].conjugate() * el.w[i];
    kinetic_[static_cast<std::size_t>(el.tube[i])] +=
        0.5 * (el.mass[i] * el.v[i].squaredNorm() + wb.dot(el.inertia[i].cwiseProduct(wb)));
  }
  const std::size_t t = work_.size();
  const std::size_t head = static_cast<std::size_t>(checks_ % (kWindowChecks + 1)) * t;
  std::copy(work_.begin(), work_.end(), ring_work_.begin() + static_cast<long>(head));
  std::copy(kinetic_.begin(), kinetic_.end(), ring_kinetic_.begin() + static_cast<long>(head));
  ring_bending_[static_cast<std::size_t>(checks_ % (kWindowChecks + 1))] =
      sys.energy().potential.stored[static_cast<int>(EnergyTerm::BondBending)];
  ++checks_;
  last_book_ps_ = sys.time();
}

bool OverTwistSeparation::unresisted_work(const System& sys, bool loaded) {
  if (!loaded || checks_ <= kWindowChecks) {
    std::fill(held_.begin(), held_.end(), 0);
    return false;
  }
  const std::size_t t = work_.size();
  const double check_ps = kCheckEvery * sys.dt();
  const double window = kWindowChecks * std::ceil(kBookEveryPs / check_ps - 1e-9) * check_ps;
  // The oldest slot of the ring (the booking kWindowChecks bookings ago) and its offset.
  const std::size_t slot = static_cast<std::size_t>(checks_ % (kWindowChecks + 1));
  const std::size_t then = slot * t;
  const std::size_t now = (slot + kWindowChecks) % (kWindowChecks + 1);
  const double bending_rise = ring_bending_[now] - ring_bending_[slot];
  double rope_work = 0;
  for (std::size_t k = 0; k < t; ++k) rope_work += work_[k] - ring_work_[then + k];
  const bool not_bending = bending_rise < rope_work;
  int fired = -1, worst = -1;
  double worst_ratio = 0;
  for (std::size_t k = 0; k < t; ++k) {
    const double dw = work_[k] - ring_work_[then + k];
    const double dk = kinetic_[k] - ring_kinetic_[then + k];
    const bool holds = not_bending && dw > 0 && dw > kMinWorkFraction * std::abs(work_[k]) &&
                       dk >= kUnresistedFraction * dw;
    held_[k] = holds ? std::min(held_[k] + 1, kSustainChecks) : 0;
    if (fired < 0 && held_[k] >= kSustainChecks) fired = static_cast<int>(k);
    if (dw > 0 && (worst < 0 || dk / dw > worst_ratio)) {
      worst = static_cast<int>(k);
      worst_ratio = dk / dw;
    }
  }
  const int k = fired >= 0 ? fired : worst;
  if (k < 0) {
    unresisted_ = UnresistedTube{};
  } else {
    const std::size_t u = static_cast<std::size_t>(k);
    unresisted_ = {k,
                   window,
                   work_[u] - ring_work_[then + u],
                   kinetic_[u] - ring_kinetic_[then + u],
                   kinetic_[u],
                   work_[u],
                   rope_work,
                   bending_rise};
  }
  return fired >= 0;
}

bool OverTwistSeparation::met(const System& sys) {
  if (time_) return true;
  const TwistPhase p = protocol_->phase_at(sys.time());
  const bool loaded =
      p == TwistPhase::Loading ||
      (p == TwistPhase::Holding && protocol_->loading().boundary == TwistBoundary::ConstantMoment);
  // The rule is for the per-element load, where each tube stores its own grip's work as
  // torsion. Under the rigid grip the rope turns as a whole about its axis, a soft mode that
  // turns much of the work into the tubes' motion in every ramp (the README's 37-tube rope at
  // 20 nN·nm fired it), so there the spin-up backstop alone decides and nothing is booked.
  const bool per_element = protocol_->loading().grip_load == GripLoad::PerElement;
  const bool due =
      per_element && (checks_ == 0 || sys.time() >= last_book_ps_ + kBookEveryPs - 1e-9);
  if (due) book(sys);
  if (due && unresisted_work(sys, loaded)) {
    time_ = sys.time();
    rule_ = OverTwistRule::UnresistedWork;
    return true;
  }
  const std::optional<SpunUpGrip> g = loaded ? protocol_->spun_up_grip(sys) : std::nullopt;
  in_a_row_ = g ? in_a_row_ + 1 : 0;
  if (in_a_row_ < kChecksInARow) return false;
  time_ = sys.time();
  rule_ = OverTwistRule::SpinUp;
  grip_ = *g;
  return true;
}

void OverTwistSeparation::save_state(StateWriter& w) const {
  w.begin("over_twist");
  w.put(in_a_row_);
  w.put(time_.has_value());
  w.put(time_.value_or(0.0));
  w.put(rule_);
  w.put(grip_.element);
  w.put(grip_.tube);
  w.put(grip_.segment);
  w.put(grip_.moment);
  w.put(grip_.spin);
  w.put(checks_);
  w.put(last_book_ps_);
  w.put(last_x_);
  w.put(last_q_);
  w.put(last_f_);
  w.put(last_t_);
  w.put(work_);
  w.put(kinetic_);
  w.put(ring_work_);
  w.put(ring_kinetic_);
  w.put(ring_bending_);
  w.put(held_);
  w.put(unresisted_.tube);
  w.put(unresisted_.window_ps);
  w.put(unresisted_.work);
  w.put(unresisted_.kinetic_rise);
  w.put(unresisted_.kinetic);
  w.put(unresisted_.total_work);
  w.put(unresisted_.rope_work);
  w.put(unresisted_.rope_bending_rise);
}

void OverTwistSeparation::load_state(StateReader& r) {
  r.begin("over_twist");
  in_a_row_ = r.get<int>("checks in a row");
  const bool separated = r.get_bool("separated");
  const double t = r.get<double>("separation time");
  const auto rule = r.get<OverTwistRule>("rule");
  grip_.element = r.get<std::size_t>("element");
  grip_.tube = r.get<int>("tube");
  grip_.segment = r.get<int>("segment");
  grip_.moment = r.get<double>("moment");
  grip_.spin = r.get<double>("spin");
  if (in_a_row_ < 0 || in_a_row_ > kChecksInARow || !std::isfinite(t))
    r.fail("checks in a row", "holds an impossible over-twist state");
  const int ri = static_cast<int>(rule);
  if (ri < 0 || ri > static_cast<int>(OverTwistRule::SpinUp) ||
      (separated != (rule != OverTwistRule::None)))
    r.fail("rule", "holds rule " + std::to_string(ri) + (separated ? " for" : " without") +
                       " a separation (allowed: 0 none without one, 1 unresisted work or 2 spin-up "
                       "with one)");
  time_ = separated ? std::optional<double>(t) : std::nullopt;
  rule_ = rule;
  checks_ = r.get<long>("checks");
  last_book_ps_ = r.get<double>("last booking time");
  if (!std::isfinite(last_book_ps_) || last_book_ps_ < 0)
    r.fail("last booking time",
           "holds " + std::to_string(last_book_ps_) + " ps (allowed: a finite time >= 0)");
  if (checks_ < 0) r.fail("checks", "holds " + std::to_string(checks_) + " checks (allowed: >= 0)");
  const std::size_t n = grips_.size(), nt = work_.size(), ring = nt * (kWindowChecks + 1);
  r.get(last_x_, "grip positions", n);
  r.get(last_q_, "grip orientations", n);
  r.get(last_f_, "grip forces", n);
  r.get(last_t_, "grip torques", n);
  r.get(work_, "tube work", nt);
  r.get(kinetic_, "tube kinetic energy", nt);
  r.get(ring_work_, "window work", ring);
  r.get(ring_kinetic_, "window kinetic energy", ring);
  r.get(ring_bending_, "window bending energy", kWindowChecks + 1);
  r.get(held_, "checks the rule held", nt);
  auto finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  };
  auto finite_vec = [](const std::vector<Vec3>& v) {
    return std::all_of(v.begin(), v.end(), [](const Vec3& x) { return x.allFinite(); });
  };
  const bool finite_q = std::all_of(last_q_.begin(), last_q_.end(),
                                    [](const Quat& q) { return q.coeffs().allFinite(); });
  if (!finite_vec(last_x_) || !finite_vec(last_f_) || !finite_vec(last_t_) || !finite_q)
    r.fail("grip positions", "holds a non-finite position, orientation or load");
  if (!finite(work_) || !finite(kinetic_) || !finite(ring_work_) || !finite(ring_kinetic_) ||
      !finite(ring_bending_))
    r.fail("tube work", "holds a non-finite work or kinetic energy");
  if (std::any_of(kinetic_.begin(), kinetic_.end(), [](double k) { return k < 0; }) ||
      std::any_of(ring_kinetic_.begin(), ring_kinetic_.end(), [](double k) { return k < 0; }))
    r.fail("tube kinetic energy", "holds a negative kinetic energy");
  if (std::any_of(held_.begin(), held_.end(), [](int h) { return h < 0 || h > kSustainChecks; }))
    r.fail("checks the rule held", "holds a count outside 0.." + std::to_string(kSustainChecks));
  unresisted_.tube = r.get<int>("unresisted tube");
  unresisted_.window_ps = r.get<double>("window");
  unresisted_.work = r.get<double>("window work");
  unresisted_.kinetic_rise = r.get<double>("window kinetic rise");
  unresisted_.kinetic = r.get<double>("tube kinetic energy now");
  unresisted_.total_work = r.get<double>("tube total work");
  unresisted_.rope_work = r.get<double>("rope window work");
  unresisted_.rope_bending_rise = r.get<double>("rope window bending rise");
  if (unresisted_.tube < -1 || unresisted_.tube >= static_cast<int>(nt))
    r.fail("unresisted tube", "names tube " + std::to_string(unresisted_.tube) + " of " +
                                  std::to_string(nt) + " (allowed: -1 for none, 0.." +
                                  std::to_string(static_cast<int>(nt) - 1) + ")");
}

void TwistJob::Peaks::save_state(StateWriter& w) const {
  w.begin("twist_peaks");
  w.put(max_charge);
  w.put(twist);
  w.put(shift);
}

void TwistJob::Peaks::load_state(StateReader& r) {
  r.begin("twist_peaks");
  max_charge = r.get<int>("max_charge");
  twist = r.get<double>("peak_twist");
  shift = r.get<double>("peak_shift");
}

std::vector<EnergyTerm> TwistJob::energy_terms() {
  return {EnergyTerm::BondTension, EnergyTerm::BondShear, EnergyTerm::BondBending,
          EnergyTerm::BondTorsion, EnergyTerm::Vdw};
}

TwistReport TwistJob::report() {
  const Elements& el = sys_.elements();
  const RopeAxis axis = rope_axis(el, rope_);
  const double shift_angle = shift_->sample(el);
  const RopeShape shape = rope_shape(el, rope_, axis);
  TwistReport r;
  r.applied_torque_nNnm = units::to_nNnm(protocol_->torque_at(sys_.time()));
  r.grip_reaction_nNnm =
      units::to_nNnm(0.5 * (grip_reaction_moment(el, el.group_indices(kRopeGripA), axis.dir) -
                            grip_reaction_moment(el, el.group_indices(kRopeGripB), axis.dir)));
  r.twist_angle_deg = shape.twist_angle_deg;
  r.shift_angle_deg = shift_angle * 180.0 / std::numbers::pi;
  r.rope_radius_nm = shape.radius;
  r.length_nm = axis.length;
  r.core_void_nm = shape.core_void_radius;
  r.axis_deviation_nm = shape.axis_deviation;
  r.clusters = shape.clusters;
  r.topological_charge = rope_topological_charge(el, rope_, axis).charge;
  r.morphology = classify_morphology(shape, rope_);
  Peaks& p = *peaks_;
  p.max_charge = std::max(p.max_charge, r.topological_charge);
  p.twist = std::max(p.twist, r.twist_angle_deg);
  p.shift = std::max(p.shift, std::abs(r.shift_angle_deg));
  return r;
}

std::vector<std::string> TwistJob::columns() const {
  std::vector<std::string> c = energy_columns(energy_terms());
  for (const char* n : {"applied_torque_nNnm", "grip_reaction_nNnm", "twist_angle_deg",
                        "shift_angle_deg", "rope_radius_nm", "length_nm", "core_void_nm",
                        "axis_deviation_nm", "clusters", "topological_charge", "morphology_code"})
    c.emplace_back(n);
  return c;
}

std::vector<double> TwistJob::observe() {
  std::vector<double> v = energy_values(sys_, energy_terms());
  const TwistReport r = report();
  v.insert(v.end(),
           {r.applied_torque_nNnm, r.grip_reaction_nNnm, r.twist_angle_deg, r.shift_angle_deg,
            r.rope_radius_nm, r.length_nm, r.core_void_nm, r.axis_deviation_nm,
            static_cast<double>(r.clusters), static_cast<double>(r.topological_charge),
            static_cast<double>(static_cast<int>(r.morphology))});
  return v;
}

Summary TwistJob::summary() {
  const TwistReport r = report();
  const OverTwistSeparation& sep = *separation_;
  Summary s = {{"outcome", std::string(sep.time() ? "separated_by_over_twist" : "completed")},
               {"outcome_time_ps", sep.time().value_or(sys_.time())},
               {"separated_tube", static_cast<long>(sep.tube())},
               {"morphology", std::string(morphology_name(r.morphology))},
               {"twist_angle_deg", r.twist_angle_deg},
               {"shift_angle_deg", r.shift_angle_deg},
               {"topological_charge", static_cast<long>(r.topological_charge)},
               {"max_topological_charge", static_cast<long>(peaks_->max_charge)},
               {"peak_twist_angle_deg", peaks_->twist},
               {"peak_shift_angle_deg", peaks_->shift},
               {"rope_radius_nm", r.rope_radius_nm},
               {"initial_rope_radius_nm", rope_.initial_radius},
               {"length_nm", r.length_nm},
               {"core_void_nm", r.core_void_nm},
               {"axis_deviation_nm", r.axis_deviation_nm},
               {"applied_torque_nNnm", r.applied_torque_nNnm},
               {"grip_reaction_nNnm", r.grip_reaction_nNnm},
               {"tubes", static_cast<long>(rope_.tubes.size())},
               {"elements", static_cast<long>(sys_.elements().size())},
               {"spacing_nm", rope_.lattice.spacing},
               {"simulated_ps", sys_.time()}};
  return s;
}

}  // namespace mdem
