#pragma once
// A stage of a job: one part of its run with its own protocol, damping and stop condition
// (generate, pre-relax, relax, grip ramp, strain, cycles; pack, compress). The job lists its
// stages in order and run_job runs them with progress, cancellation and checkpoints in any.
//
// A stage is Stateful: its state (the system it advances, where it started, its protocol's and
// observers' state) goes into a checkpoint taken inside it, and a job built anew and loaded from
// that checkpoint continues inside the stage bit-identically.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mdem/integrate/system.h"
#include "mdem/io/state_io.h"
#include "mdem/protocol/protocol.h"

namespace mdem {

class Job;

class Stage : public Stateful {
 public:
  explicit Stage(std::string name) : name_(std::move(name)) {}
  const std::string& name() const { return name_; }

  // The system the stage advances.
  virtual System& system() = 0;
  // Whether the job's frames and snapshots are reported during the stage (a stage that builds
  // the scene, before the job's system exists, reports progress only).
  virtual bool reports() const { return true; }
  // Puts the stage's settings on its system (updaters, damping). Called on entering the stage
  // and before a checkpoint taken inside it loads; calling it again changes nothing.
  virtual void install() {}
  // Called once when the stage starts, after install() (not when a checkpoint inside the stage
  // loads); it initializes the system as the stage needs.
  virtual void begin() {}
  // The stop condition holds (after begin() or a load).
  virtual bool finished() const = 0;
  // Advances the system by up to `steps` (>= 1) steps, fewer at the stage's end or at a step
  // where its criterion is checked; a stage that works in indivisible units may overrun by less
  // than one unit.
  virtual void advance(long steps) = 0;
  virtual long steps_done() const = 0;
  // Steps the stage will take: exact for a fixed length, the maximum for a criterion, the steps
  // done once finished; 0 while unknown (before its system exists).
  virtual long planned_steps() const = 0;
  // Where the stage is, for progress lines: its protocol's phase, else its name.
  virtual std::string phase() const { return name_; }
  // What a finished stage hands on to later ones (e.g. a packed particle), saved in checkpoints
  // taken in later stages; loading it is followed by Job::stage_finished, as after the run.
  virtual void save_result(StateWriter&) const {}
  virtual void load_result(StateReader&) {}

 private:
  std::string name_;
};

// When a SystemStage ends: after a simulated time or a step count, or when a criterion checked
// every check_every steps holds, at most after max_steps. A criterion beside a duration ends the
// stage early when it holds (an outcome reached before the planned end, e.g. a rope that
// separated).
class StopCriterion : public Stateful {
 public:
  virtual bool met(const System& sys) = 0;
  void save_state(StateWriter&) const override {}
  void load_state(StateReader&) override {}
};

struct StopCondition {
  double duration_ps = 0;  // > 0: this long from the stage's start
  long steps = 0;          // > 0: this many steps
  std::shared_ptr<StopCriterion> criterion;
  long check_every = 100;
  long max_steps = 0;  // with a criterion: the stage ends after this many steps whatever happens

  static StopCondition after(double ps) { return {ps, 0, nullptr, 100, 0}; }
  static StopCondition after_steps(long n) { return {0, n, nullptr, 100, 0}; }
  static StopCondition after_unless(double ps, std::shared_ptr<StopCriterion> c, long check_every) {
    return {ps, 0, std::move(c), check_every, 0};
  }
  static StopCondition when(std::shared_ptr<StopCriterion> c, long check_every, long max_steps) {
    return {0, 0, std::move(c), check_every, max_steps};
  }
};

// Net force balance: the largest |f + f_ext| over the elements with a free translational DOF is
// below `tolerance` (eV/nm), the usual end of a damped relaxation.
class ForceBalance final : public StopCriterion {
 public:
  explicit ForceBalance(double tolerance);  // finite and > 0, else std::invalid_argument
  bool met(const System& sys) override;
  // The figure compared: the largest net force (eV/nm).
  static double largest_net_force(const System& sys);

 private:
  double tolerance_;
};

// The common stage: the job's system under a protocol (or none: hands-off), with observers that
// sample every step, its own local damping and active force models, and a stop condition. Updaters
// are applied in the order protocol, observers.
class SystemStage final : public Stage {
 public:
  struct Settings {
    std::shared_ptr<Protocol> protocol;               // null: no loads (a relaxation)
    std::vector<std::shared_ptr<Updater>> observers;  // stateful samplers and trackers
    // PFC local damping α of this stage; empty: the system's own setting.
    std::optional<double> local_damping;
    // Force models of the job's system that do not act during this stage (e.g. contact dashpots
    // in an undamped hold); every other model acts.
    std::vector<const ForceModel*> inactive_models;
    // How the system orders its elements in memory during this stage (IntegratorSettings::
    // memory_order): AsBuilt keeps them in the order they are in when the stage starts; Slabs
    // (one slab of space per thread, so that threads share little data) needs every model and
    // updater of the stage to follow a reordering.
    MemoryOrder memory_order = MemoryOrder::AsBuilt;
    StopCondition stop;
  };
  // Throws std::invalid_argument for a stop condition that is not exactly one of a positive
  // duration, a positive step count, or a criterion with check_every >= 1 and max_steps >= 1.
  SystemStage(std::string name, Job& job, Settings s);

  System& system() override;
  void install() override;
  void begin() override;
  bool finished() const override;
  void advance(long steps) override;
  long steps_done() const override;
  long planned_steps() const override;
  std::string phase() const override;
  long start_step() const { return start_step_; }

  // The system, then where the stage started and ends, then the protocol's, observers' and
  // criterion's own state.
  void save_state(StateWriter& w) const override;
  void load_state(StateReader& r) override;

 private:
  const System& sys() const;
  Job& job_;
  Settings s_;
  long start_step_ = 0, end_step_ = 0;  // end: fixed length, or start + max_steps
  bool met_ = false;
  bool begun_ = false;
};

}  // namespace mdem
