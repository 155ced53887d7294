#include "mdem/spec_job.h"

#include <climits>
#include <cmath>
#include <stdexcept>

#include "mdem/core/units.h"
#include "mdem/spec.h"

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

CompressionJobSpec compression_job_spec(const v1::JobSpec& spec) {
  const v1::CompressionSpec& c = spec.compression();
  CompressionJobSpec job;
  PackingSpec& p = job.particle;
  p.shape = PackingShape::Shell;
  p.r_outer = c.outer_radius_nm();
  p.r_inner = c.inner_radius_nm();
  p.grain_r_min = c.grain_radius_min_nm();
  p.grain_r_max = c.grain_radius_max_nm();
  p.target_porosity = c.porosity();
  p.material.youngs = units::GPa(c.youngs_gpa());
  p.material.poisson = c.poisson();
  p.material.density =
      c.density_g_cm3() * units::kGramPerCm3InAmuPerNm3 * units::kAmu;  // g/cm³ -> internal
  p.seed = spec.seed();
  job.bond.material = p.material;
  switch (c.bond()) {
    case v1::PLASTIC:
      job.bond.behaviour = BondBehaviour::Plastic;
      break;
    case v1::BRITTLE:
      job.bond.behaviour = BondBehaviour::Brittle;
      break;
    default:
      job.bond.behaviour = BondBehaviour::Elastic;
  }
  // Unused by elastic bonds (a CUSTOM material's elastic bond may have none).
  job.bond.strength = c.has_strength_gpa() ? units::GPa(c.strength_gpa()) : 0.0;
  job.loading.speed = c.platen_speed_nm_per_ps();
  job.loading.peak_displacement = c.peak_displacement_nm();
  job.loading.unload = c.unload();
  job.viscous_ratio = c.viscous_ratio();
  return job;
}

IntegratorSettings integrator_settings(const v1::JobSpec& spec) {
  IntegratorSettings s;
  if (spec.has_twist()) s.local_damping = spec.twist().local_damping();
  if (spec.has_compression()) s.local_damping = spec.compression().local_damping();
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
    case v1::JobSpec::kCompression:
      return "compression";
    default:
      return "";
  }
}

bool builds_quickly(const v1::JobSpec& spec) {
  return spec.kind_case() != v1::JobSpec::kCompression;
}

long element_bound(const v1::JobSpec& spec) {
  switch (spec.kind_case()) {
    case v1::JobSpec::kTwist:
      return static_cast<long>(spec::hex_tube_count(spec.twist().layers())) *
             spec::twist_segments(spec.twist());
    case v1::JobSpec::kCompression: {
      const double n = spec::compression_grain_estimate(spec.compression());
      if (!(n < 1e15)) return LONG_MAX;  // also NaN
      return static_cast<long>(std::ceil(1.01 * n + 10)) + 2;
    }
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
    case v1::JobSpec::kCompression:
      return std::make_unique<CompressionJob>(compression_job_spec(spec), s);
    default:
      throw std::invalid_argument(
          "the job spec names no job kind this build runs (allowed: twist, compression)");
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
