// The relaxed medium film's speed (issue 14: "a benchmark line for the relaxed medium film,
// element-steps/s on 1 and 2 threads"): Table 5-1's medium film (350 tubes × 350 segments =
// 122 500 segments in 500 × 500 × 11 nm, seed 13; nps:1 adds 4000 Si NPs) stepped in the tensile
// job's relax-stage system (tensile_film_system: bonds with the generated film's rest state, vdW,
// NP contacts, dashpots at ψ = 0.03, no local damping, auto step) on 1 and 2 threads.
//
// A relaxed film takes hours to make here, so it is made once, by this program's preparation
// mode, and kept in a state file (the engine's state I/O: header, then the film's positions,
// orientations and velocities):
//
//   bench_tensile_film --prepare DIR [--nps 0|4000] [--prerelax-ps P] [--relax-ps R] [--threads N]
//
// pre-relaxes the generated film for P ps (local damping 0.7, the job's pre-relaxation; default
// 20), zeroes its motion and relaxes it for R ps (default 100) at a step picked anew, then writes
// DIR/medium_seed13_nps<N>.state. The benchmark reads MDEM_TENSILE_FILM_DIR (default: the
// working directory); without a state file it says so and steps the film as generated
// (relaxed_ps 0 in its counters). 80 steps are timed (4 × 20: at most a rebuild or two of the
// neighbour lists, which come every 50-80 steps on the relaxed film); MDEM_TENSILE_FILM_STEPS=S
// times 4 × S steps instead (1..100000; e.g. 250, so the neighbour phase holds the rebuilds a
// long run has). MDEM_TENSILE_FILM_SAFETY=s steps at s × the critical step (default 0.6, the
// jobs' default; (0, 1]) and balance_error reports the energy balance over the run.
// order:N runs the system in memory order N (IntegratorSettings::memory_order: 0 as built, 1
// Morton, 2 one slab per thread, as the tensile job's relaxation; reordered at the first list build
// and every 10th rebuild). Counters: element_steps_per_s, the step's phases (pair_ms, neighbor_ms,
// integrate_ms), the neighbour sub-lists' builds per step (builds_per_step, all sub-lists
// together), the pair phase per listed vdW pair (pair_ns_per_listed_pair), the half pairs per
// segment within the vdW cutoff (4T = 5.424 nm; tensile.md §4.1: medium 14.8 ready-to-relax, ≈ 22
// relaxed), the listed pairs per element, and the relaxation the state file had (relaxed_ps).
// BM_ClusterPairFill measures what a cluster-pair list would evaluate on the same film (below);
// BM_AlignedPairCount times the tensile job's per-frame aligned-pair count (below).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bench_support.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/integrate/spectrum.h"
#include "mdem/io/state_io.h"
#include "mdem/job/prerelax_criterion.h"
#include "mdem/job/tensile_job.h"
#include "mdem/observe/aligned_pairs.h"
#include "mdem/protocol/tensile_protocol.h"
#include "mdem/scene/tensile_film.h"

using namespace mdem;

namespace {

constexpr std::uint64_t kSeed = 13;
constexpr int kNps = 4000;
constexpr double kPrerelaxDamping = 0.7;  // the job's pre-relaxation (TensileJobSpec default)
constexpr double kDashpot = 0.03;         // ψ, the relax stage's

Elements generated_film(int nps) {
  TensileFilmSpec spec = TensileFilmSpec::of_size(FilmSize::Medium);
  spec.seed = kSeed;
  spec.nanoparticles = nps;
  Elements el;
  add_tensile_film(el, spec);
  return el;
}

std::string state_path(const std::string& dir, int nps) {
  return dir + "/medium_seed" + std::to_string(kSeed) + "_nps" + std::to_string(nps) + ".state";
}

// What a state file holds besides the film: how it was made.
struct FilmState {
  Elements el;
  double prerelax_ps = 0, relax_ps = 0;
};

void write_state(const std::string& path, const Elements& el, int nps, double prerelax_ps,
                 double relax_ps) {
  StateWriter w;
  write_header(w);
  w.begin("tensile medium film");
  w.put(kSeed);
  w.put(static_cast<std::int64_t>(nps));
  w.put(prerelax_ps);
  w.put(relax_ps);
  w.put(el.tag);
  w.put(el.x);
  w.put(el.q);
  w.put(el.v);
  w.put(el.w);
  std::ofstream f(path, std::ios::binary);
  f << w.bytes();
  if (!f) throw std::runtime_error("cannot write " + path);
}

// The generated film with the state file's positions, orientations and velocities; nullopt
// when the file does not exist. Throws CheckpointError for a file of another film.
std::optional<FilmState> read_state(const std::string& path, int nps) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return std::nullopt;
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string bytes = ss.str();
  StateReader r(bytes);
  read_header(r);
  r.begin("tensile medium film");
  if (r.get<std::uint64_t>("seed") != kSeed) r.fail("seed", "not this benchmark's film");
  if (r.get<std::int64_t>("nanoparticles") != nps) r.fail("nanoparticles", "another NP count");
  FilmState s;
  s.el = generated_film(nps);
  s.prerelax_ps = r.get<double>("prerelax ps");
  s.relax_ps = r.get<double>("relax ps");
  const std::size_t n = s.el.size();
  std::vector<std::uint64_t> tag;
  r.get(tag, "tags", n);
  if (tag != s.el.tag) r.fail("tags", "not the generated film's elements in its order");
  r.get(s.el.x, "x", n);
  r.get(s.el.q, "q", n);
  r.get(s.el.v, "v", n);
  r.get(s.el.w, "w", n);
  return s;
}

std::unique_ptr<ParallelBond> rest_bonds(const Elements& generated) {
  return ParallelBond::from_topology(generated, BondType::Cnt, cnt_bond_stiffness());
}

// The pre-relaxation (damped, fixed length) and the relaxation of the generated film, written
// to DIR. Prints its progress: a medium film step takes about a quarter of a second.
int prepare(const std::string& dir, int nps, double prerelax_ps, double relax_ps, int threads) {
  const Elements generated = generated_film(nps);
  const auto rest = rest_bonds(generated);
  IntegratorSettings pre;
  pre.local_damping = kPrerelaxDamping;
  pre.threads = threads;
  auto sys = tensile_film_system(generated, pre, kDashpot, rest.get());
  sys->initialize();
  std::printf("prepare: %zu elements, pre-relaxation %g ps at dt %g fs\n", generated.size(),
              prerelax_ps, sys->dt() * 1e3);
  std::fflush(stdout);
  while (sys->time() < prerelax_ps) sys->run(10);
  Elements el = sys->elements();
  zero_motion(el);
  IntegratorSettings relax;
  relax.threads = threads;
  sys = tensile_film_system(std::move(el), relax, kDashpot, rest.get());
  sys->initialize();
  std::printf("prepare: relaxation %g ps at dt %g fs\n", relax_ps, sys->dt() * 1e3);
  std::fflush(stdout);
  while (sys->time() < relax_ps) {
    sys->run(10);
    std::printf("  t = %.1f ps\n", sys->time());
    std::fflush(stdout);
  }
  const std::string path = state_path(dir, nps);
  write_state(path, sys->elements(), nps, prerelax_ps, sys->time());
  std::printf("prepare: wrote %s (relaxed %g ps)\n", path.c_str(), sys->time());
  return 0;
}

// Half pairs per CNT segment within the vdW cutoff, from the system's vdW list.
double pairs_per_segment(const System& sys) {
  const auto* vdw = sys.find<AnisotropicVdw>();
  const NeighborList* list = sys.neighbors(*vdw);
  const Elements& el = sys.elements();
  const double c2 = vdw->cutoff() * vdw->cutoff();
  long pairs = 0, segments = 0;
  for (std::size_t i = 0; i < el.size(); ++i) {
    segments += el.kind[i] == ElementKind::CntSegment;
    for (std::uint32_t k = list->offsets()[i]; k < list->offsets()[i + 1]; ++k)
      pairs += (el.x[list->neighbors()[k]] - el.x[i]).squaredNorm() < c2;
  }
  return static_cast<double>(pairs) / static_cast<double>(segments);
}

const FilmState& film(int nps) {
  static std::map<int, FilmState> cache;
  auto it = cache.find(nps);
  if (it != cache.end()) return it->second;
  const char* env = std::getenv("MDEM_TENSILE_FILM_DIR");
  const std::string path = state_path(env ? env : ".", nps);
  std::optional<FilmState> s = read_state(path, nps);
  if (s) {
    std::fprintf(stderr, "bench_tensile_film: %s: pre-relaxed %g ps, relaxed %g ps\n", path.c_str(),
                 s->prerelax_ps, s->relax_ps);
  } else {
    std::fprintf(stderr,
                 "bench_tensile_film: no state file %s: stepping the film as generated (not "
                 "relaxed; make one with --prepare)\n",
                 path.c_str());
    s = FilmState{generated_film(nps), 0, 0};
  }
  return cache.emplace(nps, std::move(*s)).first->second;
}

// Steps per timed iteration: MDEM_TENSILE_FILM_STEPS, default 20; 0 (and a message) when the
// variable is not a whole number in 1..100000.
long steps_per_iteration(std::string& error) {
  const char* v = std::getenv("MDEM_TENSILE_FILM_STEPS");
  if (!v) return 20;
  char* end = nullptr;
  errno = 0;
  const long s = std::strtol(v, &end, 10);
  if (end == v || *end != '\0' || errno != 0 || s < 1 || s > 100000) {
    error = std::string("MDEM_TENSILE_FILM_STEPS='") + v +
            "': give the steps per timed iteration, a whole number from 1 to 100000";
    return 0;
  }
  return s;
}

// The auto step's fraction of the critical step: MDEM_TENSILE_FILM_SAFETY, default 0.6 (the
// jobs' default, IntegratorSettings::safety); 0 (and a message) when the variable is not a
// number in (0, 1], the range `mdem run tensile --safety` takes.
double safety_factor(std::string& error) {
  const char* v = std::getenv("MDEM_TENSILE_FILM_SAFETY");
  if (!v) return IntegratorSettings{}.safety;
  char* end = nullptr;
  errno = 0;
  const double s = std::strtod(v, &end);
  if (end == v || *end != '\0' || errno != 0 || !(s > 0.0 && s <= 1.0)) {
    error = std::string("MDEM_TENSILE_FILM_SAFETY='") + v +
            "': give the fraction of the critical step, a number in (0, 1]";
    return 0;
  }
  return s;
}

// A benchmark's film: the state of its `nps` argument (range 1: 0 or 1 for the 4000 NPs), the
// generated film's rest bonds, and settings for `threads` (range 0) at the safety factor.
struct FilmCase {
  const FilmState& film;
  std::unique_ptr<ParallelBond> rest;
  IntegratorSettings set;
};
FilmCase film_case(const benchmark::State& state, double safety) {
  const int nps = state.range(1) != 0 ? kNps : 0;
  FilmCase c{film(nps), rest_bonds(generated_film(nps)), {}};
  c.set.threads = static_cast<int>(state.range(0));
  c.set.safety = safety;
  return c;
}

// The stepping benchmarks' settings from the environment: steps per timed iteration and the
// safety factor; false, the benchmark skipped with the message, when either is not allowed.
bool stepping_settings(benchmark::State& state, long& per_iteration, double& safety) {
  std::string error;
  per_iteration = steps_per_iteration(error);
  safety = error.empty() ? safety_factor(error) : 0.0;
  if (!error.empty()) state.SkipWithError(error.c_str());
  return error.empty();
}

void BM_RelaxedMediumFilm(benchmark::State& state) {
  long per_iteration = 0;
  double safety = 0;
  if (!stepping_settings(state, per_iteration, safety)) return;
  auto [f, rest, set] = film_case(state, safety);
  set.memory_order = static_cast<MemoryOrder>(state.range(2));
  auto sys = tensile_film_system(f.el, set, kDashpot, rest.get());
  sys->run(5);  // warm-up
  const StepTimers t0 = sys->timers();
  const double b0 = bench::list_builds(*sys);
  const double steps = bench::timed_steps(state, *sys, per_iteration);
  bench::add_phase_counters(state, t0, sys->timers(), steps);
  // Sub-list builds (all kind pairs together) per timed step: the neighbour phase is these
  // builds plus one displacement check per sub-list and step.
  state.counters["builds_per_step"] = (bench::list_builds(*sys) - b0) / steps;
  state.counters["sub_lists"] = static_cast<double>(sys->pair_table().entries().size());
  const double n = static_cast<double>(sys->elements().size());
  state.counters["dt_fs"] = sys->dt() * 1e3;
  // The energy balance's error over the warm-up and every timed step (a run that a larger
  // safety factor makes unstable shows here, or stops on the engine's guard).
  state.counters["balance_error"] = sys->energy_balance_error();
  state.counters["relaxed_ps"] = f.relax_ps;
  state.counters["half_pairs_per_segment"] = pairs_per_segment(*sys);
  const double listed =
      static_cast<double>(sys->neighbors(*sys->find<AnisotropicVdw>())->pair_count());
  state.counters["listed_pairs_per_element"] = listed / n;
  // The pair phase (bonds, vdW and its dashpots, NP contacts) per listed vdW pair, which
  // dominate it.
  state.counters["pair_ns_per_listed_pair"] = state.counters["pair_ms"] * 1e6 / listed;
}
BENCHMARK(BM_RelaxedMediumFilm)
    ->ArgNames({"threads", "nps", "order"})
    ->ArgsProduct({{1, 2}, {0, 1}, {0, 1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(4);

// The tensile test's step on the relaxed film: BM_RelaxedMediumFilm's system with the grips of
// tensile.md §3.5 (15 nm from each end, the job's select_grips) and the monotonic grip protocol
// (TensileProtocol, the job's loading of the medium film) as its updater, as the job's "tensile"
// stage runs it (without its observers, which sample every few ps). Counters as
// BM_RelaxedMediumFilm's, with updaters_ms (the protocol's share of a step) and grip_elements.
void BM_TensileTestMediumFilm(benchmark::State& state) {
  long per_iteration = 0;
  double safety = 0;
  if (!stepping_settings(state, per_iteration, safety)) return;
  auto [f, rest, set] = film_case(state, safety);
  set.memory_order = static_cast<MemoryOrder>(state.range(2));
  Elements el = f.el;
  const GripSelection grips = select_grips(el);
  auto sys = tensile_film_system(std::move(el), set, kDashpot, rest.get());
  TensileLoading loading;
  loading.length = TensileFilmSpec::of_size(FilmSize::Medium).side;
  sys->add_updater(std::make_shared<TensileProtocol>(loading));
  sys->run(5);  // warm-up
  const StepTimers t0 = sys->timers();
  const double steps = bench::timed_steps(state, *sys, per_iteration);
  bench::add_phase_counters(state, t0, sys->timers(), steps);
  state.counters["grip_elements"] = static_cast<double>(grips.left.size() + grips.right.size());
  state.counters["dt_fs"] = sys->dt() * 1e3;
  state.counters["balance_error"] = sys->energy_balance_error();
}
BENCHMARK(BM_TensileTestMediumFilm)
    ->ArgNames({"threads", "nps", "order"})
    ->ArgsProduct({{1, 2}, {0, 1}, {0, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(4);

// 2 threads over 1 on the relaxed film (issue 13 item 4), as built and in slabs, in one process
// (bench::thread_windows): BM_RelaxedMediumFilm's system on 1 thread as built, on 2 as built and
// on 2 in MemoryOrder::Slabs (the tensile job's relaxation runs so), windows of 10 steps, 8 cycles
// per iteration.
void BM_RelaxedMediumFilmThreadWindows(benchmark::State& state) {
  long per_iteration = 0;  // (the windows' own length is fixed)
  double safety = 0;
  if (!stepping_settings(state, per_iteration, safety)) return;
  const auto [f, rest, base] = film_case(state, safety);
  std::vector<std::unique_ptr<System>> sys;
  for (auto [threads, order] :
       {std::pair{1, MemoryOrder::AsBuilt}, {2, MemoryOrder::AsBuilt}, {2, MemoryOrder::Slabs}}) {
    IntegratorSettings set = base;
    set.threads = threads;
    set.memory_order = order;
    sys.push_back(tensile_film_system(f.el, set, kDashpot, rest.get()));
    sys.back()->run(5);  // warm-up
  }
  bench::thread_windows(state, *sys[0], *sys[1], *sys[2], 10, 8);
}
BENCHMARK(BM_RelaxedMediumFilmThreadWindows)
    ->ArgNames({"threads", "nps"})
    ->Args({2, 0})
    ->Args({2, 1})
    ->UseRealTime()
    ->Unit(benchmark::kSecond)
    ->Iterations(2);

// How far the automatic step's critical step (a Gershgorin bound over each element's summed
// stiffness bounds, System::compute_critical_dt) is below the relaxed film's true one, 2/ω_max
// from Lanczos over differenced forces (integrate/spectrum.h; undamped), and what stands in the
// way of a true one. Counters (dt in fs):
// - gershgorin_dt_fs: with the relax stage's dashpots, as the job picks it; gershgorin_undamped_fs:
//   the same system without them (the rest of the counters are of that system);
// - spectral_dt_fs, 2/ω_max with differences of 1e-4 nm (the largest move of any element's point),
//   spectral_fine_dt_fs with 1e-5 nm, smooth (1 when the two agree); spectral_over_gershgorin and
//   auto_over_spectral (the automatic step at MDEM_TENSILE_FILM_SAFETY, default 0.6, over
//   spectral_dt_fs); seeds_spread, the relative difference of ω_max from a second random start;
// - knee_pairs_1e-6 ... knee_pairs_1e-2: crossed vdW pairs (|b1·b2| < 0.9999) whose centre
//   distance is within 1e-6 ... 1e-2 nm of W's knee 2.75 r, where model.md §4's M(R, γ) has a
//   kink and the pair force jumps (smoothly distributed distances would give counts in the ratio
//   of the windows, 10 per decade);
// - kinked_elements: elements whose force derivative along a random displacement differs by more
//   than 1 % between differences of 1e-5 and 1e-6 nm.
// One iteration: the time is the estimates'.
void BM_RelaxedMediumFilmCriticalStep(benchmark::State& state) {
  std::string error;
  const double safety = safety_factor(error);
  if (!error.empty()) {
    state.SkipWithError(error.c_str());
    return;
  }
  const auto [f, rest, set] = film_case(state, safety);
  auto damped = tensile_film_system(f.el, set, kDashpot, rest.get());
  damped->initialize();
  const double gershgorin = damped->critical_dt();
  const double auto_dt = damped->dt();
  damped.reset();
  auto sys = tensile_film_system(f.el, set, 0.0, rest.get());
  sys->initialize();
  SpectrumSettings s1;
  s1.displacement = 1e-4;
  s1.tolerance = 1e-6;
  s1.max_iterations = 300;
  SpectrumSettings s2 = s1;
  s2.seed = 2;
  s2.check_smoothness = false;
  SpectrumEstimate e, other;
  for (auto _ : state) {
    e = largest_frequency(*sys, s1);
    other = largest_frequency(*sys, s2);
  }
  if (!e.converged || !other.converged) state.SetLabel("not converged");
  state.counters["gershgorin_dt_fs"] = gershgorin * 1e3;
  state.counters["gershgorin_undamped_fs"] = sys->critical_dt() * 1e3;
  state.counters["spectral_dt_fs"] = e.critical_dt * 1e3;
  state.counters["spectral_fine_dt_fs"] = 2e3 / e.omega_fine;
  state.counters["smooth"] = e.smooth ? 1 : 0;
  state.counters["spectral_over_gershgorin"] = e.critical_dt / sys->critical_dt();
  state.counters["auto_over_spectral"] = auto_dt / e.critical_dt;
  state.counters["seeds_spread"] = std::abs(e.omega_max - other.omega_max) / e.omega_max;
  state.counters["lanczos_iterations"] = e.iterations;

  // Crossed vdW pairs at W's knee.
  const auto* vdw = sys->find<AnisotropicVdw>();
  const NeighborList& list = *sys->neighbors(*vdw);
  const VdwParams p;
  const double knee = p.w_knee * p.radius;
  Elements& el = sys->elements();
  std::array<double, 5> near{};  // within 1e-6, 1e-5, 1e-4, 1e-3, 1e-2 nm of the knee
  for (std::size_t i = 0; i < el.size(); ++i)
    for (std::uint32_t m = list.offsets()[i]; m < list.offsets()[i + 1]; ++m) {
      const std::uint32_t j = list.neighbors()[m];
      if (el.kind[i] != ElementKind::CntSegment || el.kind[j] != ElementKind::CntSegment ||
          el.cnt_pair_excluded(i, j, p.intra_tube_exclusion) ||
          !(std::abs(el.axis(i).dot(el.axis(j))) < 0.9999))
        continue;
      const double off = std::abs((el.x[j] - el.x[i]).norm() - knee);
      for (int k = 0; k < 5; ++k) near[k] += off < std::pow(10.0, k - 6);
    }
  for (int k = 0; k < 5; ++k) state.counters["knee_pairs_1e" + std::to_string(k - 6)] = near[k];

  // Elements whose force is not smooth at the 1e-5 nm scale.
  const std::vector<Vec3> x0 = el.x;
  std::vector<Vec3> dir(el.size());
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  for (Vec3& d : dir) d = Vec3(g(rng), g(rng), g(rng)).normalized();
  const auto derivative = [&](double h) {  // (f(x0 + h dir) − f(x0 − h dir)) / 2h per element
    std::vector<Vec3> d(el.size());
    for (std::size_t i = 0; i < el.size(); ++i) el.x[i] = x0[i] + h * dir[i];
    sys->refresh();
    for (std::size_t i = 0; i < el.size(); ++i) d[i] = el.f[i];
    for (std::size_t i = 0; i < el.size(); ++i) el.x[i] = x0[i] - h * dir[i];
    sys->refresh();
    for (std::size_t i = 0; i < el.size(); ++i) d[i] = (d[i] - el.f[i]) / (2.0 * h);
    return d;
  };
  const std::vector<Vec3> coarse = derivative(1e-5), fine = derivative(1e-6);
  el.x = x0;
  sys->refresh();
  double kinked = 0;
  for (std::size_t i = 0; i < el.size(); ++i)
    kinked += (fine[i] - coarse[i]).norm() > 1e-2 * coarse[i].norm();
  state.counters["kinked_elements"] = kinked;
}
BENCHMARK(BM_RelaxedMediumFilmCriticalStep)
    ->ArgNames({"threads", "nps"})
    ->ArgsProduct({{2}, {0, 1}})
    ->UseRealTime()
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

// Would a cluster-pair list (GROMACS's nbnxm: clusters of C elements, every pair of a listed
// cluster pair evaluated in SIMD lanes, masked beyond the cutoff) beat the element-pair list on
// this film? It trades the gather of each listed pair for evaluating pairs beyond the cutoff, so
// it pays when the clusters' pairs are mostly within it. Clusters here are runs of C consecutive
// segments of one tube (a tube's segments are consecutive in memory, as generated). Counters:
// fill_exact, the pairs within the vdW cutoff over all pairs of the cluster pairs that hold at
// least one (the best any cluster list can do); fill_listed, the same over the cluster pairs
// whose bounding spheres are within cutoff + skin 0.5 nm (what a list built once per rebuild
// holds); element_fill, within-cutoff over listed element pairs (today's list). No timing.
void BM_ClusterPairFill(benchmark::State& state) {
  const int C = static_cast<int>(state.range(0));
  const FilmState& f = film(0);
  IntegratorSettings set;
  set.threads = 1;
  auto sys = tensile_film_system(f.el, set, kDashpot, nullptr);
  sys->initialize();
  const auto* vdw = sys->find<AnisotropicVdw>();
  const NeighborList& list = *sys->neighbors(*vdw);
  const Elements& el = sys->elements();
  const std::size_t n = el.size();
  const double rc = vdw->cutoff(), rc2 = rc * rc, skin = 0.5;
  // Clusters: [first, end) runs of at most C consecutive elements of one tube.
  std::vector<std::uint32_t> cluster(n);
  std::vector<std::pair<std::size_t, std::size_t>> run;
  for (std::size_t i = 0; i < n;) {
    std::size_t e = i + 1;
    while (e < n && e - i < static_cast<std::size_t>(C) && el.tube[i] >= 0 &&
           el.tube[e] == el.tube[i])
      ++e;
    for (std::size_t k = i; k < e; ++k) cluster[k] = static_cast<std::uint32_t>(run.size());
    run.emplace_back(i, e);
    i = e;
  }
  const std::size_t nc = run.size();
  std::vector<Vec3> centre(nc);
  std::vector<double> radius(nc);
  double rmax = 0;
  for (std::size_t a = 0; a < nc; ++a) {
    Vec3 s = Vec3::Zero();
    for (std::size_t k = run[a].first; k < run[a].second; ++k) s += el.x[k];
    centre[a] = s / static_cast<double>(run[a].second - run[a].first);
    for (std::size_t k = run[a].first; k < run[a].second; ++k)
      radius[a] = std::max(radius[a], (el.x[k] - centre[a]).norm());
    rmax = std::max(rmax, radius[a]);
  }
  const auto key = [](std::uint64_t a, std::uint64_t b) {
    return a < b ? a << 32 | b : b << 32 | a;
  };
  const auto slots = [&](const std::vector<std::uint64_t>& pairs) {
    double s = 0;
    for (std::uint64_t p : pairs) {
      const double na = static_cast<double>(run[p >> 32].second - run[p >> 32].first);
      const double nb =
          static_cast<double>(run[p & 0xffffffffu].second - run[p & 0xffffffffu].first);
      s += (p >> 32) == (p & 0xffffffffu) ? na * (na - 1) / 2 : na * nb;
    }
    return s;
  };
  const auto unique = [](std::vector<std::uint64_t>& v) {
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
  };
  for (auto _ : state) {
    double within = 0;
    std::vector<std::uint64_t> exact, listed;
    for (std::size_t i = 0; i < n; ++i)
      for (std::uint32_t m = list.offsets()[i]; m < list.offsets()[i + 1]; ++m) {
        const std::uint32_t j = list.neighbors()[m];
        if ((el.x[j] - el.x[i]).squaredNorm() < rc2) {
          within += 1;
          exact.push_back(key(cluster[i], cluster[j]));
        }
      }
    unique(exact);
    // Every cluster pair whose spheres come within rc + skin, from a grid over the centres.
    const double cell = rc + skin + 2 * rmax;
    std::map<std::array<long, 3>, std::vector<std::uint32_t>> grid;
    const auto cell_of = [&](const Vec3& x) {
      return std::array<long, 3>{static_cast<long>(std::floor(x.x() / cell)),
                                 static_cast<long>(std::floor(x.y() / cell)),
                                 static_cast<long>(std::floor(x.z() / cell))};
    };
    for (std::size_t a = 0; a < nc; ++a)
      grid[cell_of(centre[a])].push_back(static_cast<std::uint32_t>(a));
    for (const auto& [c, members] : grid)
      for (long dx = -1; dx <= 1; ++dx)
        for (long dy = -1; dy <= 1; ++dy)
          for (long dz = -1; dz <= 1; ++dz) {
            const auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
            if (it == grid.end()) continue;
            for (std::uint32_t a : members)
              for (std::uint32_t b : it->second)
                if (b >= a && (centre[a] - centre[b]).norm() - radius[a] - radius[b] < rc + skin)
                  listed.push_back(key(a, b));
          }
    unique(listed);
    state.counters["clusters"] = static_cast<double>(nc);
    state.counters["fill_exact"] = within / slots(exact);
    state.counters["fill_listed"] = within / slots(listed);
    state.counters["element_fill"] = within / static_cast<double>(list.pair_count());
    state.counters["cluster_pairs_listed"] = static_cast<double>(listed.size());
  }
}
BENCHMARK(BM_ClusterPairFill)
    ->ArgName("cluster")
    ->Arg(2)
    ->Arg(4)
    ->Arg(8)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// The tensile job's per-frame aligned-pair count on the README's film (100 × 100 × 11 nm, 30 tubes
// × 70 segments, seed 1, after 200 pre-relaxation steps): kept:0 builds a list of its own
// (count_aligned_pairs(el)), kept:1 walks the system's vdW list (what TensileJob's frames do).
// Both must give the same counts (the run stops with an error otherwise).
void BM_AlignedPairCount(benchmark::State& state) {
  static const std::unique_ptr<System> sys = [] {
    TensileFilmSpec spec;
    spec.side = 100;
    spec.tubes = 30;
    spec.segments_per_tube = 70;
    spec.seed = 1;
    Elements el;
    add_tensile_film(el, spec);
    IntegratorSettings set;
    set.local_damping = kPrerelaxDamping;
    set.threads = 1;
    auto s = tensile_film_system(std::move(el), set, kDashpot);
    s->run(200);
    return s;
  }();
  const bool kept = state.range(0) != 0;
  const Elements& el = sys->elements();
  const NeighborList& list = *sys->neighbors(*sys->find<AnisotropicVdw>());
  const AlignedPairCounts own = count_aligned_pairs(el);
  const std::optional<AlignedPairCounts> via = count_aligned_pairs(el, list);
  if (!via || via->thesis != own.thesis || via->registry_free != own.registry_free) {
    state.SkipWithError("the kept list's counts differ from the own list's");
    return;
  }
  for (auto _ : state) {
    const AlignedPairCounts c = kept ? *count_aligned_pairs(el, list) : count_aligned_pairs(el);
    benchmark::DoNotOptimize(c);
  }
  state.counters["registry_free"] = static_cast<double>(own.registry_free);
  state.counters["thesis"] = static_cast<double>(own.thesis);
}
BENCHMARK(BM_AlignedPairCount)->ArgName("kept")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

[[noreturn]] void usage(const std::string& why) {
  std::fprintf(stderr,
               "bench_tensile_film: %s\nusage: bench_tensile_film --prepare DIR [--nps 0|%d] "
               "[--prerelax-ps P (0, 1e4]] [--relax-ps R [0, 1e5]] [--threads N [1, 256]]\n"
               "       bench_tensile_film [benchmark flags]  (state files from "
               "MDEM_TENSILE_FILM_DIR)\n",
               why.c_str(), kNps);
  std::exit(2);
}

double number(const std::string& flag, const char* text, double lo, double hi) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(v) || v < lo || v > hi) {
    std::ostringstream os;
    os << flag << " must be a finite number in [" << lo << ", " << hi << "], got \"" << text
       << "\"";
    usage(os.str());
  }
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "--prepare") {
    if (argc < 3) usage("--prepare needs a directory");
    const std::string dir = argv[2];
    int nps = 0, threads = 1;
    double prerelax = 20, relax = 100;
    for (int i = 3; i < argc; i += 2) {
      const std::string k = argv[i];
      if (i + 1 >= argc) usage(k + " needs a value");
      if (k == "--nps") {
        nps = static_cast<int>(number(k, argv[i + 1], 0, kNps));
        if (nps != 0 && nps != kNps) usage("--nps must be 0 or " + std::to_string(kNps));
      } else if (k == "--prerelax-ps") {
        prerelax = number(k, argv[i + 1], 0, 1e4);
        if (prerelax == 0) usage("--prerelax-ps must be > 0");
      } else if (k == "--relax-ps") {
        relax = number(k, argv[i + 1], 0, 1e5);
      } else if (k == "--threads") {
        threads = static_cast<int>(number(k, argv[i + 1], 1, 256));
      } else {
        usage("unknown option " + k);
      }
    }
    try {
      return prepare(dir, nps, prerelax, relax, threads);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_tensile_film: %s\n", e.what());
      return 1;
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
