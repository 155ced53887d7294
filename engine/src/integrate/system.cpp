#include "mdem/integrate/system.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "integrate/step_kernels.h"
#include "integrate/step_simd.h"
#include "mdem/core/limits.h"

namespace mdem {

namespace {

std::string describe(const Elements& el, std::size_t i) {
  std::ostringstream s;
  s << "element " << i;
  if (el.tube[i] >= 0) s << " (tube " << el.tube[i] << ", segment " << el.index[i] << ")";
  return s.str();
}

bool is_free(DofMode m) { return m == DofMode::Free; }

// Adds the wall time since `mark` to `seconds` and moves the mark to now.
using Clock = std::chrono::steady_clock;
inline void lap(Clock::time_point& mark, double& seconds) {
  const Clock::time_point now = Clock::now();
  seconds += std::chrono::duration<double>(now - mark).count();
  mark = now;
}

// Adds body(b, e, sums, marks)'s contributions over [b, e) to sums[0..N), for i in [0, n),
// threaded, in a fixed order: each thread runs its static block (OpenMP's schedule(static): the
// first n % team threads one element more) into its own slot and the slots are added in thread
// order. OpenMP's reduction(+) adds the threads' sums in the order they finish, which changes the
// last bits from run to run, so a run (and a run resumed from a checkpoint) would not repeat
// exactly. marks[k]: the largest element index the body flagged with k (-1: none), per thread
// then over the threads (a maximum, exact in any order); no critical section in the loop.
// Each thread runs its own copy of body, so the values it captured stay in registers.
template <std::size_t N, class Slots, class Body>
std::array<long, 2> ordered_sums(long n, Slots& partial, std::array<double*, N> sums,
                                 const Body& body) {
  static_assert(N <= 6);
  const int team = static_cast<int>(partial.size());
  int used = 1;  // the threads that ran (and wrote their slot)
#pragma omp parallel num_threads(team) if (n >= kParallelMinItems)
  {
    const Body b = body;
    std::array<double, N> ts{};
    std::array<long, 2> marks{-1, -1};
    const long nt = omp_get_num_threads(), t = omp_get_thread_num();
    const long q = n / nt, r = n % nt;
    const long begin = t * q + std::min(t, r);
    b(begin, begin + q + (t < r), ts, marks);
    auto& slot = partial[t];
    for (std::size_t k = 0; k < N; ++k) slot.sum[k] = ts[k];  // (std::copy would keep ts in memory)
    slot.mark = marks;
    if (t == 0) used = static_cast<int>(nt);
  }
  std::array<long, 2> marks{-1, -1};
  for (int t = 0; t < used; ++t) {
    for (std::size_t k = 0; k < N; ++k) *sums[k] += partial[t].sum[k];
    for (int k = 0; k < 2; ++k) marks[k] = std::max(marks[k], partial[t].mark[k]);
  }
  return marks;
}

// A range body of ordered_sums from a body of one element.
template <class Body>
auto each(const Body& body) {
  return [body](long b, long e, auto& s, auto& marks) __attribute__((always_inline)) {
    for (long i = b; i < e; ++i) body(i, s, marks);
  };
}

// A range body that runs whole chunks of free (or clamped) isotropic elements in SIMD lanes
// (step_simd.h) where `pass` is set, and the others, and what the lanes leave, element by element.
// The body's sums start with the pass's own (pass 2's when it runs, else pass 1's); kS1: where pass
// 1's start when both run.
template <std::size_t kS1, class Body>
auto chunked(const step_simd::Pass* pass, long lanes, const Body& body) {
  return [ pass, lanes, body ](long b, long e, auto& s, auto& marks)
      __attribute__((always_inline)) {
    for (long i = b; i < e;) {
      long stop = e;
      if (pass) {
        i = step_simd::run(*pass, i, e, s.data(), s.data() + kS1, &marks[0]);
        stop = std::min(e, i + lanes);
      }
      for (; i < stop; ++i) body(i, s, marks);
    }
  };
}

// The arrays and settings of a pass in lanes (step_simd.h) from a pass's context; the sink's
// buffer pointers are kept in buffers (4 per thread). loads: whether any element may carry an
// external load (else the pass does not read f_ext, t_ext: all zero).
step_simd::Pass lanes_pass(const step::StepContext& c, bool second, bool first, bool loads,
                           std::vector<double*>& buffers) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double) && sizeof(Quat) == 4 * sizeof(double));
  static_assert(sizeof(std::array<DofMode, 6>) == 6);
  static_assert(static_cast<unsigned char>(DofMode::Fixed) == step_simd::kDofFixed &&
                static_cast<unsigned char>(DofMode::Prescribed) == step_simd::kDofPrescribed);
  Elements& E = *c.E;
  auto d = [](auto& v) { return reinterpret_cast<double*>(v.data()); };
  auto cd = [](const auto& v) { return reinterpret_cast<const double*>(v.data()); };
  step_simd::Pass p;
  p.x = d(E.x);
  p.q = d(E.q);
  p.v = d(E.v);
  p.w = d(E.w);
  p.f = d(E.f);
  p.t = d(E.t);
  p.fd = reinterpret_cast<double*>(c.fd);
  p.td = reinterpret_cast<double*>(c.td);
  p.f_ext = loads ? cd(E.f_ext) : nullptr;
  p.t_ext = loads ? cd(E.t_ext) : nullptr;
  p.mass = E.mass.data();
  p.inv_mass = E.inv_mass.data();
  p.inertia = cd(E.inertia);
  p.radius = E.radius.data();
  p.v_prescribed = cd(E.v_prescribed);
  p.dof = reinterpret_cast<const unsigned char*>(E.dof.data());
  if (second && c.sink) {
    const int nt = c.sink->threads();
    buffers.resize(4 * static_cast<std::size_t>(nt));  // no allocation after the first step
    for (int k = 0; k < nt; ++k) {
      buffers[k] = reinterpret_cast<double*>(c.sink->force(k));
      buffers[nt + k] = reinterpret_cast<double*>(c.sink->torque(k));
      if (c.sink->has_damping())
        buffers[2 * nt + k] = reinterpret_cast<double*>(c.sink->damping_force(k));
      if (c.sink->has_damping_torque())
        buffers[3 * nt + k] = reinterpret_cast<double*>(c.sink->damping_torque(k));
    }
    p.sink_f = buffers.data();
    p.sink_t = buffers.data() + nt;
    if (c.sink->has_damping()) p.sink_fd = buffers.data() + 2 * nt;
    if (c.sink->has_damping_torque()) p.sink_td = buffers.data() + 3 * nt;
    p.sink_threads = nt;
  }
  p.dt = c.dt;
  p.h = c.h;
  if (second) {
    p.alpha = c.alpha;
    p.model_damping = c.model_damping;
  }
  p.second = second;
  p.first = first;
  return p;
}

// Runs f.template operator()<C>() with element i's class: FreeIsotropic when it is one and the
// fast path is on, else General.
template <class F>
inline void by_class(bool fast, const Elements& E, long i, F&& f) {
  if (fast && step::free_isotropic(E, static_cast<std::size_t>(i)))
    f.template operator()<step::ElementClass::FreeIsotropic>();
  else
    f.template operator()<step::ElementClass::General>();
}

}  // namespace

const char* step_simd_target() { return step_simd::target_name(); }

System::System(Elements el, IntegratorSettings s) : el_(std::move(el)), settings_(s) {}
System::~System() = default;
System::System(System&&) noexcept = default;
System& System::operator=(System&&) noexcept = default;

namespace {
// A plain function as an updater.
class FunctionUpdater final : public Updater {
 public:
  explicit FunctionUpdater(std::function<void(System&, double)> fn) : fn_(std::move(fn)) {}
  void apply(System& sys, double t) override { fn_(sys, t); }

 private:
  std::function<void(System&, double)> fn_;
};
}  // namespace

void System::add_updater(std::shared_ptr<Updater> u) {
  if (!u) throw std::invalid_argument("System::add_updater: null updater");
  updaters_.push_back(std::move(u));
}

void System::add_updater(std::function<void(System&, double)> fn) {
  add_updater(std::make_shared<FunctionUpdater>(std::move(fn)));
}

void System::set_local_damping(double alpha) {
  if (!std::isfinite(alpha) || alpha < 0 || alpha >= 1)
    throw ConfigError("local_damping must be in [0, 1), got " + std::to_string(alpha));
  settings_.local_damping = alpha;
  dissipative_ = dissipative_ || alpha > 0;
}

void System::set_model_active(const ForceModel* m, bool active) {
  if (std::none_of(models_.begin(), models_.end(), [m](const auto& p) { return p.get() == m; }))
    throw std::invalid_argument("System::set_model_active: not a model of this system");
  std::erase(inactive_, m);
  if (!active) inactive_.push_back(m);
}

bool System::model_active(const ForceModel* m) const {
  return std::find(inactive_.begin(), inactive_.end(), m) == inactive_.end();
}

void System::initialize() {
  const IntegratorSettings& s = settings_;
  auto bad = [](const std::string& m) { throw ConfigError(m); };
  if (!std::isfinite(s.safety) || s.safety <= 0 || s.safety > 1)
    bad("safety must be in (0, 1], got " + std::to_string(s.safety));
  if (!std::isfinite(s.local_damping) || s.local_damping < 0 || s.local_damping >= 1)
    bad("local_damping must be in [0, 1), got " + std::to_string(s.local_damping));
  if (!std::isfinite(s.skin) || s.skin <= 0 || s.skin > 100)
    bad("skin must be in (0, 100] nm, got " + std::to_string(s.skin));
  if (s.threads < 0 || s.threads > limits::kMaxThreads)
    bad("threads must be in [0, " + std::to_string(limits::kMaxThreads) +
        "] (0 = all cores), got " + std::to_string(s.threads));
  if (s.guard_every < 1) bad("guard_every must be >= 1 step");
  if (!std::isfinite(s.guard_energy_tolerance) || s.guard_energy_tolerance <= 0)
    bad("guard_energy_tolerance must be finite and > 0");
  if (s.dt && (!std::isfinite(*s.dt) || *s.dt <= 0))
    bad("dt must be finite and > 0 ps (or auto), got " + std::to_string(*s.dt));
  if (s.respa_k < 1 || s.respa_k > limits::kMaxRespaK)
    bad("respa_k must be an integer in [1, " + std::to_string(limits::kMaxRespaK) +
        "] (inner steps per outer step, 1 = off), got " + std::to_string(s.respa_k));
  for (std::size_t i = 0; i < el_.size(); ++i) {
    if (el_.is_isotropic(i)) continue;
    for (int k = 3; k < 6; ++k)
      if (!is_free(el_.dof[i][k]))
        bad(describe(el_, i) +
            ": rotational constraints need isotropic inertia (anisotropic bodies rotate freely)");
  }

  threads_ = s.threads > 0 ? s.threads : omp_get_max_threads();
  omp_set_num_threads(threads_);

  dissipative_ = s.local_damping > 0;
  bool model_damping = false, model_damping_torque = false;
  for (const auto& m : models_) {
    model_damping = model_damping || m->dissipative();
    model_damping_torque = model_damping_torque || m->damping_torques();
    m->bind_domain(domain_.get());
  }
  dissipative_ = dissipative_ || model_damping;
  try {
    pairs_.setup(models_, s.skin, *domain_);
  } catch (const std::invalid_argument& e) {
    bad(e.what());
  }
  check_memory_order();
  // A pair-table entry's owner and its first other member share a list: they may run as one.
  pair_partner_.assign(models_.size(), -1);
  computed_.assign(models_.size(), 0);
  const auto index_of = [&](const ForceModel* m) {
    return static_cast<int>(
        std::find_if(models_.begin(), models_.end(), [m](const auto& p) { return p.get() == m; }) -
        models_.begin());
  };
  for (const auto& e : pairs_.entries())
    if (e.members.size() > 1) {
      const int a = index_of(e.owner), b = index_of(e.members[1]);
      pair_partner_[a] = b;
      pair_partner_[b] = a;
    }

  const std::size_t n = el_.size();
  sink_.resize(n, threads_, model_damping, model_damping_torque);
  partial_sums_.assign(threads_, ThreadSlot{});
  respa_.setup(s.respa_k, n);
  fd_.assign(n, Vec3::Zero());
  td_.assign(n, Vec3::Zero());

  for (auto& u : updaters_) u->apply(*this, time_);
  compute_forces();
  check_finite_forces();

  dt_critical_ = compute_critical_dt();
  if (s.dt) {
    if (s.check_dt && *s.dt > max_safe_dt()) {
      std::ostringstream m;
      m << "time step dt = " << *s.dt << " ps is above the safe limit " << max_safe_dt()
        << " ps (safety " << s.safety << " x critical step " << dt_critical_
        << " ps from the stiffest bond/contact); use dt <= " << max_safe_dt() << " ps or dt: auto";
      throw ConfigError(m.str());
    }
    dt_ = *s.dt;
  } else {
    if (!std::isfinite(dt_critical_))
      bad("dt: auto needs at least one bond or contact to derive a step from; give dt in ps");
    dt_ = max_safe_dt();
  }
  dt_critical_outer_ =
      respa_.on() ? compute_critical_dt(true) : std::numeric_limits<double>::infinity();
  if (s.check_dt && respa_.k() * dt_ > s.safety * dt_critical_outer_) {
    std::ostringstream m;
    m << "outer step respa_k x dt = " << respa_.k() << " x " << dt_ << " ps is above the slow "
      << "forces' safe limit " << s.safety * dt_critical_outer_ << " ps (safety " << s.safety
      << " x their critical step " << dt_critical_outer_ << " ps); use respa_k <= "
      << std::max(1, static_cast<int>(s.safety * dt_critical_outer_ / dt_)) << " at this dt";
    throw ConfigError(m.str());
  }

  update_kinetic();
  start_ledger();
  initialized_ = true;
}

void System::start_ledger() {
  ledger_.initial_total = ledger_.total();
  ledger_.external_work = 0;
  ledger_.dissipated = 0;
  initial_kinetic_ = ledger_.kinetic();
  initial_stored_ = ledger_.potential.total_stored();
  energy_scale_ = initial_kinetic_;
}

void System::restart_clock() {
  time_ = 0;
  steps_ = 0;  // first: step 0 opens an outer step (multiple time stepping)
  refresh();
  start_ledger();
}

void System::refresh() {
  if (!initialized_) {
    initialize();
    return;
  }
  compute_forces();
  check_finite_forces();
  update_kinetic();
}

void System::refresh_booking_work() {
  const double before = ledger_.potential.total_stored();
  refresh();
  ledger_.external_work += ledger_.potential.total_stored() - before;
  update_energy_scale();
}

void System::compute_forces(bool with_local_damping, StepTimers* timers, bool in_step,
                            bool defer_sums) {
  Clock::time_point mark;
  if (timers) mark = Clock::now();
  update_pairs();
  if (timers) lap(mark, timers->neighbor_s);
  sink_.clear();
  compute_models(false);
  // Deferred: the caller's pass takes each element's sums (ForceSink::take), the energies now.
  sums_deferred_ = defer_sums && !respa_.on();
  ledger_.potential = sums_deferred_ ? sink_.energy_total() : sink_.reduce(el_.f, el_.t, fd_, td_);
  if (respa_.on()) add_slow_forces(in_step);
  if (timers) lap(mark, timers->pair_s);

  const double a = settings_.local_damping;
  if (a == 0) {
    // fd_, td_ hold the model dampers' forces, or are zero (also after a stage turned local
    // damping off: set_local_damping).
    if (!sink_.has_damping() && local_damping_was_on_) {
      std::fill(fd_.begin(), fd_.end(), Vec3::Zero());
      std::fill(td_.begin(), td_.end(), Vec3::Zero());
      local_damping_was_on_ = false;
    }
    return;
  }
  local_damping_was_on_ = true;
  if (!with_local_damping) return;  // the caller's pass over the elements adds it
  const long n = static_cast<long>(el_.size());
  const bool model_damping = sink_.has_damping();
  const RespaSplit* net = respa_.on() ? &respa_ : nullptr;
  const double w = respa_.net_weight(steps_);
#pragma omp parallel for schedule(static) if (n >= kParallelMinItems)
  for (long i = 0; i < n; ++i) {
    if (net)
      step::local_damping<step::ElementClass::General, true>(el_, i, a, model_damping, fd_[i],
                                                             td_[i], net, w);
    else
      step::local_damping<step::ElementClass::General, false>(el_, i, a, model_damping, fd_[i],
                                                              td_[i], nullptr, 0);
  }
}

void System::compute_models(bool slow) {
  const auto wanted = [&](std::size_t a) {
    const ForceModel& m = *models_[a];
    return (slow ? respa_.slow(m) : respa_.inner(m)) && (inactive_.empty() || model_active(&m));
  };
  std::fill(computed_.begin(), computed_.end(), char{0});
  for (std::size_t a = 0; a < models_.size(); ++a) {
    if (computed_[a] || !wanted(a)) continue;
    const ForceModel& m = *models_[a];
    const NeighborList* list = pairs_.list_of(&m);
    computed_[a] = 1;
    if (const int b = pair_partner_[a]; b >= 0 && !computed_[b] && wanted(b)) {
      const ForceModel& o = *models_[b];
      const bool both = m.pair_owner().empty() ? o.compute_with(m, el_, list, sink_)
                                               : m.compute_with(o, el_, list, sink_);
      if (both) {
        computed_[b] = 1;
        continue;
      }
    }
    m.compute(el_, list, sink_);
  }
}

void System::add_slow_forces(bool in_step) {
  const bool closes = respa_.closes_outer_step(steps_);
  if (closes || !in_step) {
    sink_.clear();
    compute_models(true);
    respa_.tally = sink_.reduce(respa_.f, respa_.t, respa_.fd, respa_.td);
    respa_.tags = el_.tag;
  } else {
    respa_.follow(el_);  // the elements were reordered since (memory order)
  }
  if (closes) {
    respa_.add_impulse(el_.f, el_.t, fd_, td_, sink_.has_damping());
    ledger_.potential += respa_.tally;
  } else {
    ledger_.potential += respa_.held();
  }
}

void System::update_kinetic() {
  double kt = 0, kr = 0;
  const long n = static_cast<long>(el_.size());
  ordered_sums<2>(n, partial_sums_, {&kt, &kr}, each([this](long i, auto& k, auto&) {
                    k[0] += step::kinetic_translational(el_, i);
                    k[1] += step::kinetic_rotational(el_, i, el_.is_isotropic(i));
                  }));
  ledger_.kinetic_translational = kt;
  ledger_.kinetic_rotational = kr;
}

StiffnessSums System::stiffness_sums(bool slow_only) const {
  StiffnessSums s;
  s.reset(el_.size());
  for (const auto& m : models_)
    if ((!slow_only || respa_.slow(*m)) && (inactive_.empty() || model_active(m.get())))
      m->add_stiffness(el_, pairs_.list_of(m.get()), s);
  return s;
}

namespace {
// Damping lowers the limit of an oscillator of frequency w: dt_c = (2/w)(√(1+ζ²) − ζ).
double damped_limit(double w, double zeta) {
  return 2.0 / w * (std::sqrt(1.0 + zeta * zeta) - zeta);
}
}  // namespace

double System::damped_critical_dt(double omega) const {
  if (std::isnan(omega)) throw std::invalid_argument("damped_critical_dt: the frequency is NaN");
  if (!(omega > 0)) return std::numeric_limits<double>::infinity();
  const StiffnessSums s = stiffness_sums(false);
  double zeta = 0;
  for (std::size_t i = 0; i < el_.size(); ++i)
    zeta = std::max(zeta, s.c[i] / (el_.mass[i] * omega));
  return damped_limit(omega, zeta);
}

double System::compute_critical_dt(bool slow_only) const {
  const StiffnessSums s = stiffness_sums(slow_only);
  double dt = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < el_.size(); ++i) {
    const double m = el_.mass[i];
    const double I = el_.inertia[i].minCoeff();
    // Gershgorin bound of the largest eigenfrequency of M^-1/2 K M^-1/2 over this element's rows:
    // each interaction contributes its diagonal and one off-diagonal block (factor 2), plus the
    // translation-rotation coupling on both kinds of rows.
    const double coupling = 2.0 * s.ktr[i] / std::sqrt(m * I);
    const double w2 = std::max(2.0 * s.kt[i] / m, 2.0 * s.kr[i] / I) + coupling;
    if (!(w2 > 0)) continue;
    const double w = std::sqrt(w2);
    // Damping lowers the limit, ζ ≤ Σc/(m ω).
    dt = std::min(dt, damped_limit(w, s.c[i] / (m * w)));
  }
  return dt;
}

void System::check_finite_forces() const {
  for (std::size_t i = 0; i < el_.size(); ++i) {
    if (!el_.x[i].allFinite() || !el_.q[i].coeffs().allFinite())
      throw NumericalError(describe(el_, i) + " has a non-finite position or orientation at step " +
                               std::to_string(steps_),
                           steps_, static_cast<long>(i));
    if (!el_.f[i].allFinite() || !el_.t[i].allFinite() || !fd_[i].allFinite() ||
        !td_[i].allFinite())
      throw NumericalError("non-finite force or torque on " + describe(el_, i) + " at step " +
                               std::to_string(steps_) +
                               ": elements overlap so deeply that a contact diverges, or an input "
                               "value is not finite",
                           steps_, static_cast<long>(i));
  }
}

std::string System::unstable_cause() const {
  // Above the safe limit (the check was off) the step is the cause; within it, lowering dt alone
  // may only postpone the stop (a tensile film at 300 % strain stopped so at 0.16 x critical).
  if (dt_ > max_safe_dt())
    return "dt is above the safe limit " + std::to_string(max_safe_dt()) +
           " ps: lower dt, or use dt: auto";
  if (respa_.k() * dt_ > settings_.safety * dt_critical_outer_)
    return "the outer step respa_k x dt is above the slow forces' safe limit " +
           std::to_string(settings_.safety * dt_critical_outer_) + " ps: lower respa_k";
  return "dt is within the safe limit (from the stiffness at the start), so the step alone is "
         "not the cause: check for deeply overlapping or coincident elements (they stiffen "
         "contacts past that limit: lower safety), a load that runs away, or a fragment torn "
         "loose and spun up";
}

void System::run(long nsteps) {
  if (!initialized_) initialize();
  check_memory_order();  // a stage may have installed updaters since
  omp_set_num_threads(threads_);
  const bool loads = any_loads();  // for the whole run (its updaters do not change within it)
  const double dt = dt_, h = 0.5 * dt_;
  const long n = static_cast<long>(el_.size());
  auto& E = el_;
  const double a_local = settings_.local_damping;
  StepTimers& timers = timers_;

  // The per-element kernels (step_kernels.h): 1. first half kick and drift, 2. local damping,
  // second half kick and kinetic energy. An element that ran away in 1. is marked 0, one whose
  // velocity became non-finite in 2. is marked 1 (ordered_sums' marks). The context is taken
  // afresh for each pass: a reordering of the elements (memory order) reallocates fd_, td_.
  const bool fast = settings_.free_isotropic_fast_path;
  const long lanes = static_cast<long>(step_simd::lanes());
  auto context = [&] { return step::StepContext{&E, fd_.data(), td_.data(), dt, h}; };
  long runaway = -1;
  // Each element's arithmetic is that of velocity Verlet, in one pass over the elements per step
  // (plus the force evaluation's own): pass 2 of step n and pass 1 of step n+1 run in one loop,
  // element by element (each reads and writes its own element only), except at the last step of
  // this call and where the energy guard runs (so a guard that stops the run sees the state of
  // step n, as without the fusion). The sums are per thread in a fixed order (ordered_sums), each
  // step's apart, so the books are bit for bit those of separate passes.
  Clock::time_point mark = Clock::now();
  double work = 0, diss = 0;
  bool first_done = false;  // pass 1 of this step ran with the previous step's pass 2
  for (long step = 0; step < nsteps; ++step) {
    if (!first_done) {
      work = diss = 0;
      const step::StepContext c = context();
      auto first = [ c, fast ](long i, auto& s, auto& mark) __attribute__((always_inline)) {
        by_class(
            fast, *c.E, i, [&]<step::ElementClass C>() __attribute__((always_inline)) {
              if (!step::first_element<C>(c, i, s[0], s[1])) mark[0] = i;
            });
      };
      const step_simd::Pass p1 = lanes_pass(c, false, true, loads, sink_buffers_);
      runaway = ordered_sums<2>(n, partial_sums_, {&work, &diss},
                                chunked<0>(fast ? &p1 : nullptr, lanes, first))[0];
    }
    if (runaway >= 0) {
      const std::size_t i = static_cast<std::size_t>(runaway);
      std::string cause;  // a load that explains the runaway, else the step's own account
      for (const auto& u : updaters_)
        if (cause.empty()) cause = u->explain_runaway(*this, i);
      std::ostringstream m;
      m << describe(E, i) << " moved " << (E.v[i] * dt).norm() << " nm and turned "
        << E.w[i].norm() * dt << " rad in one step at step " << steps_ + 1 << " (t = " << time_ + dt
        << " ps): the run is unstable; dt = " << dt_ << " ps against a critical step of "
        << dt_critical_ << " ps - " << (cause.empty() ? unstable_cause() : cause);
      throw NumericalError(m.str(), steps_ + 1, runaway);
    }

    time_ += dt;
    ++steps_;
    lap(mark, timers.integrate_s);
    for (auto& u : updaters_) u->apply(*this, time_);
    lap(mark, timers.updaters_s);
    compute_forces(false, &timers, true, true);
    mark = Clock::now();

    const step::StepContext c = context();
    step::StepContext c2 = c;
    c2.alpha = a_local;
    c2.model_damping = sink_.has_damping();
    c2.net = respa_.on() ? &respa_ : nullptr;
    c2.w_net = respa_.net_weight(steps_);
    c2.sink = sums_deferred_ ? &sink_ : nullptr;  // the pass takes the forces it kicks with
    auto second = [ c2, fast ](long i, auto& s, auto& mark) __attribute__((always_inline)) {
      by_class(
          fast, *c2.E, i, [&]<step::ElementClass C>() __attribute__((always_inline)) {
            if (!step::second_element<C>(c2, i, s[0], s[1], s[2], s[3])) mark[1] = i;
          });
    };
    // Pass 2 of this step and, where it succeeded, pass 1 of the next (with the context of pass
    // 1, which has no local damping).
    auto second_first =
        [ c, c2, fast ](long i, auto& s, auto& mark) __attribute__((always_inline)) {
      by_class(
          fast, *c2.E, i, [&]<step::ElementClass C>() __attribute__((always_inline)) {
            if (!step::second_element<C>(c2, i, s[0], s[1], s[2], s[3]))
              mark[1] = i;
            else if (!step::first_element<C>(c, i, s[4], s[5]))
              mark[0] = i;
          });
    };
    long bad = -1;
    // The books close only where an outer step does (the slow energy is held in between).
    const bool guard =
        respa_.closes_outer_step(steps_) && steps_ % settings_.guard_every < respa_.k();
    const bool fuse = !guard && step + 1 < nsteps;
    double kt = 0, kr = 0, work_next = 0, diss_next = 0;
    // Lanes take pass 2 unless multiple time stepping's held forces enter local damping.
    const bool lanes2 = fast && !(c2.alpha > 0 && c2.net);
    step_simd::Pass p2 = lanes_pass(c2, true, fuse, loads, sink_buffers_);
    // Whether an updater's next apply() reads the forces this pass takes (else a fused pass
    // keeps them in registers: step_simd::Pass::keep_forces).
    p2.keep_forces = std::any_of(updaters_.begin(), updaters_.end(),
                                 [](const auto& u) { return u->reads_forces(); });
    if (fuse) {
      const auto marks =
          ordered_sums<6>(n, partial_sums_, {&work, &diss, &kt, &kr, &work_next, &diss_next},
                          chunked<4>(lanes2 ? &p2 : nullptr, lanes, second_first));
      runaway = marks[0];
      bad = marks[1];
    } else {
      bad = ordered_sums<4>(n, partial_sums_, {&work, &diss, &kt, &kr},
                            chunked<0>(lanes2 ? &p2 : nullptr, lanes, second))[1];
    }
    if (c2.sink) sink_.taken();
    if (bad >= 0) check_finite_forces();  // names the element and the cause
    if (bad >= 0)
      throw NumericalError("non-finite velocity of " + describe(E, static_cast<std::size_t>(bad)) +
                               " at step " + std::to_string(steps_),
                           steps_, bad);

    ledger_.external_work += work;
    // Damping, plus the stored energy the models released for good in this step's evaluation
    // (plastic flow, bonds breaking). Only evaluations inside run() count: initialize() resets
    // the books, and refresh() follows edits the ledger cannot account for.
    ledger_.dissipated += diss + ledger_.potential.released;
    ledger_.kinetic_translational = kt;
    ledger_.kinetic_rotational = kr;
    if (guard) check_energy_growth();
    first_done = fuse;
    work = work_next;
    diss = diss_next;
    lap(mark, timers.integrate_s);
  }
}

bool System::any_loads() const {
  if (std::any_of(updaters_.begin(), updaters_.end(),
                  [](const auto& u) { return u->applies_loads(); }))
    return true;
  // Anything but +0 (a −0 or a NaN too), so that the pass's zeros are the stored ones bit for bit.
  const auto set = [](const Vec3& v) {
    return (v.x() != 0.0) | (v.y() != 0.0) | (v.z() != 0.0) | std::signbit(v.x()) |
           std::signbit(v.y()) | std::signbit(v.z());
  };
  const long n = static_cast<long>(el_.size());
  int loaded = 0;  // an OR over the elements: exact in any order
#pragma omp parallel for schedule(static) reduction(| : loaded) if (n >= kParallelMinItems)
  for (long i = 0; i < n; ++i) loaded |= set(el_.f_ext[i]) | set(el_.t_ext[i]);
  return loaded != 0;
}

void System::update_energy_scale() {
  // The energy legitimately in play: initial kinetic energy, work put in, energy dissipated, and
  // stored energy released. Not the current kinetic or stored energy, which an instability grows.
  const EnergyLedger& L = ledger_;
  energy_scale_ = std::max({energy_scale_, initial_kinetic_, std::abs(L.external_work),
                            std::abs(L.dissipated), initial_stored_ - L.potential.total_stored()});
}

void System::check_energy_growth() {
  const EnergyLedger& L = ledger_;
  update_energy_scale();
  if (!std::isfinite(L.total()) || !std::isfinite(L.external_work) ||
      !std::isfinite(L.dissipated)) {
    check_finite_forces();
    throw NumericalError("energy became non-finite at step " + std::to_string(steps_), steps_, -1);
  }
  // Unexplained growth: the system holds more energy than external work put in.
  const double growth = -L.balance_residual();
  const double floor = 1e-4 * static_cast<double>(el_.size());  // eV, ~1 K per element
  const double limit = settings_.guard_energy_tolerance * std::max(energy_scale_, floor);
  if (growth > limit) {
    // Blame the element with the largest kinetic energy: that is where an instability shows.
    std::size_t worst = 0;
    double ke_max = -1;
    for (std::size_t i = 0; i < el_.size(); ++i) {
      const double ke = el_.mass[i] * el_.v[i].squaredNorm();
      if (ke > ke_max) {
        ke_max = ke;
        worst = i;
      }
    }
    std::ostringstream m;
    m << "energy grew by " << growth << " eV more than external work explains at step " << steps_
      << " (t = " << time_ << " ps; tolerance " << limit << " eV); fastest is "
      << describe(el_, worst) << ": the integration is unstable (dt " << dt_ << " ps, critical "
      << dt_critical_ << " ps) - " << unstable_cause();
    throw NumericalError(m.str(), steps_, static_cast<long>(worst));
  }
}

double System::energy_balance_error() const {
  const EnergyLedger& L = ledger_;
  const double scale =
      std::max({energy_scale_, initial_kinetic_, std::abs(L.external_work), std::abs(L.dissipated),
                initial_stored_ - L.potential.total_stored(), 1e-300});
  return std::abs(L.balance_residual()) / scale;
}

}  // namespace mdem
