// Engine throughput: element-steps per second of full velocity-Verlet steps (parallel bonds +
// anisotropic vdW + neighbour list) on a seven-tube bundle and on a random in-plane film, each on
// 1 and 2 threads, and the neighbour-list build alone on the film.
//
// Rates are per wall-clock second (UseRealTime), the figure that matters for threaded runs.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdio>
#include <memory>

#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/integrate/system.h"
#include "mdem/job/twist_job.h"
#include "mdem/neighbor/neighbor_list.h"
#include "mdem/scene/film_builder.h"

using namespace mdem;

namespace {

struct Scene {
  Elements el;
  std::unique_ptr<ParallelBond> bonds = std::make_unique<ParallelBond>();
};

// (a) Seven 100-segment tubes, 1.7 nm apart (about the vdW equilibrium spacing): 700 segments.
Scene bundle_scene() {
  Scene s;
  add_seven_tube_bundle(s.el, s.bonds.get(), 100, 1.7);
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

Scene film_scene() {
  Scene s;
  add_random_film(s.el, s.bonds.get(), film_spec());
  return s;
}

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
  const long steps0 = sys.steps();
  for (auto _ : state) sys.run(steps_per_iteration);
  const double steps = static_cast<double>(sys.steps() - steps0);
  const double n = static_cast<double>(sys.elements().size());
  state.counters["element_steps_per_s"] =
      benchmark::Counter(n * steps, benchmark::Counter::kIsRate);
  state.counters["steps_per_s"] = benchmark::Counter(steps, benchmark::Counter::kIsRate);
  state.counters["elements"] = n;
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
BENCHMARK(BM_BundleSteps)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_FilmSteps(benchmark::State& state) { run_steps(state, relaxed_film(), film_bonds(), 10); }
BENCHMARK(BM_FilmSteps)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Iterations(4)  // 40 steps: several neighbour-list rebuilds per measurement
    ->Unit(benchmark::kMillisecond);

// The twist job's fixed scene: the thesis's 91-tube rope (N = 6, 50 segments, 4550 elements) with
// bonds, vdW and its dashpots, under the rigid-grip torque ramp at local damping 0.1 — the
// inner loop of the Table 4-1 runs, without the per-frame observables.
void BM_TwistRopeSteps(benchmark::State& state) {
  TwistJobSpec spec;
  spec.loading.torque_max = units::nNnm(64);
  spec.loading.rate = units::nNnm(1);
  spec.loading.hold = 100;
  IntegratorSettings set;
  set.threads = static_cast<int>(state.range(0));
  set.local_damping = 0.1;
  TwistJob job(spec, set);
  System& sys = job.system();
  sys.initialize();
  sys.run(50);
  const long steps0 = sys.steps();
  for (auto _ : state) sys.run(50);
  const double steps = static_cast<double>(sys.steps() - steps0);
  const double n = static_cast<double>(sys.elements().size());
  state.counters["element_steps_per_s"] =
      benchmark::Counter(n * steps, benchmark::Counter::kIsRate);
  state.counters["elements"] = n;
  state.counters["pairs"] = static_cast<double>(sys.neighbors()->pair_count());
  state.counters["dt_fs"] = sys.dt() * 1e3;
}
BENCHMARK(BM_TwistRopeSteps)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Iterations(4)
    ->Unit(benchmark::kMillisecond);

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
BENCHMARK(BM_FilmNeighborBuild)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
