#pragma once
// A job: a scene and its protocol on a System, with the observables it reports (HOOMD's
// "analyzers"), and one run loop that every front end (the CLI in-process, the daemon's workers)
// shares: time series frames and snapshots at their cadences, progress, cancellation.
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "mdem/core/energy.h"
#include "mdem/integrate/system.h"
#include "mdem/io/state_io.h"
#include "mdem/observe/snapshot.h"

namespace mdem {

// A job's key figures, in order: numbers or labels.
using SummaryValue = std::variant<double, long, std::string>;
using Summary = std::vector<std::pair<std::string, SummaryValue>>;

class Job {
 public:
  virtual ~Job() = default;
  virtual std::string_view kind() const = 0;
  virtual System& system() = 0;
  // Simulated time the protocol needs (ps).
  virtual double duration() const = 0;
  // Names of the time-series columns (units in the names), and one row at the current state.
  virtual std::vector<std::string> columns() const = 0;
  virtual std::vector<double> observe() = 0;
  // The protocol's figures at the current state (call after the run).
  virtual Summary summary() = 0;
  // A few words on where the protocol is ("loading", "holding"), for progress lines.
  virtual std::string phase() const { return {}; }
  // Adds the job's own per-element values for colouring (e.g. a slip vector) to a snapshot that
  // run_job captured at the current state.
  virtual void decorate(Snapshot&) const {}

  // Checkpoints: the system and every bit of protocol and observer state a run changes, so that
  // a job built anew from the same spec, with the same thread count, and loaded from the bytes,
  // continues under run_job bit-identically. Save at a step boundary (JobObserver::checkpoint).
  // load_state throws CheckpointError for a checkpoint of another scene, loading or thread count;
  // the job must be discarded then. Kinds that cannot checkpoint throw CheckpointError.
  virtual bool can_checkpoint() const { return false; }
  virtual void save_state(StateWriter& w) const;
  virtual void load_state(StateReader& r);
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

struct JobProgress {
  long step = 0, total_steps = 0;
  double time_ps = 0;
  std::string phase;
};

// What the run loop reports to; every callback may be empty.
struct JobObserver {
  std::function<void(const SeriesFrame&)> frame;
  std::function<void(const Snapshot&)> snapshot;
  std::function<void(const JobProgress&)> progress;  // about every 0.5 % of the run
  std::function<bool()> cancelled;                   // polled between chunks of steps
  // Called after every chunk of steps (often: every few steps on a large system), with the state
  // consistent at that step and everything due at it reported: the caller may save_state now.
  std::function<void(long step)> checkpoint;
};

struct JobRunResult {
  long steps = 0;
  bool cancelled = false;
};

// Initializes the system, then runs it to step ceil(duration / dt), reporting a frame at step 0,
// every frame_every_ps and at the end, and snapshots likewise (none when snapshot_every_ps is 0).
// A job whose system is past step 0 (restored from a checkpoint) continues from its step without
// initializing or reporting step 0 again: every cadence counts absolute steps, so it reports
// exactly what an uninterrupted run reports after that step. JobRunResult::steps is the step
// reached. Throws NumericalError or ConfigError from the system; what was reported before stays
// valid.
JobRunResult run_job(Job& job, const JobCadence& cadence, const JobObserver& observer);

}  // namespace mdem
