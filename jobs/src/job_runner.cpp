#include "mdem/job_runner.h"

#include <cmath>

namespace mdem {

void check_time_step(Job& job) {
  if (!job.system().initialized()) job.system().initialize();
}

bool scene_built(const Job& job) {
  const Stage* st = job.current_stage();
  return !st || st->reports();
}

long steps_needed(Job& job) {
  return std::max(1L, static_cast<long>(std::ceil(job.duration() / job.system().dt() - 1e-9)));
}

JobRunner::JobRunner(const v1::JobSpec& spec, int threads, const JobKindRegistry& kinds)
    : spec_(spec), kind_(kinds.of(spec)), job_(make_spec_job(spec, threads, kinds)) {}

JobOutcome JobRunner::run(const JobObserver& observer,
                          const std::function<std::string(Job&)>& cancel_reason) {
  JobOutcome o;
  const auto t0 = std::chrono::steady_clock::now();
  try {
    const JobRunResult r = run_job(*job_, job_cadence(spec_), observer);
    o.steps = r.steps;
    if (r.cancelled) {
      o.cancelled = true;
      o.state = v1::CANCELLED;
      o.reason = cancel_reason ? cancel_reason(*job_) : std::string();
    }
  } catch (const NumericalError& e) {
    o.state = v1::FAILED;
    o.reason = e.what();
    o.steps = job_->system().steps();
  } catch (const ConfigError& e) {
    // A setting refused only once a stage has built its system (a compression job's time step
    // is checked after its particle is packed): the job is invalid, results so far kept.
    o.state = v1::FAILED;
    o.reason = std::string("invalid job: ") + e.what();
    o.steps = job_->system().steps();
  }
  o.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return o;
}

ReportJson JobRunner::report(const std::string& job_id, const JobOutcome& outcome,
                             double wall_before) const {
  return job_report(*job_, *kind_, job_id, outcome.state, outcome.reason,
                    wall_before + outcome.wall_s);
}

}  // namespace mdem
