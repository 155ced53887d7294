#include "mdem/spec_job.h"

#include <cmath>
#include <stdexcept>

#include "mdem/spec.h"
#include "mdem/units.h"

namespace mdem {

TwistJobSpec twist_job_spec(const v1::JobSpec& spec) {
  const v1::TwistSpec& t = spec.twist();
  TwistJobSpec job;
  RopeSpec& r = job.rope;
  r.layers = t.layers();
  r.segments = std::max(2, static_cast<int>(std::lround(t.length_nm() / 1.356)));
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
  l.unload = t.unload();
  l.unload_hold = t.unload_hold_ps();
  job.vdw_damping_ratio = t.vdw_damping_ratio();
  job.temperature_k = t.temperature_k();
  job.seed = static_cast<unsigned>(spec.seed());
  return job;
}

IntegratorSettings integrator_settings(const v1::JobSpec& spec) {
  IntegratorSettings s;
  if (spec.has_twist()) s.local_damping = spec.twist().local_damping();
  if (spec.run().has_dt_ps()) s.dt = spec.run().dt_ps();
  s.safety = spec.run().safety();
  s.threads = spec.run().threads();
  return s;
}

JobCadence job_cadence(const v1::JobSpec& spec) {
  JobCadence c;
  c.frame_every_ps = spec.outputs().energy_every_ps();
  c.snapshot_every_ps = spec.outputs().snapshot_every_ps();
  return c;
}

std::string_view job_kind_name(const v1::JobSpec& spec) {
  switch (spec.kind_case()) {
    case v1::JobSpec::kTwist:
      return "twist";
    default:
      return "";
  }
}

long element_bound(const v1::JobSpec& spec) {
  switch (spec.kind_case()) {
    case v1::JobSpec::kTwist:
      return static_cast<long>(spec::hex_tube_count(spec.twist().layers())) *
             spec::twist_segments(spec.twist());
    default:
      return 0;
  }
}

std::unique_ptr<Job> make_spec_job(const v1::JobSpec& spec, int threads) {
  IntegratorSettings s = integrator_settings(spec);
  if (threads > 0) s.threads = threads;
  switch (spec.kind_case()) {
    case v1::JobSpec::kTwist:
      return std::make_unique<TwistJob>(twist_job_spec(spec), s);
    default:
      throw std::invalid_argument(
          "the job spec names no job kind this build runs (allowed: twist)");
  }
}

ReportJson summary_json(const Summary& s) {
  ReportJson j = ReportJson::object();
  for (const auto& [k, v] : s) std::visit([&, &k = k](const auto& x) { j[k] = x; }, v);
  return j;
}

ReportJson accuracy_json(const System& sys, bool with_balance) {
  ReportJson acc;
  if (with_balance) acc["energy_balance_error"] = sys.energy_balance_error();
  acc["dt_ps"] = sys.dt();
  acc["critical_dt_ps"] = sys.critical_dt();
  acc["dt_over_critical"] = sys.dt() / sys.critical_dt();
  return acc;
}

ReportJson performance_json(const System& sys, double wall_s) {
  const double n = static_cast<double>(sys.elements().size());
  ReportJson perf;
  perf["wall_s"] = wall_s;
  perf["steps"] = sys.steps();
  perf["threads"] = sys.threads();
  perf["element_steps_per_s"] = wall_s > 0 ? n * sys.steps() / wall_s : 0.0;
  return perf;
}

ReportJson job_report(Job& job, const std::string& job_id, const std::string& state,
                      const std::string& reason, double wall_s) {
  const bool failed = state == "FAILED";
  ReportJson doc;
  doc["job_id"] = job_id;
  doc["kind"] = std::string(job.kind());
  doc["state"] = state;
  if (!reason.empty()) doc["reason"] = reason;
  doc["summary"] = failed ? ReportJson::object() : summary_json(job.summary());
  doc["accuracy"] = accuracy_json(job.system(), !failed);
  doc["performance"] = performance_json(job.system(), wall_s);
  return doc;
}

}  // namespace mdem
