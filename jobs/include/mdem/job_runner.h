#pragma once
// The one job runner behind `mdem run` (in-process) and mdemd's workers: build the engine job of
// a finalized spec, run it with the caller's observer, classify how it ended and write its
// report. The callers add only what is theirs: where frames and snapshots go, what cancels, and
// (the daemon) checkpoints, resume and requeue.
#include <chrono>
#include <functional>
#include <memory>
#include <string>

#include "mdem/job/job.h"
#include "mdem/job/stage.h"
#include "mdem/job_kinds.h"
#include "mdem/job_state.h"
#include "mdem/spec_job.h"
#include "mdem/v1/job.pb.h"

namespace mdem {

// Initializes the job's system, so that a time step above the safe limit is refused (ConfigError)
// before anything is stored. A system that a scene-building stage set up and initialized itself
// (a compression job's packing, whose grains start shrunk) is left alone: initializing it again
// would take its step from the shrunk grains and spoil the packing.
void check_time_step(Job& job);

// Whether the job's own system exists: no scene-building stage is still to run (its step count
// and time step are those of the job, not of a packing).
bool scene_built(const Job& job);

// Steps a job needs: ceil(duration / dt), at least 1 (the system must be initialized).
long steps_needed(Job& job);

struct JobOutcome {
  JobState state = v1::SUCCEEDED;
  std::string reason;
  bool cancelled = false;  // the observer's cancelled() stopped it (state CANCELLED)
  long steps = 0;          // the step reached
  double wall_s = 0;       // this run's wall time
};

class JobRunner {
 public:
  // Builds the job with the spec's kind in `kinds` (make_spec_job); threads > 0 overrides the
  // spec's. Throws what building throws (std::invalid_argument for an impossible scene or load,
  // or a kind `kinds` does not hold).
  explicit JobRunner(const v1::JobSpec& spec, int threads = 0,
                     const JobKindRegistry& kinds = job_kinds());

  Job& job() { return *job_; }
  const v1::JobSpec& spec() const { return spec_; }

  // run_job at the spec's cadence. A run the observer cancels is CANCELLED with the reason
  // cancel_reason(job) gives; a NumericalError or a ConfigError (a setting refused once a stage
  // built its system) is FAILED with its message; other exceptions propagate (the caller knows what
  // they mean).
  JobOutcome run(const JobObserver& observer,
                 const std::function<std::string(Job&)>& cancel_reason);

  // The report (job_report) of the outcome; wall_before: wall time of earlier runs of the job.
  ReportJson report(const std::string& job_id, const JobOutcome& outcome,
                    double wall_before = 0) const;

 private:
  v1::JobSpec spec_;
  const JobKind* kind_;
  std::unique_ptr<Job> job_;
};

}  // namespace mdem
