#include "mdem/job/twist_job.h"

#include <cmath>
#include <numbers>

#include "mdem/core/cnt.h"
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
  separation_ = std::make_shared<OverTwistSeparation>(protocol_);
  stage.stop = StopCondition::after_unless(protocol_->duration(), separation_,
                                           OverTwistSeparation::kCheckEvery);
  add_stage(std::make_unique<SystemStage>("twist", *this, std::move(stage)));
  add_state(peaks_);
}

OverTwistSeparation::OverTwistSeparation(std::shared_ptr<const TwistProtocol> protocol)
    : protocol_(std::move(protocol)) {}

bool OverTwistSeparation::met(const System& sys) {
  if (time_) return true;
  const TwistPhase p = protocol_->phase_at(sys.time());
  const bool loaded =
      p == TwistPhase::Loading ||
      (p == TwistPhase::Holding && protocol_->loading().boundary == TwistBoundary::ConstantMoment);
  const std::optional<SpunUpGrip> g = loaded ? protocol_->spun_up_grip(sys) : std::nullopt;
  in_a_row_ = g ? in_a_row_ + 1 : 0;
  if (in_a_row_ < kChecksInARow) return false;
  time_ = sys.time();
  grip_ = *g;
  return true;
}

void OverTwistSeparation::save_state(StateWriter& w) const {
  w.begin("over_twist");
  w.put(in_a_row_);
  w.put(time_.has_value());
  w.put(time_.value_or(0.0));
  w.put(grip_.element);
  w.put(grip_.tube);
  w.put(grip_.segment);
  w.put(grip_.moment);
  w.put(grip_.spin);
}

void OverTwistSeparation::load_state(StateReader& r) {
  r.begin("over_twist");
  in_a_row_ = r.get<int>("checks in a row");
  const bool separated = r.get_bool("separated");
  const double t = r.get<double>("separation time");
  time_ = separated ? std::optional<double>(t) : std::nullopt;
  grip_.element = r.get<std::size_t>("element");
  grip_.tube = r.get<int>("tube");
  grip_.segment = r.get<int>("segment");
  grip_.moment = r.get<double>("moment");
  grip_.spin = r.get<double>("spin");
  if (in_a_row_ < 0 || in_a_row_ > kChecksInARow || !std::isfinite(t))
    r.fail("checks in a row", "holds an impossible over-twist state");
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
               {"separated_tube", static_cast<long>(sep.time() ? sep.grip().tube : -1)},
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
