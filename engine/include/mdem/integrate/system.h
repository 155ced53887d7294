#pragma once
// A simulated system: elements, the force models a scene asked for, an optional neighbour list
// (built only when some model acts on pairs), and the velocity-Verlet integrator with energy
// bookkeeping, the critical-step check and the run guard.
#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/core/domain.h"
#include "mdem/core/elements.h"
#include "mdem/core/energy.h"
#include "mdem/force/force_model.h"
#include "mdem/integrate/respa.h"
#include "mdem/integrate/step_timers.h"
#include "mdem/io/state_io.h"
#include "mdem/neighbor/memory_order.h"
#include "mdem/neighbor/neighbor_list.h"
#include "mdem/neighbor/pair_table.h"

namespace mdem {

class StateWriter;
class StateReader;
class System;

// What acts on a system before each force evaluation: a protocol (loads, prescribed motion) or
// an observer that samples every step. It saves and loads the state a run changes in it (none
// by default); its owner (a job's stage) puts that in checkpoints. One that holds element indices
// remaps them when the system reorders its elements (ElementIndexHolder).
class Updater : public Stateful, public ElementIndexHolder {
 public:
  virtual void apply(System& sys, double time) = 0;
  // Why element i ran away, when this updater's load explains it (e.g. an applied moment that
  // nothing resists any more); empty when it does not. The run guard says it instead of blaming dt.
  virtual std::string explain_runaway(const System& /*sys*/, std::size_t /*i*/) const { return {}; }
  // Whether the next apply() reads the elements' forces or torques (Elements::f, t, or the
  // system's damping_forces(), damping_torques()). Asked at every step of a run, after the
  // updaters applied and before the pass that stores the forces the next apply() sees: when no
  // updater says true, that pass (which kicks with them and drifts into the next step) keeps them
  // in registers; the run's last step and the energy guard's steps store them always (System::
  // run). An updater whose next apply() reads them after saying false sees forces one or more
  // steps old. True (always fresh) unless an updater says otherwise.
  virtual bool reads_forces() const { return true; }
  // Whether apply() may set external loads (Elements::f_ext, t_ext). When no updater says true
  // and every element's loads are zero at the start of a run, the integrator's pass in lanes
  // does not read them (48 bytes per element and step). True unless an updater says otherwise;
  // an updater must not set loads after saying false: the lanes would run without them (the
  // scalar kernels, for the elements outside the lanes, would not).
  virtual bool applies_loads() const { return true; }
  void save_state(StateWriter&) const override {}
  void load_state(StateReader&) override {}
};

// A run that went numerically wrong: says at which step, which element and the likely cause.
class NumericalError : public std::runtime_error {
 public:
  NumericalError(const std::string& what, long step, long element)
      : std::runtime_error(what), step_(step), element_(element) {}
  long step() const { return step_; }
  long element() const { return element_; }  // -1 when no single element is to blame

 private:
  long step_, element_;
};

// A time step or setting that cannot be used; the message gives the allowed range.
class ConfigError : public std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

struct IntegratorSettings {
  std::optional<double> dt;    // ps; empty = auto (safety × critical step)
  double safety = 0.6;         // fraction of the critical step that is safe
  double local_damping = 0.0;  // PFC local damping α in [0, 1)
  double skin = 0.5;           // neighbour-list skin (nm)
  // Memory order of the elements (neighbor/memory_order.h): Morton reorders them along a Morton
  // curve over the neighbour search's cells at neighbour-list rebuilds, Slabs into one slab of
  // space per thread (what lets two threads share little data: docs/engine.md). Every model
  // and updater must follow a reordering (ElementIndexHolder), else initialize and run throw
  // ConfigError naming the one that does not. Tags stay with their elements.
  MemoryOrder memory_order = MemoryOrder::AsBuilt;
  // Rebuilds of the (first) neighbour sub-list from one reordering to the next, in
  // [1, limits::kMaxReorderEvery]: the first build reorders, then every this many. Elements move
  // at most half the skin between rebuilds, so the order decays slowly, and a reordering costs
  // about as much as a rebuild.
  int memory_order_every = 10;
  int threads = 0;  // 0: OpenMP's default
  // Run guard.
  int guard_every = 100;  // steps between energy-balance checks
  // Unexplained energy growth, as a fraction of the energy in play (initial kinetic energy, work
  // put in, energy dissipated or released), that stops the run. Velocity Verlet's bounded
  // fluctuation at the default step stays well below it; an instability grows past it fast.
  double guard_energy_tolerance = 0.5;
  // Off: a fixed dt above safety × critical step is taken as given instead of refused (stability
  // studies probe the limit; the run guard still stops what goes unstable). No spec field sets it.
  bool check_dt = true;
  // Multiple time stepping (respa.h): slow models (Timescale::Slow) once every respa_k steps of dt
  // as impulses, fast ones every step. [1, limits::kMaxRespaK]; 1 = off (plain velocity Verlet).
  // respa_k·dt must stay within safety × the slow models' critical step (else ConfigError).
  int respa_k = 1;
  // Off: every element takes the integrator's general per-DOF kernels; on, elements with all six
  // DOFs free and isotropic inertia take the same arithmetic compiled without the per-DOF
  // branches (integrate/step_kernels.h), in SIMD lanes of consecutive elements where a whole
  // chunk is of that class (integrate/step_simd.h, step_simd_target()). Results are bit for bit
  // the same either way; tests compare the two. No spec field sets it.
  bool free_isotropic_fast_path = true;
};

class System {
 public:
  explicit System(Elements el, IntegratorSettings s = {});
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;
  System(System&&) noexcept;
  System& operator=(System&&) noexcept;

  Elements& elements() { return el_; }
  const Elements& elements() const { return el_; }
  const IntegratorSettings& settings() const { return settings_; }

  // Adds a force model; returns a pointer to it (owned by the system).
  template <class M>
  M* add(std::unique_ptr<M> m) {
    M* raw = m.get();
    models_.push_back(std::move(m));
    initialized_ = false;
    return raw;
  }
  template <class M>
  M* find() const {
    for (const auto& m : models_)
      if (auto* p = dynamic_cast<M*>(m.get())) return p;
    return nullptr;
  }
  const std::vector<ForceModelPtr>& models() const { return models_; }

  // Updaters are called before each force evaluation with the time it is for, in the order
  // added: protocols set external loads and prescribed velocities, observers that need every
  // step sample it (HOOMD's "updater"). A job's stage installs its own (set_updaters).
  void add_updater(std::shared_ptr<Updater> u);
  // A plain function as an updater (tests, ad-hoc drivers); it has no checkpoint state.
  void add_updater(std::function<void(System&, double time)> fn);
  void set_updaters(std::vector<std::shared_ptr<Updater>> u) { updaters_ = std::move(u); }
  const std::vector<std::shared_ptr<Updater>>& updaters() const { return updaters_; }
  // PFC local damping α in [0, 1) from the next force evaluation on (a stage's damping); throws
  // ConfigError outside the range.
  void set_local_damping(double alpha);
  // The memory order from now on (a stage's). Switching from AsBuilt to another reorders the
  // elements at once (not only at the next memory_order_every-th list build); AsBuilt keeps them
  // in the order they are in. Throws ConfigError, changing nothing, for an unknown order or one
  // that a model or updater cannot follow.
  void set_memory_order(MemoryOrder m);
  MemoryOrder memory_order() const { return settings_.memory_order; }
  // Whether a model of this system acts (a stage's active models): an inactive one adds no force,
  // energy or stiffness from the next evaluation on, and keeps its state. Throws
  // std::invalid_argument for a model the system does not hold.
  void set_model_active(const ForceModel* m, bool active);
  bool model_active(const ForceModel* m) const;

  // Validates the settings, builds the neighbour list if any model needs one, evaluates forces
  // and energies, computes the critical step and picks or checks dt. Throws ConfigError for a dt
  // above the safe limit (the message gives the limit) and NumericalError for non-finite state.
  void initialize();
  // Advances n steps (initializing first if needed). Throws NumericalError when the guard trips;
  // the state is then that of the failing step and must not be reported as a result.
  void run(long n);
  void step() { run(1); }
  bool initialized() const { return initialized_; }

  // Checkpoints: everything a run changes (element state, loads and DOF modes, the forces of the
  // last evaluation, energy ledger and guard figures, time, step count, dt, the neighbour list and
  // each model's state), so that after load_state the next run() continues exactly as the saved
  // system would have. load_state initializes the system (models and settings come from the
  // job's spec, not the checkpoint), then overwrites its state; it throws CheckpointError when the
  // checkpoint is of another scene (element count or properties differ, other models) or thread
  // count (forces are summed per thread, so only the same count reproduces the run), and leaves
  // the system unusable then. Updaters hold their own state: their owner saves it.
  void save_state(StateWriter& w) const;
  void load_state(StateReader& r);

  double time() const { return time_; }
  long steps() const { return steps_; }
  double dt() const { return dt_; }
  double critical_dt() const { return dt_critical_; }
  // Largest safe step = safety × critical step.
  double max_safe_dt() const { return settings_.safety * dt_critical_; }
  // With respa_k > 1: the critical step of the slow models alone, which bounds the outer step
  // respa_k·dt (infinite without slow models or with respa_k = 1).
  double critical_outer_dt() const { return dt_critical_outer_; }
  int threads() const { return threads_; }

  // Bytes the system's data holds now (container capacities): the element arrays, the force
  // buffers (per thread), the neighbour lists and each model's own data (bonds; ForceModel::
  // memory_bytes). Shared objects (the domain, groups, topology) and the heap's overhead are not
  // counted. O(models + lists), no pass over the elements: cheap enough to sample at every poll.
  std::size_t memory_bytes() const;

  // Reorders the elements (new_to_old, as Elements::reorder) and remaps every index the system,
  // its models and updaters hold; the neighbour sub-lists are rebuilt at the next evaluation.
  // Throws ConfigError, changing nothing, when a model or updater does not follow a reordering,
  // and std::invalid_argument when new_to_old is not a permutation of the elements.
  void reorder_elements(std::span<const std::uint32_t> new_to_old);
  // Reorderings done since the system was made (memory_order Morton or Slabs: at the first
  // neighbour-list build, then at every memory_order_every-th; plus any reorder_elements call).
  std::size_t reorders() const { return reorders_; }

  // Wall time of run()'s parts since the system was made (step_timers.h).
  const StepTimers& timers() const { return timers_; }

  const EnergyLedger& energy() const { return ledger_; }
  // |W_ext − (ΔE + E_diss)| over the energy in play: the largest of the initial kinetic energy,
  // the work put in, the energy dissipated and the stored energy released.
  double energy_balance_error() const;
  // Damping forces of the last evaluation (contact dashpots + local damping), per element.
  const std::vector<Vec3>& damping_forces() const { return fd_; }
  const std::vector<Vec3>& damping_torques() const { return td_; }
  // The neighbour sub-list of the first pair model (null without pair models), and that of model
  // m (null when m is not a pair model of this system).
  const NeighborList* neighbors() const {
    return pairs_.empty() ? nullptr : pairs_.entries().front().list.get();
  }
  const NeighborList* neighbors(const ForceModel& m) const { return pairs_.list_of(&m); }
  // Which pair models act on which kind pairs over which sub-list (set up by initialize).
  const PairTable& pair_table() const { return pairs_; }

  // The box: every pair displacement is its minimum image (open on all axes by default). Takes
  // effect at the next initialize(); a periodic axis must be at least 2·(cutoff + skin) long for
  // every pair model (else initialize throws ConfigError).
  void set_domain(const Domain& d) {
    *domain_ = d;
    initialized_ = false;
  }
  const Domain& domain() const { return *domain_; }

  // Recomputes forces and energies at the current state without moving (after a caller edited
  // positions or models).
  void refresh();
  // refresh() after a change of models or settings at a stage boundary: the change in stored
  // energy it makes is booked as external work (the work of switching), so the energy balance
  // stays closed and the guard does not read it as an instability.
  void refresh_booking_work();
  // Clock and step count back to 0 and the energy ledger restarted from the current state (no
  // work done, nothing dissipated yet), after a refresh() at the current state: the end of a
  // pre-relaxation (tensile.md §3.3), whose velocities the caller zeroes first. Initializes first
  // if needed.
  void restart_clock();
  // Critical step of the current configuration (does not change dt); of the slow models alone
  // with slow_only (multiple time stepping's outer step).
  double compute_critical_dt(bool slow_only = false) const;
  // The critical step 2/ω of the current configuration for a largest frequency ω (rad/ps) found
  // otherwise (integrate/spectrum.h's largest_frequency, which leaves damping out), lowered for
  // the contact dashpots as compute_critical_dt lowers it: (2/ω)(√(1+ζ²) − ζ) with the largest
  // element's ζ = Σc/(m ω). Infinite for ω ≤ 0; throws std::invalid_argument for a NaN ω.
  double damped_critical_dt(double omega) const;

 private:
  // Forces, energies and damping of the current state; with_local_damping false leaves the
  // local damping to the caller's own pass over the elements (run()'s second half kick). With
  // timers, the neighbour-list update and the force evaluation are timed into them.
  // In a step (in_step), the slow models of multiple time stepping are evaluated only when the
  // evaluation closes an outer step; outside (initialize, refresh) always, for the energy books.
  // defer_sums: leave the per-thread force sums in the sink for the caller's pass over the
  // elements to take (ForceSink::take; sums_deferred_ says whether they were left: not under
  // multiple time stepping, whose slow impulses are added to the summed forces).
  void compute_forces(bool with_local_damping = true, StepTimers* timers = nullptr,
                      bool in_step = false, bool defer_sums = false);
  void add_slow_forces(bool in_step);
  // Adds the forces of the models of one timescale (slow: r-RESPA's outer step; else the inner
  // step's) that the stage has not switched off, each once; a model and the one whose pairs are
  // its (a dashpot and its contact) in one pass where they can (ForceModel::compute_with).
  void compute_models(bool slow);
  // Memory order (system_order.cpp). update_pairs: the pair table's update, reordering the
  // elements in settings_.memory_order first (a curve, or slabs) when a sub-list is stale.
  void update_pairs();
  // True when the reordering changed the order (all sub-lists are then rebuilt).
  bool reorder_along_curve();
  // The order of settings_.memory_order for the elements now (new_to_old); empty for AsBuilt, and
  // for Morton before the pair table exists (its cells are the lists' largest reach).
  std::vector<std::uint32_t> wanted_order() const;
  // Throws ConfigError for an unknown memory_order, or one that a model or updater cannot follow.
  void check_memory_order() const;
  // What stops a reordering ("force model 'x' does not follow ..."), empty when nothing does;
  // the models only without with_updaters (a checkpoint's load: below).
  std::string reorder_blocker(bool with_updaters = true) const;
  // reorder_elements without the check.
  void apply_order(std::span<const std::uint32_t> new_to_old);
  // Every active model's stiffness bounds (of the slow models alone with slow_only).
  StiffnessSums stiffness_sums(bool slow_only) const;
  void update_kinetic();
  void check_finite_forces() const;
  void check_energy_growth();
  // What a guard message says to change: dt when above the safe limit, else the real suspects.
  std::string unstable_cause() const;
  void update_energy_scale();
  // Whether an updater may apply loads or an element carries one now (asked at run()'s start).
  bool any_loads() const;
  void start_ledger();  // the ledger's origin at the current state

  Elements el_;
  IntegratorSettings settings_;
  std::vector<ForceModelPtr> models_;
  std::vector<std::shared_ptr<Updater>> updaters_;
  std::vector<const ForceModel*> inactive_;  // models switched off by the current stage
  // Per model: the index of the model it may run with in one pass (a pair-table entry's owner
  // and its first other member) or −1, and whether compute_models has computed it yet.
  std::vector<int> pair_partner_;
  std::vector<char> computed_;
  std::unique_ptr<Domain> domain_ = std::make_unique<Domain>();  // models point to it
  PairTable pairs_;   // per-kind-pair table: the pair models' neighbour sub-lists
  RespaSplit respa_;  // multiple time stepping's slow forces (respa_k > 1)
  ForceSink sink_;
  std::vector<Vec3> fd_, td_;  // damping force / torque (model dampers + local damping)
  std::vector<Vec3> f_prev_, t_prev_, fext_prev_, text_prev_;  // for work bookkeeping
  // Per thread, for sums in a fixed order and the elements a pass flagged; a cache line each, so
  // the threads' writes at the end of a pass do not contend for one line.
  struct alignas(64) ThreadSlot {
    std::array<double, 6> sum{};
    std::array<long, 2> mark{-1, -1};
  };
  std::vector<ThreadSlot> partial_sums_;
  std::vector<double*> sink_buffers_;  // the sink's per-thread buffers for the passes in lanes
  EnergyLedger ledger_;
  StepTimers timers_;
  double energy_scale_ = 0;  // energy in play, for relative errors
  double initial_kinetic_ = 0, initial_stored_ = 0;
  double time_ = 0, dt_ = 0, dt_critical_ = 0;
  double dt_critical_outer_ = std::numeric_limits<double>::infinity();
  long steps_ = 0;
  std::size_t reorders_ = 0;
  int threads_ = 1;
  bool initialized_ = false;
  bool dissipative_ = false;
  bool local_damping_was_on_ = false;  // fd_/td_ may hold local damping to clear
  bool sums_deferred_ = false;         // the last compute_forces left the sums in sink_
};

// The instruction set the integrator's lanes run on (IntegratorSettings::free_isotropic_fast_path),
// e.g. "AVX3", "AVX2", "EMU128".
const char* step_simd_target();

}  // namespace mdem
