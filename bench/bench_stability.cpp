// The stability suite's expensive cases (docs/stability.md, issue 15 item 5): jobs of 10^5-10^6
// elements, run a few steps, with the memory they take. Each entry reports its element count,
// the resident memory the scene and its system added (MB and bytes per element), the listed
// pairs, the step, whether the state stayed finite (1/0), or the run guard's stop (the entry
// is then marked with SkipWithError carrying the message).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>

#include "mdem/core/cnt.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/job/tensile_job.h"
#include "mdem/job/twist_job.h"
#include "mdem/scene/film_builder.h"

namespace {

using namespace mdem;

// Resident memory of this process now (bytes), from /proc/self/statm.
double resident_bytes() {
  std::ifstream in("/proc/self/statm");
  long pages = 0, resident = 0;
  in >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE));
}

bool state_finite(const Elements& el) {
  for (std::size_t i = 0; i < el.size(); ++i)
    if (!el.x[i].allFinite() || !el.v[i].allFinite() || !el.w[i].allFinite()) return false;
  return true;
}

// Runs `steps` steps per iteration and reports the counters; rss0: resident memory before the
// scene was built.
void run_and_report(benchmark::State& state, System& sys, double rss0, long steps) {
  try {
    sys.initialize();
    const double rss = resident_bytes() - rss0;
    const double n = static_cast<double>(sys.elements().size());
    for (auto _ : state) sys.run(steps);
    state.counters["elements"] = n;
    state.counters["memory_MB"] = rss / 1e6;
    state.counters["bytes_per_element"] = rss / n;
    state.counters["peak_memory_MB"] = (resident_bytes() - rss0) / 1e6;
    state.counters["pairs"] =
        sys.neighbors() ? static_cast<double>(sys.neighbors()->pair_count()) : 0.0;
    state.counters["dt_fs"] = sys.dt() * 1e3;
    state.counters["finite"] = state_finite(sys.elements()) ? 1 : 0;
    state.counters["balance_error"] = sys.energy_balance_error();
    state.counters["element_steps_per_s"] = benchmark::Counter(
        n * static_cast<double>(steps), benchmark::Counter::kIsIterationInvariantRate);
  } catch (const NumericalError& e) {
    state.SkipWithError(e.what());
  }
}

// A random film of 10^4 tubes x 100 segments = 10^6 segments at the areal density of the
// thesis's medium film (0.49 segments/nm²: 1429 nm square, 11 nm thick), as generated: tubes
// cross and overlap (no pre-relaxation), with the twist job's models (bonds, vdW, dashpots),
// undamped otherwise.
void BM_MillionSegmentFilm(benchmark::State& state) {
  const double rss0 = resident_bytes();
  Elements el;
  FilmSpec f;
  f.side = 1429;
  f.thickness = 11;
  f.tubes = 10000;
  f.segments_per_tube = 100;
  f.seed = 2024;
  add_random_film(el, f);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  IntegratorSettings set;
  set.threads = static_cast<int>(state.range(0));
  System sys(std::move(el), set);
  sys.add(std::move(bonds));
  sys.add(std::make_unique<AnisotropicVdw>());
  sys.add(std::make_unique<ViscousContactDamping>(ContactDampingParams{}));
  run_and_report(state, sys, rss0, 10);
}
BENCHMARK(BM_MillionSegmentFilm)->Arg(0)->Iterations(1)->Unit(benchmark::kSecond);

// The largest twist job the spec allows: 10 layers (271 tubes) of 2000 nm (1475 segments) =
// 399 725 elements, built by the CLI's TwistJob.
void BM_LargestTwistJob(benchmark::State& state) {
  const double rss0 = resident_bytes();
  TwistJobSpec spec;
  spec.rope.layers = 10;
  spec.rope.segments = 1475;
  spec.loading.torque_max = units::nNnm(64);
  spec.loading.rate = units::nNnm(1);
  spec.loading.hold = 100;
  IntegratorSettings set;
  set.threads = static_cast<int>(state.range(0));
  set.local_damping = 0.1;
  TwistJob job(spec, set);
  run_and_report(state, job.system(), rss0, 10);
}
BENCHMARK(BM_LargestTwistJob)->Arg(0)->Iterations(1)->Unit(benchmark::kSecond);

// 300 % strain (docs/stability.md): `mdem run tensile --side 40 --tubes 30 --segments 20
// --prerelax 5 --relax 0 --ramp 10 --rate 0.01 --strain 300 --threads 1` (600 segments, the
// spec's largest strain at its largest rate). The model's bonds never break, so pieces held by
// both grips are drawn out until a bond's load stiffens its rotation past the step: the run stops
// (at about 127 % strain at safety 0.6, 269 % at 0.3) with the tensile protocol's explanation.
// Counters: stopped (1/0), the simulated time and step reached, explained (1: the stop message
// names the drawn-out bond). Too slow for ctest (tens of seconds on a loaded machine).
void BM_TensileThreeHundredPercent(benchmark::State& state) {
  TensileJobSpec spec;
  spec.film.side = 40;
  spec.film.tubes = 30;
  spec.film.segments_per_tube = 20;
  spec.film.seed = spec.seed = 1;
  spec.prerelax.max_time = 5;
  spec.relax_ps = 0;
  spec.monotonic = {0.01, 10, 3.0};
  spec.relax_report_ps = {0};
  spec.test_report_strains = {0, 0.02, 0.1, 0.2};
  IntegratorSettings set;
  set.threads = 1;
  set.safety = static_cast<double>(state.range(0)) / 10.0;
  for (auto _ : state) {
    TensileJob job(spec, set);
    bool stopped = false, explained = false;
    try {
      run_job(job, JobCadence{}, JobObserver{});
    } catch (const NumericalError& e) {
      stopped = true;
      explained = std::string(e.what()).find("bonds never break") != std::string::npos;
      std::fprintf(stderr, "safety %.1f: %s\n", set.safety, e.what());
    }
    state.counters["stopped"] = stopped ? 1 : 0;
    state.counters["explained"] = explained ? 1 : 0;
    state.counters["t_ps"] = job.system().time();
    state.counters["steps"] = static_cast<double>(job.system().steps());
    state.counters["dt_fs"] = job.system().dt() * 1e3;
  }
}
BENCHMARK(BM_TensileThreeHundredPercent)->Arg(6)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();
