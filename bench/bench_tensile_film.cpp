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
// (relaxed_ps 0 in its counters). 80 steps are timed (4 × 20: a few neighbour-list rebuilds).
// Counters: element_steps_per_s, the step's phases (pair_ms, neighbor_ms, integrate_ms), the half
// pairs per segment within the vdW cutoff (4T = 5.424 nm; tensile.md §4.1: medium 14.8
// ready-to-relax, ≈ 22 relaxed), the listed pairs per element, and the relaxation the state file
// had (relaxed_ps). BM_AlignedPairCount times the tensile job's per-frame aligned-pair count
// (below).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bench_support.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/io/state_io.h"
#include "mdem/job/prerelax_criterion.h"
#include "mdem/job/tensile_job.h"
#include "mdem/observe/aligned_pairs.h"
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

void BM_RelaxedMediumFilm(benchmark::State& state) {
  const int nps = state.range(1) != 0 ? kNps : 0;
  const FilmState& f = film(nps);
  const auto rest = rest_bonds(generated_film(nps));
  IntegratorSettings set;
  set.threads = static_cast<int>(state.range(0));
  auto sys = tensile_film_system(f.el, set, kDashpot, rest.get());
  sys->run(5);  // warm-up
  const StepTimers t0 = sys->timers();
  const double steps = bench::timed_steps(state, *sys, 20);
  bench::add_phase_counters(state, t0, sys->timers(), steps);
  const double n = static_cast<double>(sys->elements().size());
  state.counters["dt_fs"] = sys->dt() * 1e3;
  state.counters["relaxed_ps"] = f.relax_ps;
  state.counters["half_pairs_per_segment"] = pairs_per_segment(*sys);
  state.counters["listed_pairs_per_element"] =
      static_cast<double>(sys->neighbors(*sys->find<AnisotropicVdw>())->pair_count()) / n;
}
BENCHMARK(BM_RelaxedMediumFilm)
    ->ArgNames({"threads", "nps"})
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(4);

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
