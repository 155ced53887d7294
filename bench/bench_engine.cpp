// Engine throughput: element-steps per second of full velocity-Verlet steps (parallel bonds +
// anisotropic vdW + neighbour list) on a seven-tube bundle and on a random in-plane film, each on
// 1 and 2 threads, and the neighbour-list build alone on the film.
//
// Rates are per wall-clock second (UseRealTime), the figure that matters for threaded runs.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <tuple>

#include "bench_support.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/contact/np_cnt_contact.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/integrate/system.h"
#include "mdem/job/tensile_job.h"
#include "mdem/job/twist_job.h"
#include "mdem/neighbor/neighbor_list.h"
#include "mdem/scene/film_builder.h"
#include "mdem/scene/tensile_film.h"

using namespace mdem;

namespace {

// Every benchmark here runs on 1 and 2 threads, timed by the wall clock (UseRealTime).
void one_and_two_threads(benchmark::internal::Benchmark* b) {
  b->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);
}

struct Scene {
  Elements el;
  std::unique_ptr<ParallelBond> bonds = std::make_unique<ParallelBond>();
};

// (a) Seven 100-segment tubes, 1.7 nm apart (about the vdW equilibrium spacing): 700 segments.
Scene bundle_scene() {
  Scene s;
  add_seven_tube_bundle(s.el, 100, 1.7);
  s.bonds = ParallelBond::from_topology(s.el, BondType::Cnt, cnt_bond_stiffness());
  return s;
}

// (b) A film of the areal density of the thesis's medium film (Table 5-1: 350 tubes of 475 nm,
// ≈ 122 500 segments in 500 × 500 nm², 0.49 segments/nm²): 500 tubes × 100 segments = 50 000
// segments in 320 × 320 nm² (0.49 /nm²), 11 nm thick, at most 2° out of plane.
FilmSpec film_spec() {
  FilmSpec f;
  f.side = 320;
  f.thickness = 11;
  f.tubes = 500;
  f.segments_per_tube = 100;
  f.seed = 2024;
  return f;
}

// Every film of these benchmarks is built here, with the project's own generator.
Scene make_film(const FilmSpec& spec) {
  Scene s;
  add_random_film(s.el, spec);
  s.bonds = ParallelBond::from_topology(s.el, BondType::Cnt, cnt_bond_stiffness());
  return s;
}

Scene film_scene() { return make_film(film_spec()); }

// The generated film has tubes crossing through each other. A short damped pre-relaxation
// (PFC local damping) pushes the worst overlaps apart so the timed run starts from a state a
// production run would reach; its end state is cached and shared by the film benchmarks.
const Elements& relaxed_film() {
  static const Elements relaxed = [] {
    Scene s = film_scene();
    IntegratorSettings set;
    set.local_damping = 0.7;
    System sys(std::move(s.el), set);
    sys.add(std::move(s.bonds));
    sys.add(std::make_unique<AnisotropicVdw>());
    sys.initialize();
    sys.run(200);
    Elements out = sys.elements();
    for (std::size_t i = 0; i < out.size(); ++i) {
      out.v[i].setZero();
      out.w[i].setZero();
    }
    return out;
  }();
  return relaxed;
}

// Bonds of the film rebuilt for the (relaxed) elements: the bond rest state is the generated
// straight tube, so the bonds are made on the generated film and reused as they are.
std::unique_ptr<ParallelBond> film_bonds() { return std::move(film_scene().bonds); }

void run_steps(benchmark::State& state, Elements el, std::unique_ptr<ParallelBond> bonds,
               long steps_per_iteration) {
  IntegratorSettings set;
  set.threads = static_cast<int>(state.range(0));
  System sys(std::move(el), set);
  sys.add(std::move(bonds));
  sys.add(std::make_unique<AnisotropicVdw>());
  sys.initialize();
  sys.run(steps_per_iteration);  // warm-up: buffers sized, first rebuilds done
  const std::size_t builds0 = sys.neighbors() ? sys.neighbors()->builds() : 0;
  const double steps = bench::timed_steps(state, sys, steps_per_iteration);
  state.counters["steps_per_s"] = benchmark::Counter(steps, benchmark::Counter::kIsRate);
  state.counters["dt_fs"] = sys.dt() * 1e3;
  if (sys.neighbors()) {
    state.counters["pairs"] = static_cast<double>(sys.neighbors()->pair_count());
    state.counters["rebuilds_per_step"] =
        static_cast<double>(sys.neighbors()->builds() - builds0) / steps;
  }
}

void BM_BundleSteps(benchmark::State& state) {
  Scene s = bundle_scene();
  run_steps(state, std::move(s.el), std::move(s.bonds), 200);
}
BENCHMARK(BM_BundleSteps)->Apply(one_and_two_threads);

void BM_FilmSteps(benchmark::State& state) { run_steps(state, relaxed_film(), film_bonds(), 10); }
// 40 steps: several neighbour-list rebuilds per measurement.
BENCHMARK(BM_FilmSteps)->Apply(one_and_two_threads)->Iterations(4);

// A neighbour list built on el for pair model m alone (its cutoff, kinds' exclusion, owner).
NeighborList list_for(const ForceModel& m, const Elements& el) {
  NeighborList nl(m.cutoff(), IntegratorSettings{}.skin);
  nl.set_exclusion(
      [&m](const Elements& e, std::size_t i, std::size_t j) { return m.excludes(e, i, j); });
  nl.set_owner(&m);
  nl.build(el);
  return nl;
}

// One evaluation of model m per iteration into a sink of `threads` slots (cleared untimed), after
// one untimed warm-up evaluation.
void time_evaluations(benchmark::State& state, const ForceModel& m, const Elements& el,
                      const NeighborList* nl, int threads) {
  ForceSink sink;
  sink.resize(el.size(), threads, m.dissipative());
  m.compute(el, nl, sink);  // warm-up
  for (auto _ : state) {
    state.PauseTiming();
    sink.clear();
    state.ResumeTiming();
    m.compute(el, nl, sink);
  }
}

// Issue 13's films, the peer code's (waLBerla mesa_pd) CNT film set-up reproduced with our
// generator: 396 tubes × 148 segments = 58 608 segments, relaxed 500 steps at dt 20 fs under
// local damping 0.2 (no dashpots).
//   dense:  300 × 300 × 20 nm, at most 2° out of plane (relaxed: 7.5 listed vdW pairs per
//           segment, 5.7 within the cutoff; the peer counts 6.8);
//   sparse: 500 × 500 × 70 nm, at most 26° out of plane (0.86 listed, 0.65 within; peer 0.85).
FilmSpec issue13_film(bool dense) {
  FilmSpec f;
  f.side = dense ? 300 : 500;
  f.thickness = dense ? 20 : 70;
  f.max_out_of_plane_deg = dense ? 2 : 26;
  f.tubes = 396;
  f.segments_per_tube = 148;
  f.seed = 13;
  return f;
}
constexpr double kIssue13Dt = 0.020;  // ps

// A film system at dt 20 fs (the issue's, the peer's), or at our safe step when the critical step
// is smaller (the generated film's overlapping tubes sit on the stiff linear branch of the vdW
// law: its first safe step is ~5 fs). 20 fs is taken when it is within the critical step itself
// (safety 1): the critical step's rotational vdW bound (docs/stability.md) puts the relaxed dense
// film's at 22.9 fs, so the default safety 0.6 would run it at 13.7 fs, not the issue's set-up.
System issue13_system(Elements el, bool dense, int threads, double skin = IntegratorSettings{}.skin,
                      MemoryOrder order = MemoryOrder::AsBuilt) {
  auto build = [&](IntegratorSettings set) {
    System sys(el, set);
    sys.add(std::move(make_film(issue13_film(dense)).bonds));
    sys.add(std::make_unique<AnisotropicVdw>());
    sys.initialize();
    return sys;
  };
  IntegratorSettings set;
  set.threads = threads;
  set.local_damping = 0.2;
  set.skin = skin;
  set.safety = 1.0;
  set.memory_order = order;
  if (build(set).dt() >= kIssue13Dt) {
    set.dt = kIssue13Dt;
    return build(set);
  }
  set.safety = 0.6;  // the default safe step
  return build(set);
}

// The relaxed film (velocities zeroed), once per process and film: 500 steps in chunks of 100,
// the step re-chosen for each chunk.
const Elements& relaxed_issue13_film(bool dense) {
  auto relax = [](bool d) {
    Elements el = make_film(issue13_film(d)).el;
    for (int chunk = 0; chunk < 5; ++chunk) {
      System sys = issue13_system(std::move(el), d, 0);
      sys.run(100);
      el = sys.elements();
    }
    for (std::size_t i = 0; i < el.size(); ++i) {
      el.v[i].setZero();
      el.w[i].setZero();
    }
    return el;
  };
  static const Elements dense_film = relax(true);
  static const Elements sparse_film = relax(false);
  return dense ? dense_film : sparse_film;
}

// Full steps at the films' own step (dt 20 fs when safe, local damping 0.2, as they were relaxed),
// the elements as built (slabs:0, tube after tube) or in one slab of space per thread (slabs:1,
// MemoryOrder::Slabs; with 1 thread the same order as built).
void issue13_steps(benchmark::State& state, bool dense) {
  const Elements& el = relaxed_issue13_film(dense);
  const MemoryOrder order = state.range(1) ? MemoryOrder::Slabs : MemoryOrder::AsBuilt;
  System sys =
      issue13_system(el, dense, static_cast<int>(state.range(0)), IntegratorSettings{}.skin, order);
  sys.run(10);  // warm-up
  const StepTimers t0 = sys.timers();
  const double steps = bench::timed_steps(state, sys, 10);
  const double n = static_cast<double>(el.size());
  bench::add_phase_counters(state, t0, sys.timers(), steps);
  state.counters["dt_fs"] = sys.dt() * 1e3;
  state.counters["pairs_per_element"] = static_cast<double>(sys.neighbors()->pair_count()) / n;
}
void BM_DenseFilmSteps(benchmark::State& state) { issue13_steps(state, true); }
void BM_SparseFilmSteps(benchmark::State& state) { issue13_steps(state, false); }
// 1 and 2 threads, as built and (2 threads) in slabs.
void threads_and_slabs(benchmark::internal::Benchmark* b) {
  b->ArgNames({"threads", "slabs"})
      ->Args({1, 0})
      ->Args({2, 0})
      ->Args({2, 1})
      ->UseRealTime()
      ->Unit(benchmark::kMillisecond);
}
BENCHMARK(BM_DenseFilmSteps)->Apply(threads_and_slabs)->Iterations(4);
BENCHMARK(BM_SparseFilmSteps)->Apply(threads_and_slabs)->Iterations(6);

// The integrator's pass alone (kicks, drift, local damping 0.2, kinetic energy, guard) on issue
// 13's sparse film as generated, cut to its first `tubes` tubes × 148 segments: both force models
// switched off, random velocities and spins (0.02 nm/ps and rad/ps per component, the order of
// 300 K), so every element takes the free isotropic fast path with the signs of a thermal film.
// integrate_ms and ns_per_element are the pass's (the timers' integrate phase). 8 tubes (1184
// elements, ~1 MB of the pass's arrays) run from the core's caches, 396 (the whole film) from
// memory, so the pair says how much of the pass is memory traffic.
void BM_IntegratorPass(benchmark::State& state) {
  FilmSpec f = issue13_film(false);
  f.tubes = static_cast<int>(state.range(1));
  Scene film = make_film(f);
  IntegratorSettings set;
  set.threads = static_cast<int>(state.range(0));
  set.local_damping = 0.2;
  set.dt = kIssue13Dt;
  System sys(std::move(film.el), set);
  sys.add(std::move(film.bonds));
  sys.initialize();
  Elements& el = sys.elements();
  std::mt19937_64 rng(13);
  std::normal_distribution<double> g(0.0, 0.02);
  for (std::size_t i = 0; i < el.size(); ++i) {
    el.v[i] = Vec3(g(rng), g(rng), g(rng));
    el.w[i] = Vec3(g(rng), g(rng), g(rng));
  }
  for (const auto& m : sys.models()) sys.set_model_active(m.get(), false);
  sys.restart_clock();
  sys.run(10);
  const StepTimers t0 = sys.timers();
  const double steps = bench::timed_steps(state, sys, 100);
  const double n = static_cast<double>(el.size());
  bench::add_phase_counters(state, t0, sys.timers(), steps);
  state.counters["ns_per_element"] =
      (sys.timers().integrate_s - t0.integrate_s) / (steps * n) * 1e9;
}
BENCHMARK(BM_IntegratorPass)
    ->ArgNames({"threads", "tubes"})
    ->Args({1, 8})
    ->Args({1, 40})
    ->Args({1, 396})
    ->Args({2, 8})
    ->Args({2, 40})
    ->Args({2, 396})
    ->Iterations(5);

// One pair model alone on a film: one force evaluation over its own neighbour list (built for
// it, with its exclusion) per iteration. ns_per_pair is per listed pair (within cutoff + skin);
// ns_per_interacting_pair per pair within the cutoff (the others are rejected by distance).
void pair_model_evaluations(benchmark::State& state, const ForceModel& m, const Elements& el) {
  const int threads = static_cast<int>(state.range(0));
  const NeighborList nl = list_for(m, el);
  std::size_t within = 0;
  const double rc2 = m.cutoff() * m.cutoff();
  for (std::size_t i = 0; i < el.size(); ++i)
    for (std::uint32_t k = nl.offsets()[i]; k < nl.offsets()[i + 1]; ++k)
      within += (el.x[nl.neighbors()[k]] - el.x[i]).squaredNorm() < rc2;
  time_evaluations(state, m, el, &nl, threads);
  const double evals = static_cast<double>(state.iterations());
  const double n = static_cast<double>(el.size());
  state.counters["ns_per_pair"] =
      benchmark::Counter(static_cast<double>(nl.pair_count()) * evals * 1e-9,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["ns_per_interacting_pair"] =
      benchmark::Counter(static_cast<double>(within) * evals * 1e-9,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["pairs_per_element"] = static_cast<double>(nl.pair_count()) / n;
  state.counters["interacting_per_element"] = static_cast<double>(within) / n;
}

// The vdW pair model alone on issue 13's relaxed films.
void issue13_vdw(benchmark::State& state, bool dense) {
  const AnisotropicVdw vdw;
  pair_model_evaluations(state, vdw, relaxed_issue13_film(dense));
}
void BM_DenseFilmVdw(benchmark::State& state) { issue13_vdw(state, true); }
void BM_SparseFilmVdw(benchmark::State& state) { issue13_vdw(state, false); }
BENCHMARK(BM_DenseFilmVdw)->Apply(one_and_two_threads);
BENCHMARK(BM_SparseFilmVdw)->Apply(one_and_two_threads);

// The vdW kernel's batch stage alone (VdwKernel::batch: the gather of the pairs' axes and the
// SIMD lanes; no list walk, no cutoff reject, no scatter) on the relaxed dense film's first 2048
// pairs within the cutoff, in batches of 64 as the driver fills them, evaluated over and over
// (the batches and the axes they touch stay in the core's caches). ns_per_pair: per pair.
void BM_DenseFilmVdwBatch(benchmark::State& state) {
  const Elements& el = relaxed_issue13_film(true);
  const AnisotropicVdw vdw;
  const NeighborList nl = list_for(vdw, el);
  const double rc2 = vdw.cutoff() * vdw.cutoff();
  constexpr int kBatches = 32;
  std::vector<PairBatch> batches(kBatches);
  int filled = 0;
  for (std::size_t i = 0; i < el.size() && filled < kBatches; ++i)
    for (std::uint32_t m = nl.offsets()[i]; m < nl.offsets()[i + 1] && filled < kBatches; ++m) {
      const std::uint32_t j = nl.neighbors()[m];
      const Vec3 d = nl.domain().delta(el.x[i], el.x[j]);
      if (d.squaredNorm() >= rc2) continue;
      PairBatch& b = batches[filled];
      b.i[b.n] = static_cast<std::uint32_t>(i);
      b.j[b.n] = j;
      b.dx[b.n] = d.x();
      b.dy[b.n] = d.y();
      b.dz[b.n] = d.z();
      if (++b.n == PairBatch::kCapacity) ++filled;
    }
  const VdwKernel& k = vdw.kernel();
  k.begin(el);
  for (long i = 0; i < static_cast<long>(el.size()); ++i) k.prepare(el, i);
  for (auto _ : state) {
    for (PairBatch& b : batches) k.batch(el, b);
    benchmark::ClobberMemory();
  }
  state.counters["ns_per_pair"] =
      benchmark::Counter(static_cast<double>(filled) * PairBatch::kCapacity *
                             static_cast<double>(state.iterations()) * 1e-9,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(vdw_simd_target());
}
BENCHMARK(BM_DenseFilmVdwBatch);

// The neighbour phase of the relaxed dense film against the skin (skin_pm: picometres, 500 =
// the default 0.5 nm): 60 steps at 1 thread from the relaxed state, the list's rebuilds per step,
// the CPU time of one build and of one displacement check (the per-step test against skin/2),
// and the step's phase split, so neighbour + pair time per step can be read against the skin.
void BM_DenseFilmSkin(benchmark::State& state) {
  const Elements& el = relaxed_issue13_film(true);
  const double skin = static_cast<double>(state.range(0)) * 1e-3;
  const auto cpu_s = [] {
    timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
  };
  double steps = 0, builds = 0;
  StepTimers t0{}, t1{};
  double build_cpu = 0, check_cpu = 0, pairs = 0;
  for (auto _ : state) {
    System sys = issue13_system(el, true, 1, skin);
    const std::size_t b0 = sys.neighbors()->builds();
    const long s0 = sys.steps();
    t0 = sys.timers();
    sys.run(60);
    t1 = sys.timers();
    steps = static_cast<double>(sys.steps() - s0);
    builds = static_cast<double>(sys.neighbors()->builds() - b0);
    state.PauseTiming();
    NeighborList nl(sys.neighbors()->cutoff(), skin);
    const AnisotropicVdw vdw;
    nl.set_exclusion(
        [&vdw](const Elements& e, std::size_t i, std::size_t j) { return vdw.excludes(e, i, j); });
    double c = cpu_s();
    nl.build(sys.elements());
    build_cpu = cpu_s() - c;
    c = cpu_s();
    benchmark::DoNotOptimize(nl.needs_rebuild(sys.elements()));
    check_cpu = cpu_s() - c;
    pairs = static_cast<double>(nl.pair_count());
    state.ResumeTiming();
  }
  bench::add_phase_counters(state, t0, t1, steps);
  state.counters["rebuilds_per_step"] = builds / steps;
  state.counters["build_cpu_ms"] = build_cpu * 1e3;
  state.counters["check_cpu_ms"] = check_cpu * 1e3;
  state.counters["pairs_per_element"] = pairs / static_cast<double>(el.size());
}
BENCHMARK(BM_DenseFilmSkin)
    ->ArgName("skin_pm")
    ->Arg(300)
    ->Arg(500)
    ->Arg(700)
    ->Arg(1000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

// The parallel bond alone on the relaxed sparse film (its 396 × 147 bonds deformed by the
// relaxation): one force evaluation into a thread sink, the scalar reference (evaluation:0)
// against the SIMD batches (evaluation:1), interleaved in one process; ns_per_bond per bond.
void BM_SparseFilmBonds(benchmark::State& state) {
  const Elements& el = relaxed_issue13_film(false);
  const int threads = static_cast<int>(state.range(0));
  const auto bonds = make_film(issue13_film(false)).bonds;
  bonds->set_evaluation(state.range(1) ? BondEvaluation::Batched : BondEvaluation::Scalar);
  time_evaluations(state, *bonds, el, nullptr, threads);
  const double nb = static_cast<double>(bonds->bonds().size());
  state.counters["ns_per_bond"] =
      benchmark::Counter(nb * static_cast<double>(state.iterations()) * 1e-9,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["bonds"] = nb;
}
BENCHMARK(BM_SparseFilmBonds)
    ->ArgNames({"threads", "evaluation"})
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// The twist job's fixed scene: the thesis's 91-tube rope (N = 6, 50 segments, 4550 elements) with
// bonds, vdW and its dashpots, under the rigid-grip torque ramp at local damping 0.1 — the
// inner loop of the Table 4-1 runs, without the per-frame observables.
// Steps of the rope under `set` (local damping 0.1 added), 48 per iteration (a multiple of every
// respa_k benchmarked, so each timed chunk ends on an outer step).
void twist_rope_steps(benchmark::State& state, IntegratorSettings set) {
  TwistJobSpec spec;
  spec.loading.torque_max = units::nNnm(64);
  spec.loading.rate = units::nNnm(1);
  spec.loading.hold = 100;
  set.local_damping = 0.1;
  TwistJob job(spec, set);
  System& sys = job.system();
  sys.initialize();
  sys.run(48);
  bench::timed_steps(state, sys, 48);
  state.counters["pairs"] = static_cast<double>(sys.neighbors()->pair_count());
  state.counters["dt_fs"] = sys.dt() * 1e3;
  state.counters["outer_critical_fs"] = sys.critical_outer_dt() * 1e3;
}
void BM_TwistRopeSteps(benchmark::State& state) {
  IntegratorSettings set;
  set.threads = static_cast<int>(state.range(0));
  twist_rope_steps(state, set);
}
BENCHMARK(BM_TwistRopeSteps)->Apply(one_and_two_threads)->Iterations(4);

// Multiple time stepping (IntegratorSettings::respa_k) on the same rope at a fixed fine step of
// 5 fs (the vdW's own safe outer step there is ~25 fs, so k <= 4): the vdW and its dashpots once
// per k steps, bonds every step. element_steps_per_s counts inner steps.
void BM_TwistRopeRespa(benchmark::State& state) {
  IntegratorSettings set;
  set.threads = static_cast<int>(state.range(0));
  set.dt = 0.005;
  set.respa_k = static_cast<int>(state.range(1));
  twist_rope_steps(state, set);
}
BENCHMARK(BM_TwistRopeRespa)
    ->ArgNames({"threads", "respa_k"})
    ->ArgsProduct({{1}, {1, 2, 4}})
    ->Iterations(4)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// The CNT contact dashpot alone on the twist job's 91-tube rope with thermal velocities (300 K):
// one evaluation over the vdW sub-list into a sink, scalar reference (evaluation:0) against the
// batched SIMD path (evaluation:1), interleaved in one process; ns_per_pair per listed pair.
void BM_TwistRopeDashpot(benchmark::State& state) {
  static const Elements rope = [] {
    TwistJobSpec spec;
    spec.loading.torque_max = units::nNnm(64);
    spec.loading.rate = units::nNnm(1);
    spec.temperature_k = 300;
    TwistJob job(spec, IntegratorSettings{});
    return job.system().elements();
  }();
  const int threads = static_cast<int>(state.range(0));
  const auto eval = state.range(1) ? DashpotEvaluation::Batched : DashpotEvaluation::Scalar;
  const ViscousContactDamping model(ContactDampingParams{}, eval);
  const ForceModel& dashpot = model;  // through the virtual call, as System runs it
  const NeighborList nl = list_for(dashpot, rope);
  time_evaluations(state, dashpot, rope, &nl, threads);
  state.counters["ns_per_pair"] = benchmark::Counter(
      static_cast<double>(nl.pair_count()) * static_cast<double>(state.iterations()) * 1e-9,
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["pairs"] = static_cast<double>(nl.pair_count());
}
BENCHMARK(BM_TwistRopeDashpot)
    ->ArgNames({"threads", "evaluation"})
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->UseRealTime()
    ->Unit(benchmark::kMicrosecond);

// The tensile job's medium film (tensile.md §3.1, Table 5-1: 350 tubes × 350 segments = 122 500
// segments in 500 × 500 × 11 nm, ≤ 2° out of plane; nps:1 adds 4000 Si nanoparticles by
// np_placement) in the job's own system (tensile_film_system: bonds, vdW, NP contacts and all
// dashpots at ψ = 0.03, auto step, no local damping: the relax stage's settings), full steps on 1
// and 2 threads. state:0 ready to relax (as generated), state:1 briefly pre-relaxed (100 steps at
// the pre-relaxation's local damping 0.7, velocities then zeroed). The film gains pairs as it
// relaxes: ~19 listed pairs per segment ready to relax, ~27 once relaxed (pairs_per_element
// reports this run's), so the relaxed rate is below the ready-to-relax one.
const Elements& tensile_film(FilmSize size, bool nps, bool prerelaxed) {
  auto make = [](FilmSize sz, bool with_nps, bool relax) {
    TensileFilmSpec spec = TensileFilmSpec::of_size(sz);
    spec.seed = 13;
    spec.nanoparticles = with_nps ? 4000 : 0;
    Elements el;
    add_tensile_film(el, spec);
    if (!relax) return el;
    IntegratorSettings set;
    set.local_damping = 0.7;
    auto sys = tensile_film_system(std::move(el), set, 0.03);
    sys->run(100);
    Elements out = sys->elements();
    for (std::size_t i = 0; i < out.size(); ++i) {
      out.v[i].setZero();
      out.w[i].setZero();
    }
    return out;
  };
  static std::map<std::tuple<FilmSize, bool, bool>, Elements> cache;
  auto it = cache.find({size, nps, prerelaxed});
  if (it == cache.end())
    it = cache.emplace(std::tuple{size, nps, prerelaxed}, make(size, nps, prerelaxed)).first;
  return it->second;
}

// Full steps of a tensile film (the job's relax-stage system) on state.range(0) threads.
void tensile_film_steps(benchmark::State& state, FilmSize size, bool nps, bool prerelaxed) {
  Elements el = tensile_film(size, nps, prerelaxed);
  // The bonds' rest state is the generated film's: bonds made on it, reused on the relaxed one.
  Elements generated;
  TensileFilmSpec spec = TensileFilmSpec::of_size(size);
  spec.seed = 13;
  spec.nanoparticles = nps ? 4000 : 0;
  add_tensile_film(generated, spec);
  const auto rest = ParallelBond::from_topology(generated, BondType::Cnt, cnt_bond_stiffness());
  IntegratorSettings set;
  set.threads = static_cast<int>(state.range(0));
  auto sys = tensile_film_system(std::move(el), set, 0.03, rest.get());
  sys->run(5);  // warm-up
  const long steps0 = sys->steps();
  const StepTimers t0 = sys->timers();
  for (auto _ : state) sys->run(5);
  const double steps = static_cast<double>(sys->steps() - steps0);
  const double n = static_cast<double>(sys->elements().size());
  state.counters["element_steps_per_s"] =
      benchmark::Counter(n * steps, benchmark::Counter::kIsRate);
  bench::add_phase_counters(state, t0, sys->timers(), steps);
  state.counters["elements"] = n;
  state.counters["dt_fs"] = sys->dt() * 1e3;
  state.counters["pairs_per_element"] = static_cast<double>(sys->neighbors()->pair_count()) / n;
}

void BM_TensileMediumFilm(benchmark::State& state) {
  tensile_film_steps(state, FilmSize::Medium, state.range(1) != 0, state.range(2) != 0);
}
BENCHMARK(BM_TensileMediumFilm)
    ->ArgNames({"threads", "nps", "state"})
    ->ArgsProduct({{1, 2}, {0, 1}, {0, 1}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);

// Table 5-1's small film (200 tubes × 200 segments = 40 000 segments in 300 × 300 × 11 nm, seed
// 13, no NPs), pre-relaxed as state:1 above, in the same system: the tensile film of issue 13's
// threads target (2t/1t ≥ 1.85) at a size that relaxes in seconds. 20 steps per measurement.
void BM_TensileSmallFilm(benchmark::State& state) {
  tensile_film_steps(state, FilmSize::Small, false, true);
}
BENCHMARK(BM_TensileSmallFilm)->Apply(one_and_two_threads)->Iterations(4);

// The NP–CNT contact alone on Table 5-1's medium film with 4000 NPs (pre-relaxed as state:1
// above), over its own list: evaluation:0 the scalar law, evaluation:1 the batched one (SIMD,
// the default), in one run so the two compare on one machine state.
void BM_TensileFilmNpCnt(benchmark::State& state) {
  const NpCntContact np_cnt(
      NpCntParams{}, state.range(1) != 0 ? NpCntEvaluation::Batched : NpCntEvaluation::Scalar);
  pair_model_evaluations(state, np_cnt, tensile_film(FilmSize::Medium, true, true));
}
BENCHMARK(BM_TensileFilmNpCnt)
    ->ArgNames({"threads", "evaluation"})
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->UseRealTime();

// Memory order (issue 13 item 3): full steps of issue 13's films as generated, their elements in
// the generator's order (tube after tube, segments in order along each; the tubes themselves lie
// at random places, so tube order is already spatially random) or shuffled element by element
// (scrambled:1, a scene built in no spatial order at all), with the elements kept as built
// (order:0) or reordered along a Morton curve at neighbour-list rebuilds (order:1, the first build
// and every memory_order_every-th). As generated (overlapping tubes, auto step ~5 fs) under the
// pre-relaxation's local damping 0.7, so no 500-step relaxation is needed first: short enough for
// callgrind (`--collect-atstart=no --toggle-collect='mdem::System::run(long)'`).
void BM_MemoryOrderFilmSteps(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const bool dense = state.range(1) != 0, scrambled = state.range(2) != 0;
  const auto order = state.range(3) ? MemoryOrder::Morton : MemoryOrder::AsBuilt;
  Elements el;
  add_random_film(el, issue13_film(dense));
  if (scrambled) {
    std::vector<std::uint32_t> p(el.size());
    std::iota(p.begin(), p.end(), 0u);
    std::mt19937_64 rng(5);
    std::shuffle(p.begin(), p.end(), rng);
    el.reorder(p);
  }
  IntegratorSettings set;
  set.threads = threads;
  set.local_damping = 0.7;
  set.memory_order = order;
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  System sys(std::move(el), set);
  sys.add(std::move(bonds));
  sys.add(std::make_unique<AnisotropicVdw>());
  sys.initialize();
  sys.run(5);  // warm-up: buffers sized, the first reorder done
  const std::size_t builds0 = sys.neighbors()->builds(), reorders0 = sys.reorders();
  const StepTimers t0 = sys.timers();
  const double steps = bench::timed_steps(state, sys, 10);
  const double n = static_cast<double>(sys.elements().size());
  bench::add_phase_counters(state, t0, sys.timers(), steps);
  state.counters["rebuilds_per_step"] =
      static_cast<double>(sys.neighbors()->builds() - builds0) / steps;
  state.counters["reorders_per_step"] = static_cast<double>(sys.reorders() - reorders0) / steps;
  state.counters["pairs_per_element"] = static_cast<double>(sys.neighbors()->pair_count()) / n;
  state.counters["dt_fs"] = sys.dt() * 1e3;
}
BENCHMARK(BM_MemoryOrderFilmSteps)
    ->ArgNames({"threads", "dense", "scrambled", "order"})
    ->ArgsProduct({{1, 2}, {1, 0}, {0, 1}, {0, 1}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

// The neighbour-list build alone on the (unrelaxed) film, with the vdW model's exclusion.
void BM_FilmNeighborBuild(benchmark::State& state) {
  const int saved = omp_get_max_threads();
  omp_set_num_threads(static_cast<int>(state.range(0)));
  const Scene s = film_scene();
  const AnisotropicVdw vdw;
  NeighborList nl(vdw.cutoff(), IntegratorSettings{}.skin);
  nl.set_exclusion(
      [&vdw](const Elements& el, std::size_t i, std::size_t j) { return vdw.excludes(el, i, j); });
  nl.build(s.el);  // warm-up
  for (auto _ : state) {
    nl.build(s.el);
    benchmark::DoNotOptimize(nl.neighbors().data());
  }
  state.counters["elements"] = static_cast<double>(s.el.size());
  state.counters["pairs"] = static_cast<double>(nl.pair_count());
  state.counters["elements_per_s"] = benchmark::Counter(
      static_cast<double>(s.el.size() * state.iterations()), benchmark::Counter::kIsRate);
  omp_set_num_threads(saved);
}
BENCHMARK(BM_FilmNeighborBuild)->Apply(one_and_two_threads);

// 2 threads over 1 on the dense film, as built and in slabs (issue 13 item 4), measured in one
// process (bench::thread_windows): windows of 40 steps, 12 cycles per iteration.
void BM_DenseFilmThreadWindows(benchmark::State& state) {
  const Elements& el = relaxed_issue13_film(true);
  const double skin = IntegratorSettings{}.skin;
  System one = issue13_system(el, true, 1, skin, MemoryOrder::AsBuilt);
  System two = issue13_system(el, true, 2, skin, MemoryOrder::AsBuilt);
  System slabs = issue13_system(el, true, 2, skin, MemoryOrder::Slabs);
  for (System* s : {&one, &two, &slabs}) s->run(10);  // warm-up
  bench::thread_windows(state, one, two, slabs, 40, 12);
}
BENCHMARK(BM_DenseFilmThreadWindows)->Iterations(2)->UseRealTime()->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();
