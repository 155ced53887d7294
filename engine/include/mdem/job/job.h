#pragma once
// A job: a scene and its stages on a System, with the observables it reports (HOOMD's
// "analyzers"), and one run loop that every front end (the CLI in-process, the daemon's workers)
// shares: stages in order, time series frames and snapshots at their cadences, progress,
// cancellation and checkpoints in any stage.
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "mdem/core/energy.h"
#include "mdem/integrate/system.h"
#include "mdem/io/state_io.h"
#include "mdem/job/stage.h"
#include "mdem/observe/snapshot.h"

namespace mdem {

// What a job's systems did, summed over every system it has run since it was built or loaded: a
// stage may hand on to a new system (the tensile job rebuilds its film's after the
// pre-relaxation, the compression job builds its own from the packing stage's), and the steps
// and engine timers of the systems it left would otherwise drop out of throughput figures. Not
// checkpointed: after a resume it counts from the resumption, as System::timers() do.
struct JobWork {
  long steps = 0;            // steps of all the systems
  double element_steps = 0;  // sum over the systems of elements x steps
  StepTimers timers;         // the systems' engine timers, added up
  void add(const JobWork& other);
  void add(const System& sys);  // its steps, elements x steps and timers
};

// A job's key figures, in order: numbers or labels.
using SummaryValue = std::variant<double, long, std::string>;
using Summary = std::vector<std::pair<std::string, SummaryValue>>;

// A job: a scene and an ordered list of stages (job/stage.h) on it, with the observables it
// reports. Its parts that a run changes (stages with their protocols and observers, trackers the
// job reports from) are Stateful and listed once (add_stage, add_state): checkpoints save and
// load them in that order, no job writes a checkpoint layout by hand.
class Job {
 public:
  virtual ~Job() = default;
  virtual std::string_view kind() const = 0;
  // The system the job advances now: the job's own, or, while a stage that builds the scene runs
  // (a packing), that stage's.
  virtual System& system() = 0;
  // Simulated time of the reporting stages (ps), as far as known before the run.
  virtual double duration() const = 0;
  // Names of the time-series columns (units in the names), and one row at the current state.
  virtual std::vector<std::string> columns() const = 0;
  virtual std::vector<double> observe() = 0;
  // The protocol's figures at the current state (call after the run).
  virtual Summary summary() = 0;
  // Where the run is ("packing", "loading", "holding"): the current stage's phase.
  virtual std::string phase() const;
  // Adds the job's own per-element values for colouring (e.g. a slip vector) to a snapshot that
  // run_job captured at the current state.
  virtual void decorate(Snapshot&) const {}

  const std::vector<std::unique_ptr<Stage>>& stages() const { return stages_; }
  // The stage under way (stages().size() once all finished), whether it has begun, and the
  // steps of the stages before it.
  std::size_t stage_index() const { return index_; }
  bool stage_begun() const { return begun_; }
  long finished_steps() const { return finished_steps_; }
  // Steps run over all stages so far (what progress reports count): finished stages' steps plus
  // the current stage's.
  long overall_step() const;
  Stage* current_stage() const { return index_ < stages_.size() ? stages_[index_].get() : nullptr; }
  // The work of every system the job has run (the ones it has left, then its current one).
  JobWork work();

  // Checkpoints: the stage index, what the finished stages handed on, the current stage's state
  // (its system, protocol and observers) and the job's listed parts, so that a job built anew
  // from the same spec, with the same thread count, and loaded from the bytes, continues under
  // run_job bit-identically, in any stage. Save at a step boundary (JobObserver::checkpoint).
  // load_state throws CheckpointError for a checkpoint of another scene, loading or thread count;
  // the job must be discarded then.
  virtual bool can_checkpoint() const { return true; }
  void save_state(StateWriter& w) const;
  void load_state(StateReader& r);

  // The run loop's moves (run_job): begin the current stage (install it, Stage::begin), and
  // leave it once finished (stage_finished, then the next stage is installed).
  void begin_stage();
  void finish_stage();

 protected:
  // Appends a stage; the first is installed at once, so the job's system runs under its
  // protocol even when driven by hand (System::run).
  Stage& add_stage(std::unique_ptr<Stage> stage);
  // A part of the job a run changes that no stage owns (e.g. a tracker of peak values).
  void add_state(std::shared_ptr<Stateful> part);
  // Called when stage k has finished, in the run or when a checkpoint taken after it loads: e.g.
  // the job builds its system from what a packing stage made.
  virtual void stage_finished(std::size_t /*k*/) {}

 private:
  std::vector<std::unique_ptr<Stage>> stages_;
  std::vector<std::shared_ptr<Stateful>> parts_;
  std::size_t index_ = 0;
  bool begun_ = false;
  long finished_steps_ = 0;
  JobWork left_;  // the systems the job has left behind (finish_stage)
};

// A job's checkpoint as bytes: header (format and version), the job's kind, then its state.
std::string save_checkpoint(const Job& job);
// Loads bytes from save_checkpoint into a freshly built job; run_job then continues the run.
// Throws CheckpointError (corrupt or truncated bytes, another kind, scene or thread count).
void load_checkpoint(Job& job, std::string_view bytes);

// Energy columns for the given stored terms, then kinetic (translational, rotational), external
// work, dissipated, total and the balance residual; all in eV, names ending in "_eV".
std::vector<std::string> energy_columns(const std::vector<EnergyTerm>& terms);
std::vector<double> energy_values(const System& sys, const std::vector<EnergyTerm>& terms);

struct JobCadence {
  double frame_every_ps = 1.0;     // > 0
  double snapshot_every_ps = 0.0;  // 0: no snapshots
};

// Where a run is. step and total_steps count over all stages (total_steps grows when a later
// stage's length becomes known); the stage_ fields are the current stage's.
struct JobProgress {
  long step = 0, total_steps = 0;
  double time_ps = 0;
  std::string phase;
  std::string stage{};
  int stage_index = 0, stage_count = 1;
  long stage_step = 0, stage_total_steps = 0;
};

// What the run loop reports to; every callback may be empty.
struct JobObserver {
  std::function<void(const SeriesFrame&)> frame;
  std::function<void(const Snapshot&)> snapshot;
  std::function<void(const JobProgress&)> progress;  // about every 0.5 % of the run
  std::function<bool()> cancelled;                   // polled between chunks of steps
  // Called after every chunk of steps in every stage (often: every few steps on a large system),
  // with the state consistent and everything due reported: the caller may save_state now. The
  // step is that of the job's time series (the frames' step): 0 while a stage that builds the
  // scene runs.
  std::function<void(long step)> checkpoint;
};

struct JobRunResult {
  long steps = 0;  // the step of the time series reached (the job's system's step)
  bool cancelled = false;
};

// Runs the job's stages in order from where it is: a stage that has not begun is installed, its
// system initialized if at step 0 (the time series' step 0 is reported then: frame, snapshot),
// and run until its stop condition holds, reporting frames every frame_every_ps and at the
// stage's end, snapshots likewise (none when snapshot_every_ps is 0), progress about every 0.5 %
// of the stage. A job restored from a checkpoint continues inside its stage without initializing
// or reporting again: every cadence counts the system's absolute steps, so it reports exactly
// what an uninterrupted run reports after that step. Throws NumericalError or ConfigError from
// the system; what was reported before stays valid.
JobRunResult run_job(Job& job, const JobCadence& cadence, const JobObserver& observer);

// Runs the stages that build the scene (those before the first reporting stage), without
// reports, and installs the first reporting stage: the job's own system then exists, ready for
// run_job or to be driven by hand.
void prepare_job(Job& job);

}  // namespace mdem
