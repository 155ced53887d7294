// The twist kind in the jobs layer: TwistSpec -> TwistJob, its element bound and its summary.
#include <algorithm>
#include <cmath>

#include "mdem/core/units.h"
#include "mdem/job/twist_job.h"
#include "mdem/job_kinds.h"
#include "mdem/spec.h"
#include "mdem/spec_job.h"
#include "mdem/spec_rules.h"

namespace mdem {

TwistJobSpec twist_job_spec(const v1::JobSpec& spec) {
  const v1::TwistSpec& t = spec.twist();
  TwistJobSpec job;
  RopeSpec& r = job.rope;
  r.layers = t.layers();
  r.segments = std::max(2, static_cast<int>(std::lround(t.length_nm() / spec::kSegmentNm)));
  r.spacing = t.has_spacing_nm() ? t.spacing_nm() : 0.0;
  r.missing.assign(t.missing_tubes().begin(), t.missing_tubes().end());
  for (const v1::LineDefect& d : t.line_defects())
    r.lines.push_back({d.angle_deg(), d.width(), d.length_fraction()});
  r.grip_segments = t.grip_segments();
  TwistLoading& l = job.loading;
  l.torque_max = units::nNnm(t.torque_nn_nm());
  l.rate = units::nNnm(t.torque_rate_nn_nm_per_ps());
  l.hold = t.hold_ps();
  l.boundary = t.boundary() == v1::TWIST_RELAXATION ? TwistBoundary::TwistRelaxation
                                                    : TwistBoundary::ConstantMoment;
  l.grip_load = t.grip_load() == v1::PER_ELEMENT ? GripLoad::PerElement : GripLoad::RigidGrip;
  l.grip_hold = t.grip_hold() == v1::HOLD_POSITIONS_AND_SPINS ? GripHold::PositionsAndSpins
                                                              : GripHold::Positions;
  l.unload = t.unload();
  l.unload_hold = t.unload_hold_ps();
  job.vdw_damping_ratio = t.vdw_damping_ratio();
  job.temperature_k = t.temperature_k();
  job.seed = static_cast<unsigned>(spec.seed());
  return job;
}

JobKind twist_job_kind() {
  JobKind k;
  k.name = "twist";
  k.kind_case = v1::JobSpec::kTwist;
  k.build = [](const v1::JobSpec& spec, const IntegratorSettings& s) -> std::unique_ptr<Job> {
    return std::make_unique<TwistJob>(twist_job_spec(spec), s);
  };
  k.local_damping = [](const v1::JobSpec& spec) { return spec.twist().local_damping(); };
  k.element_bound = [](const v1::JobSpec& spec) {
    return static_cast<long>(spec::hex_tube_count(spec.twist().layers())) *
           spec::twist_segments(spec.twist());
  };
  k.builds_quickly = true;  // a lattice
  // Results (the last flag): the end state a user reads - twist angle, end shift, radius, Q.
  k.summary = {
      {"outcome", SummaryField::Type::Label, "", "outcome", 1, 6, true},
      // When the outcome was reached (the end of the hold, or the separation, where the run ends:
      // the "simulated" time says it): in the JSON.
      {"outcome_time_ps", SummaryField::Type::Real, "ps", "at", 0, 6, false},
      {"separated_tube", SummaryField::Type::Count, "", "separated tube", 1, 6, false, false, 1.0,
       true},
      {"morphology", SummaryField::Type::Label, "", "morphology", 1, 6, true},
      {"twist_angle_deg", SummaryField::Type::Real, "deg", "twist angle", 1, 6, false, true},
      {"shift_angle_deg", SummaryField::Type::Real, "deg", "end shift", 1, 6, false, true},
      {"topological_charge", SummaryField::Type::Count, "", "topological charge Q", 2, 6, false,
       true},
      {"max_topological_charge", SummaryField::Type::Count, "", "max Q", 2, 6, false},
      {"peak_twist_angle_deg", SummaryField::Type::Real, "deg", "peak twist angle", 2, 6, false},
      {"peak_shift_angle_deg", SummaryField::Type::Real, "deg", "peak end shift", 2, 6, false},
      {"rope_radius_nm", SummaryField::Type::Real, "nm", "rope radius", 3, 6, false, true},
      {"initial_rope_radius_nm", SummaryField::Type::Real, "nm", "initial radius", 3, 6, false},
      {"length_nm", SummaryField::Type::Real, "nm", "length", 3, 6, false},
      {"core_void_nm", SummaryField::Type::Real, "nm", "core void", 3, 6, false},
      {"axis_deviation_nm", SummaryField::Type::Real, "nm", "axis deviation", 3, 6, false},
      {"applied_torque_nNnm", SummaryField::Type::Real, "nN·nm", "grip torque applied", 4, 6,
       false},
      {"grip_reaction_nNnm", SummaryField::Type::Real, "nN·nm", "reaction", 4, 6, false},
      {"tubes", SummaryField::Type::Count, "", "tubes", 5, 6, false},
      {"elements", SummaryField::Type::Count, "", "elements", 5, 6, true},
      {"spacing_nm", SummaryField::Type::Real, "nm", "spacing", 5, 6, false},
      {"simulated_ps", SummaryField::Type::Real, "ps", "simulated", 5, 6, false},
  };
  return k;
}

}  // namespace mdem
