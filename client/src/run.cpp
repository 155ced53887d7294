// `mdem run <kind>`: a job run in this process. The kinds built from a job spec (twist,
// compression: run_spec.cpp), and `bundle` (the engine's energy-conservation check: a vibrating,
// spinning CNT bundle without damping).
#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "console.h"
#include "flags.h"
#include "jobs.h"
#include "mdem/cli.h"
#include "mdem/core/units.h"
#include "mdem/job/bundle_job.h"
#include "mdem/job_state.h"
#include "mdem/spec_job.h"
#include "mdem/suggest.h"
#include "spec_flags.h"

namespace mdem::cli {
namespace {

constexpr const char* kBundleAbout =
    "A bundle of parallel CNTs without damping from random velocities: the engine's energy-"
    "conservation check";

// The first clause of a kind's description (up to its first ':' or '.'), on one line.
std::string first_clause(const std::string& about) {
  std::string text;
  for (const char c : about) {
    if (c == ':' || (c == '.' && (text.empty() || text.back() != 'h'))) break;  // "Ch. 4"
    text += c == '\n' ? ' ' : c;
  }
  return text;
}

// `mdem run --help`: the job kinds, one line each.
void print_kinds_help(std::ostream& os) {
  os << "Usage: mdem run KIND [--spec FILE] [flags]\n"
        "       mdem run --resume ID [flags]   (continue a stopped or killed job)\n"
        "\n"
        "Runs a job in this process and stores its results in the local results database\n"
        "(`mdem submit KIND` queues the same job on an mdemd daemon).\n"
        "\n"
        "Job kinds (`mdem run KIND --help`: the flags of one):\n";
  std::vector<std::vector<std::string>> rows;
  for (const SpecKind& k : spec_kinds().all())
    rows.push_back({"  " + k.name, first_clause(k.about)});
  rows.push_back({"  bundle", kBundleAbout});
  print_table(os, rows);
  os << "\nExit codes: 0 success, 1 the job failed (e.g. numerical instability) or was\n"
        "interrupted, 2 usage error.\n";
}

void print_run_help(std::ostream& os) {
  os << "Usage: mdem run bundle [flags]\n"
        "\n"
        "Runs a bundle of parallel (10,10) CNTs (bonds + anisotropic vdW, no damping) from seeded\n"
        "random velocities and spins, and reports the energy balance: without damping or loads,\n"
        "W_ext = 0 = dE, so the balance error measures the integration's accuracy.\n"
        "\n"
        "Flags:\n"
        "  --tubes N       1 or 7 (default 7)\n"
        "  --segments N    segments per tube, 2..5000 (default 50; T = 1.356 nm each)\n"
        "  --steps N       time steps, 1..1e9 (default 20000)\n"
        "  --dt X          time step in ps, or 'auto' (default: auto = safety x critical step)\n"
        "  --speed X       rms velocity per component, 0..10 nm/ps (default 0.05)\n"
        "  --spin X        rms angular velocity per component, 0..100 rad/ps (default 0.08)\n"
        "  --bundle-spin X rigid spin of the bundle about its axis, 0..10 rad/ps (default 0.05)\n"
        "  --seed N        random seed, 0..4294967295 (default 1)\n"
        "  --threads N     OpenMP threads, 0 = all cores (default 0)\n"
        "  --json          print one JSON object instead of text\n"
        "\n"
        "Exit codes: 0 success, 1 the job failed (e.g. numerical instability), 2 usage error.\n";
}

struct RunOptions {
  BundleSpec bundle;
  IntegratorSettings settings;
  long steps = 20000;
  bool json = false;
};

RunOptions parse_run_options(const std::vector<std::string>& args) {
  const FlagSpec spec{{"--tubes", "--segments", "--steps", "--dt", "--speed", "--spin",
                       "--bundle-spin", "--seed", "--threads"},
                      {"--json"}};
  auto given = parse_flags(args, spec);
  RunOptions o;
  if (given.count("--tubes")) {
    o.bundle.tubes = static_cast<int>(parse_integer("--tubes", given["--tubes"], 1, 7));
    if (o.bundle.tubes != 1 && o.bundle.tubes != 7)
      throw UsageError("--tubes: " + given["--tubes"] + " is not allowed (allowed: 1 or 7)");
  }
  if (given.count("--segments"))
    o.bundle.segments = static_cast<int>(parse_integer("--segments", given["--segments"], 2, 5000));
  if (given.count("--steps"))
    o.steps = parse_integer("--steps", given["--steps"], 1, 1'000'000'000);
  if (given.count("--dt") && given["--dt"] != "auto")
    o.settings.dt = parse_in_range("--dt", given["--dt"], 1e-6, 1.0, "ps (or auto)");
  if (given.count("--speed"))
    o.bundle.speed = parse_in_range("--speed", given["--speed"], 0.0, 10.0, "nm/ps");
  if (given.count("--spin"))
    o.bundle.spin = parse_in_range("--spin", given["--spin"], 0.0, 100.0, "rad/ps");
  if (given.count("--bundle-spin"))
    o.bundle.bundle_spin =
        parse_in_range("--bundle-spin", given["--bundle-spin"], 0.0, 10.0, "rad/ps");
  if (given.count("--seed"))
    o.bundle.seed = static_cast<unsigned>(parse_integer("--seed", given["--seed"], 0, 4294967295L));
  if (given.count("--threads"))
    o.settings.threads = static_cast<int>(parse_integer("--threads", given["--threads"], 0, 256));
  o.json = given.count("--json") > 0;
  return o;
}

json energies_json(const System& sys) {
  const EnergyLedger& L = sys.energy();
  json e;
  for (int k = 0; k < kEnergyTermCount; ++k)
    e[std::string(kEnergyTermNames[k]) + "_eV"] = L.potential.stored[k];
  e["kinetic_translational_eV"] = L.kinetic_translational;
  e["kinetic_rotational_eV"] = L.kinetic_rotational;
  e["external_work_eV"] = L.external_work;
  e["dissipated_eV"] = L.dissipated;
  e["total_eV"] = L.total();
  return e;
}

int run_bundle(const RunOptions& o, std::ostream& out, std::ostream& err) {
  // An ordinary job under the one run loop: progress, Ctrl-C and checkpoints as for every kind.
  BundleJob job({o.bundle, o.steps}, o.settings);
  System& sys = job.system();
  sys.initialize();
  const double e0 = sys.energy().total();
  const long n = static_cast<long>(sys.elements().size());
  if (!o.json)
    err << "bundle: " << o.bundle.tubes << " tube(s) x " << o.bundle.segments << " segments = " << n
        << " elements, " << o.steps << " steps of " << sys.dt() * 1000 << " fs on " << sys.threads()
        << " thread(s)\n";
  const auto t0 = std::chrono::steady_clock::now();
  // A progress line about every tenth of the run.
  const long chunk = std::max(1L, o.steps / 10);
  JobObserver obs;
  long printed = 0;
  obs.progress = [&](const JobProgress& p) {
    if (o.json || p.step == 0 || (p.step / chunk <= printed / chunk && p.step != o.steps)) return;
    printed = p.step;
    err << "  step " << p.step << "/" << o.steps << "  t = " << std::fixed << std::setprecision(1)
        << sys.time() << " ps  E = " << std::setprecision(6) << sys.energy().total() << " eV\n"
        << std::defaultfloat;
  };
  InterruptGuard interrupt;
  obs.cancelled = [] { return InterruptGuard::interrupted(); };
  std::string failure;
  bool cancelled = false;
  try {
    cancelled = run_job(job, {1.0, 0.0}, obs).cancelled;
    if (cancelled) failure = "interrupted by the user at step " + std::to_string(sys.steps());
  } catch (const NumericalError& e) {
    failure = e.what();
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  json doc;
  doc["kind"] = "bundle";
  doc["state"] = job_state_name(failure.empty() ? v1::SUCCEEDED
                                : cancelled     ? v1::CANCELLED
                                                : v1::FAILED);
  if (!failure.empty()) doc["reason"] = failure;
  json summary;
  summary["tubes"] = o.bundle.tubes;
  summary["segments_per_tube"] = o.bundle.segments;
  summary["elements"] = n;
  summary["simulated_ps"] = sys.time();
  if (failure.empty()) {
    summary["initial_total_eV"] = e0;
    summary["energies"] = energies_json(sys);
  }
  doc["summary"] = summary;
  doc["accuracy"] = accuracy_json(sys, failure.empty());
  doc["performance"] = performance_json(sys, wall);
  const json& perf = doc["performance"];

  if (o.json) {
    write_json(out, doc);
    out << "\n";
  } else if (failure.empty()) {
    out << "bundle: SUCCEEDED after " << sys.steps() << " steps (" << sys.time() << " ps)\n"
        << "  total energy " << e0 << " -> " << sys.energy().total() << " eV (kinetic "
        << sys.energy().kinetic() << " eV)\n"
        << "  energy balance error " << sys.energy_balance_error() << " (of the energy in play)\n"
        << "  dt " << sys.dt() * 1000 << " fs = " << sys.dt() / sys.critical_dt()
        << " x critical step\n"
        << "  " << wall << " s wall, " << perf["element_steps_per_s"].get<double>()
        << " element-steps/s\n";
  } else {
    err << "bundle: FAILED: " << failure << "\n";
  }
  return failure.empty() ? kOk : kJobFailed;
}

}  // namespace

int guarded_run(const std::string& command, const std::function<int()>& body, std::ostream& err) {
  try {
    return body();
  } catch (const UsageError& e) {
    err << command << ": " << e.what() << "\nRun '" << command << " --help' for the flags.\n";
    return kUsage;
  } catch (const ConfigError& e) {
    err << command << ": " << e.what() << "\n";
    return kUsage;
  } catch (const std::invalid_argument& e) {
    err << command << ": " << e.what() << "\n";
    return kUsage;
  } catch (const std::exception& e) {
    err << command << ": error: " << e.what() << "\n";
    return kJobFailed;
  }
}

int run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (args.empty() || args.front() == "--help" || args.front() == "-h") {
    print_kinds_help(args.empty() ? err : out);
    return args.empty() ? kUsage : kOk;
  }
  if (args.front() == "--resume" || args.front().rfind("--resume=", 0) == 0)
    return run_resume(args, out, err);
  const std::string kind = args.front();
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (const SpecKind* k = find_spec_kind(kind)) return run_spec_kind(*k, rest, out, err);
  if (kind != "bundle") {
    std::vector<std::string> kinds = {"bundle"};
    for (const SpecKind& k : spec_kinds().all()) kinds.push_back(k.name);
    err << "mdem run: unknown job kind '" << kind << "'" << did_you_mean(kind, kinds)
        << " (allowed: " << spec_kind_names() << ", bundle)\n";
    return kUsage;
  }
  if (wants_help(rest)) {
    print_run_help(out);
    return kOk;
  }
  return guarded_run(
      "mdem run bundle", [&] { return run_bundle(parse_run_options(rest), out, err); }, err);
}

}  // namespace mdem::cli
