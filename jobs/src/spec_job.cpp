#include "mdem/spec_job.h"

#include <climits>
#include <cmath>
#include <stdexcept>

#include "mdem/core/units.h"
#include "mdem/job_kinds.h"
#include "mdem/spec.h"

namespace mdem {

IntegratorSettings integrator_settings(const v1::JobSpec& spec) {
  IntegratorSettings s;
  if (const JobKind* kind = job_kinds().of(spec)) s.local_damping = kind->local_damping(spec);
  if (spec.run().has_dt_ps()) s.dt = spec.run().dt_ps();
  s.safety = spec.run().safety();
  s.threads = spec.run().threads();
  s.respa_k = spec.run().respa_k();
  return s;
}

JobCadence job_cadence(const v1::JobSpec& spec) {
  JobCadence c;
  c.frame_every_ps = spec.outputs().energy_every_ps();
  c.snapshot_every_ps = spec.outputs().snapshot_every_ps();
  return c;
}

std::string_view job_kind_name(const v1::JobSpec& spec) {
  const JobKind* kind = job_kinds().of(spec);
  return kind ? std::string_view(kind->name) : std::string_view();
}

bool builds_quickly(const v1::JobSpec& spec) {
  const JobKind* kind = job_kinds().of(spec);
  return !kind || kind->builds_quickly;
}

long element_bound(const v1::JobSpec& spec) {
  const JobKind* kind = job_kinds().of(spec);
  return kind ? kind->element_bound(spec) : 0;
}

std::unique_ptr<Job> make_spec_job(const v1::JobSpec& spec, int threads,
                                   const JobKindRegistry& kinds) {
  const JobKind* kind = kinds.of(spec);
  if (!kind)
    throw std::invalid_argument(
        "the job spec names no job kind this build runs (allowed: " + kinds.names() + ")");
  IntegratorSettings s = integrator_settings(spec);
  s.local_damping = kind->local_damping(spec);
  if (threads > 0) s.threads = threads;
  return kind->build(spec, s);
}

std::unique_ptr<Job> make_spec_job(const v1::JobSpec& spec, int threads) {
  return make_spec_job(spec, threads, job_kinds());
}

ReportJson summary_json(const Summary& s) { return summary_json(SummaryLayout{}, s); }

ReportJson accuracy_json(const System& sys, bool with_balance) {
  ReportJson acc;
  if (with_balance) acc["energy_balance_error"] = sys.energy_balance_error();
  acc["dt_ps"] = sys.dt();
  acc["critical_dt_ps"] = sys.critical_dt();
  acc["dt_over_critical"] = sys.dt() / sys.critical_dt();
  return acc;
}

ReportJson performance_json(const System& sys, double wall_s) {
  JobWork work;
  work.add(sys);
  return performance_json(sys, work, wall_s);
}

ReportJson performance_json(const System& sys, const JobWork& work, double wall_s) {
  ReportJson perf;
  perf["wall_s"] = wall_s;
  perf["steps"] = sys.steps();
  perf["threads"] = sys.threads();
  // Throughput over every system the job ran (a pre-relaxation's or a packing's too), since the
  // wall time covers them.
  perf["element_steps_per_s"] = wall_s > 0 ? work.element_steps / wall_s : 0.0;
  if (work.steps != sys.steps()) perf["steps_all_systems"] = work.steps;
  // The simulation data's size at the end (System::memory_bytes: capacities, which only grow
  // during a run, so also its peak), for `mdem show` of a local run.
  perf["job_data_bytes"] = sys.memory_bytes();
  return perf;
}

namespace {

ReportJson report(Job& job, const std::string& kind, const SummaryLayout& layout,
                  const std::string& job_id, JobState state, const std::string& reason,
                  double wall_s) {
  const bool failed = state == v1::FAILED;
  ReportJson doc;
  doc["job_id"] = job_id;
  doc["kind"] = kind;
  doc["state"] = job_state_name(state);
  if (!reason.empty()) doc["reason"] = reason;
  doc["summary"] = failed ? ReportJson::object() : summary_json(layout, job.summary());
  doc["accuracy"] = accuracy_json(job.system(), !failed);
  doc["performance"] = performance_json(job.system(), job.work(), wall_s);
  return doc;
}

}  // namespace

ReportJson job_report(Job& job, const std::string& job_id, JobState state,
                      const std::string& reason, double wall_s) {
  const std::string kind(job.kind());
  const SummaryLayout* layout = summary_layout(kind);
  return report(job, kind, layout ? *layout : SummaryLayout{}, job_id, state, reason, wall_s);
}

ReportJson job_report(Job& job, const JobKind& kind, const std::string& job_id, JobState state,
                      const std::string& reason, double wall_s) {
  return report(job, kind.name, kind.summary, job_id, state, reason, wall_s);
}

}  // namespace mdem
