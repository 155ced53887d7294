// The tensile job's validation runs (docs/tensile.md), a plain timed program:
//
//   validate_tensile two-tube   thesis Fig. 5-7 (tensile.md §3.7): t_align of two crossed
//                               50-segment tubes with 0, 1 and 2 NPs in the acute wedges;
//                               options --psi LIST (dashpot ratios, default 0.03) --max-ps T
//                               --dashpot-shear 1 (the thesis's shear dashpot too);
//   validate_tensile film       one tensile job on a film: --size small|medium|large or
//                               --side L --tubes N --segments S; --nps N --relax-ps T
//                               --target E --rate R --ramp T --seed K --report-strains LIST
//                               --report-times LIST --dt PS (fixed; default: picked per stage);
//                               --psi X (dashpots), --dashpot-shear 1 (the thesis's shear
//                               dashpot too), --local-damping X; --vdw-law pfc (the
//                               thesis's literal Table 2-3: PFC torque, flip_blend 0) and
//                               --flip-blend X (after it) for comparisons with the thesis,
//                               --guard-tolerance X (the literal law is not conservative);
//                               cyclic with --cycles N --amplitude A --cyclic-rate R; prints the
//                               summary and the wall time (bench/validate_tensile_films.sh runs
//                               the validation set with it).
//
// --threads N for both.
#include <omp.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "mdem/job/tensile_job.h"
#include "mdem/scene/two_tube_alignment.h"

namespace {

using namespace mdem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::vector<double> list(const std::string& s) {
  std::vector<double> v;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) v.push_back(std::stod(item));
  return v;
}

int two_tube(const std::vector<std::string>& args, IntegratorSettings is) {
  std::vector<double> psis = {0.03};
  double max_ps = 4000;
  bool shear = false;
  for (std::size_t i = 0; i + 1 < args.size(); i += 2) {
    if (args[i] == "--psi")
      psis = list(args[i + 1]);
    else if (args[i] == "--max-ps")
      max_ps = std::stod(args[i + 1]);
    else if (args[i] == "--dashpot-shear")
      shear = args[i + 1] == "1";
    else
      throw std::invalid_argument("two-tube: unknown option " + args[i]);
  }
  std::printf("%6s %4s %12s %10s %10s %8s\n", "psi", "NPs", "t_align_ps", "steps", "dt_ps",
              "wall_s");
  for (double psi : psis)
    for (int n = 0; n <= 2; ++n) {
      TwoTubeAlignmentSpec s;
      s.nanoparticles = n;
      AlignmentSettings st;
      st.max_ps = max_ps;
      st.dashpot_ratio = psi;
      st.dashpot_shear = shear;
      st.sample_every_ps = 5;
      const auto t0 = Clock::now();
      const AlignmentRun r = run_two_tube_alignment(s, st, is);
      std::printf("%6.3f %4d %12.0f %10ld %10.4f %8.2f\n", psi, n, r.t_align ? *r.t_align : -1.0,
                  r.steps, r.dt, seconds_since(t0));
    }
  std::printf("(t_align -1: not aligned within %.0f ps; thesis: 750 / ~1500 / 2300 ps)\n", max_ps);
  return 0;
}

int film(const std::vector<std::string>& args, IntegratorSettings is) {
  TensileJobSpec spec;
  spec.film = TensileFilmSpec::of_size(FilmSize::Small);
  for (std::size_t i = 0; i + 1 < args.size(); i += 2) {
    const std::string& k = args[i];
    const std::string& v = args[i + 1];
    if (k == "--size")
      spec.film = TensileFilmSpec::of_size(film_size_from_name(v));
    else if (k == "--side")
      spec.film.side = std::stod(v);
    else if (k == "--tubes")
      spec.film.tubes = std::stoi(v);
    else if (k == "--segments")
      spec.film.segments_per_tube = std::stoi(v);
    else if (k == "--nps")
      spec.nanoparticles = std::stoi(v);
    else if (k == "--relax-ps")
      spec.relax_ps = std::stod(v);
    else if (k == "--target")
      spec.monotonic.target_strain = std::stod(v);
    else if (k == "--rate")
      spec.monotonic.strain_rate = std::stod(v);
    else if (k == "--ramp")
      spec.monotonic.ramp_time = std::stod(v);
    else if (k == "--seed")
      spec.seed = std::stoull(v);
    else if (k == "--cycles") {  // a cyclic test of this many cycles (mean rate --cyclic-rate)
      spec.mode = TensileMode::Cyclic;
      spec.cyclic.cycles = std::stoi(v);
    } else if (k == "--amplitude")
      spec.cyclic.amplitude = std::stod(v);
    else if (k == "--cyclic-rate")
      spec.cyclic.mean_rate = std::stod(v);
    else if (k == "--report-strains")
      spec.test_report_strains = list(v);
    else if (k == "--report-times")
      spec.relax_report_ps = list(v);
    else if (k == "--vdw-law") {  // exact (default) or pfc: the thesis's literal Table 2-3
      if (v == "pfc") {
        spec.laws.vdw.torque = VdwTorque::Pfc;
        spec.laws.vdw.flip_blend = 0;
      } else if (v != "exact") {
        throw std::invalid_argument("film: --vdw-law must be exact or pfc, got " + v);
      }
    } else if (k == "--flip-blend")  // after --vdw-law, to keep one of its settings apart
      spec.laws.vdw.flip_blend = std::stod(v);
    else if (k == "--local-damping")
      spec.local_damping = std::stod(v);
    else if (k == "--psi")
      spec.dashpot_ratio = std::stod(v);
    else if (k == "--dashpot-shear")  // 1: the thesis's shear dashpot too, 0: normal-only
      spec.laws.dashpot_shear = v == "1";
    else if (k == "--guard-tolerance")  // the run guard's (a non-conservative law adds energy)
      is.guard_energy_tolerance = std::stod(v);
    else if (k == "--dt")  // fixed for every stage (default: the job picks it per stage)
      is.dt = std::stod(v);
    else
      throw std::invalid_argument("film: unknown option " + k);
  }
  if (spec.mode == TensileMode::Cyclic) spec.test_report_strains.clear();
  const auto t0 = Clock::now();
  TensileJob job(spec, is);
  JobCadence c;
  c.frame_every_ps = 1e9;  // no frames: the summary only
  JobObserver obs;
  std::string stage;
  obs.progress = [&](const JobProgress& p) {
    if (p.stage != stage) {
      stage = p.stage;
      std::printf("  stage %s at %.1f s\n", stage.c_str(), seconds_since(t0));
      std::fflush(stdout);
    }
  };
  run_job(job, c, obs);
  const double wall = seconds_since(t0);
  for (const auto& [key, value] : job.summary()) {
    std::printf("  %-36s ", key.c_str());
    std::visit(
        [](const auto& x) {
          using T = std::decay_t<decltype(x)>;
          if constexpr (std::is_same_v<T, std::string>)
            std::printf("%s\n", x.c_str());
          else if constexpr (std::is_same_v<T, long>)
            std::printf("%ld\n", x);
          else
            std::printf("%.6g\n", x);
        },
        value);
  }
  std::printf("  wall %.1f s on %d thread(s), %zu elements, %ld steps\n", wall,
              job.system().threads(), job.system().elements().size(), job.overall_step());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: validate_tensile two-tube|film [options] (see the source)\n");
    return 2;
  }
  const std::string mode = argv[1];
  std::vector<std::string> args(argv + 2, argv + argc);
  IntegratorSettings is;
  for (std::size_t i = 0; i + 1 < args.size(); ++i)
    if (args[i] == "--threads") {
      is.threads = std::stoi(args[i + 1]);
      args.erase(args.begin() + static_cast<long>(i), args.begin() + static_cast<long>(i) + 2);
      break;
    }
  try {
    if (mode == "two-tube") return two_tube(args, is);
    if (mode == "film") return film(args, is);
    std::fprintf(stderr, "unknown mode %s\n", mode.c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
