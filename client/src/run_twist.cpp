// `mdem run twist`: the twist job in this process, from flags and/or a JSON/YAML spec file, with
// a progress bar on a terminal (plain lines when piped), results in the local database and a
// summary (text, or one JSON object with --json).
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "flags.h"
#include "jobs.h"
#include "mdem/cli.h"
#include "mdem/spec.h"
#include "results_store.h"
#include "twist_spec.h"

namespace mdem::cli {
namespace {

void print_twist_help(std::ostream& os) {
  os << "Usage: mdem run twist [--spec FILE] [flags]\n"
        "\n"
        "Twists a hexagonal rope of parallel (10,10) CNTs by torques on its end grips (thesis\n"
        "Ch. 4): the torque rises at --rate to --torque, is held for --hold, and optionally\n"
        "unloaded. Reports twist angle, end shift, radius, topological charge Q of the mid\n"
        "cross-section and the morphology; stores spec, energies and snapshots in the results\n"
        "database (see `mdem ls`, `mdem show`, `mdem export`, `mdem plot`).\n"
        "\n"
        "Spec:\n"
        "  --spec FILE          a JobSpec as JSON or YAML (.json/.yaml/.yml); flags override it\n"
        "Rope:\n"
        "  --layers N           hexagon layers incl. the centre tube, 2..10 (default 6 = 91 "
        "tubes)\n"
        "  --length NM          tube length, 5..2000 nm, whole 1.356 nm segments (default 67.8)\n"
        "  --spacing NM|auto    tube spacing 1.5..2.5 nm (default auto: the lattice vdW minimum)\n"
        "  --missing I,J,...    point defects: lattice sites without a tube (0 = centre)\n"
        "  --line-defects A[:W[:F]];...  rows of missing tubes from the centre at angle A deg,\n"
        "                       W rows wide (1..3), over the central fraction F of the length\n"
        "Loading:\n"
        "  --torque X           T_max, (0, 500] nN·nm (default 64)\n"
        "  --rate X             ramp rate, (0, 100] nN·nm/ps (default 1.0)\n"
        "  --hold X             hold at T_max, 0..1e6 ps (default 100)\n"
        "  --bc B               constant-moment (default) or twist-relaxation\n"
        "  --grip-load G        rigid-grip (default: the grip's moment about the rope axis is T)\n"
        "                       or per-element (each grip element carries T about its own\n"
        "                       centre, the thesis's PFC ball moments)\n"
        "  --unload             ramp the torque down after the hold, then relax\n"
        "  --unload-hold X      relaxation after unloading, 0..1e6 ps (default 50)\n"
        "  --grip-segments N    end segments per tube in each grip, 1..segments/4 (default 1)\n"
        "  --damping-ratio X    vdW contact dashpot ratio, 0..1 (default 0.03)\n"
        "  --local-damping X    PFC local damping, 0..0.99 (default 0.1)\n"
        "  --temperature K      seeded random velocities and spins of K kelvin at the start,\n"
        "                       0..2000 (default 0: at rest; noise lets buckling start)\n"
        "Run:\n"
        "  --dt X|auto          time step, 1e-6..1 ps (default auto = safety x critical step)\n"
        "  --safety X           fraction of the critical step, (0, 1] (default 0.6)\n"
        "  --threads N          OpenMP threads, 0 = all cores (default 0)\n"
        "  --energy-every X     energy/observable frame interval, ps (default 1)\n"
        "  --snapshot-every X   snapshot interval, ps; 0 = none (default 10)\n"
        "  --name TEXT          a label for `mdem ls`\n"
        "  --seed N             random seed for --temperature (default 1)\n"
        "Output:\n"
        "  --db PATH            results database (default $MDEM_DB, else\n"
        "                       ~/.local/share/mdem/results.db)\n"
        "  --json               print one JSON object: job_id, state, summary, accuracy,\n"
        "                       performance\n"
        "\n"
        "Exit codes: 0 success, 1 the job failed (e.g. numerical instability) or was cancelled\n"
        "(Ctrl-C keeps what was computed), 2 usage error (bad flag or spec value).\n";
}

std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) { g_interrupted = true; }

// Progress: a redrawn bar with ETA on a terminal, a plain line every 10 % otherwise.
class ProgressReporter {
 public:
  ProgressReporter(std::ostream& err, bool tty, bool quiet) : err_(err), tty_(tty), quiet_(quiet) {}
  void operator()(const JobProgress& p) {
    if (quiet_ || p.total_steps <= 0) return;
    const double frac = static_cast<double>(p.step) / p.total_steps;
    const double wall = seconds();
    const double eta = frac > 0 ? wall * (1 - frac) / frac : 0;
    if (tty_) {
      const int w = 30, filled = static_cast<int>(frac * w);
      err_ << "\r[" << std::string(filled, '#') << std::string(w - filled, '-') << "] "
           << std::setw(3) << static_cast<int>(frac * 100) << "%  t " << std::fixed
           << std::setprecision(1) << p.time_ps << " ps  " << std::setw(9) << p.phase << "  ETA "
           << clock(eta) << "   " << std::defaultfloat << std::flush;
      if (p.step == p.total_steps) err_ << "\n";
    } else if (p.step == 0 || static_cast<int>(frac * 10) > last_decile_) {
      last_decile_ = static_cast<int>(frac * 10);
      err_ << "  step " << p.step << "/" << p.total_steps << "  t = " << std::fixed
           << std::setprecision(1) << p.time_ps << " ps  " << p.phase << "  wall " << clock(wall)
           << "  ETA " << clock(eta) << "\n"
           << std::defaultfloat;
    }
  }

 private:
  static std::string clock(double s) {
    const long t = static_cast<long>(s + 0.5);
    std::ostringstream o;
    o << t / 60 << ":" << std::setw(2) << std::setfill('0') << t % 60;
    return o.str();
  }
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }
  std::ostream& err_;
  bool tty_, quiet_;
  int last_decile_ = -1;
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

json summary_json(const Summary& s) {
  json j = json::object();
  for (const auto& [k, v] : s) std::visit([&, &k = k](const auto& x) { j[k] = x; }, v);
  return j;
}

struct Parsed {
  v1::JobSpec spec;
  std::string db;
  bool json = false;
};

Parsed parse_twist_args(const std::vector<std::string>& args) {
  FlagSpec fs;
  for (const auto& [flag, field] : twist_flag_fields())
    if (flag != "--unload") fs.with_value.push_back(flag);
  fs.with_value.insert(fs.with_value.end(), {"--spec", "--db"});
  fs.switches = {"--unload", "--json"};
  const auto given = parse_flags(args, fs);
  Parsed p;
  if (given.count("--spec")) p.spec = spec::load_file(given.at("--spec"));
  if (p.spec.kind_case() != v1::JobSpec::kTwist && p.spec.kind_case() != v1::JobSpec::KIND_NOT_SET)
    throw UsageError("--spec: the file describes another job kind (allowed here: twist)");
  apply_twist_flags(given, p.spec);
  p.spec = spec::finalize(p.spec);
  p.db = given.count("--db") ? given.at("--db") : ResultsStore::default_path();
  p.json = given.count("--json") > 0;
  return p;
}

// A spec error as usage lines: the field, and the flag that sets it.
std::string describe(const spec::SpecError& e) {
  std::ostringstream o;
  for (const spec::FieldError& f : e.errors()) {
    std::string flag;
    for (const auto& [fl, field] : twist_flag_fields())
      if (f.field == field || f.field.rfind(field + "[", 0) == 0) flag = fl;
    o << "  " << f.field << (flag.empty() ? "" : " (" + flag + ")") << ": " << f.message << "\n";
  }
  return o.str();
}

int execute(const Parsed& p, std::ostream& out, std::ostream& err) {
  const EngineJob ej = twist_engine_job(p.spec);
  TwistJob job(ej.twist, ej.settings);
  // A time step above the safe limit is refused here, before anything is stored.
  job.system().initialize();
  ResultsStore store(p.db);
  JobRecord rec;
  rec.id = ResultsStore::new_job_id();
  rec.kind = "twist";
  rec.spec_json = spec::to_json(p.spec, false);
  rec.state = "RUNNING";
  store.create_job(rec);
  store.set_columns(rec.id, job.columns());

  const long n = static_cast<long>(job.system().elements().size());
  if (!p.json)
    err << "twist " << rec.id << ": " << job.rope().tubes.size() << " tubes x "
        << job.rope().segments << " segments = " << n << " elements, " << job.duration()
        << " ps (ramp " << job.protocol().ramp_time() << " ps to " << p.spec.twist().torque_nn_nm()
        << " nN·nm, hold " << p.spec.twist().hold_ps() << " ps, "
        << (ej.twist.loading.boundary == TwistBoundary::ConstantMoment ? "constant-moment"
                                                                       : "twist-relaxation")
        << ")\n";

  std::vector<SeriesFrame> pending;
  ProgressReporter progress(err, isatty(STDERR_FILENO) && &err == &std::cerr, p.json);
  JobObserver obs;
  obs.frame = [&](const SeriesFrame& f) {
    pending.push_back(f);
    if (pending.size() >= 64) {
      store.append_frames(rec.id, pending);
      pending.clear();
    }
  };
  obs.snapshot = [&](const Snapshot& s) { store.append_snapshot(rec.id, s); };
  obs.progress = [&](const JobProgress& pr) { progress(pr); };
  g_interrupted = false;
  obs.cancelled = [] { return g_interrupted.load(); };
  auto previous = std::signal(SIGINT, on_sigint);

  const auto t0 = std::chrono::steady_clock::now();
  std::string state = "SUCCEEDED", reason;
  try {
    if (run_job(job, ej.cadence, obs).cancelled) {
      state = "CANCELLED";
      reason = "interrupted by the user; results up to t = " + std::to_string(job.system().time()) +
               " ps are kept";
    }
  } catch (const NumericalError& e) {
    state = "FAILED";
    reason = e.what();
  }
  std::signal(SIGINT, previous);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!pending.empty()) store.append_frames(rec.id, pending);

  const System& sys = job.system();
  json doc;
  doc["job_id"] = rec.id;
  doc["kind"] = "twist";
  doc["state"] = state;
  if (!reason.empty()) doc["reason"] = reason;
  doc["summary"] = state == "FAILED" ? json::object() : summary_json(job.summary());
  doc["accuracy"] = accuracy_json(sys, state != "FAILED");
  doc["performance"] = performance_json(sys, wall);
  const json& acc = doc["accuracy"];
  const json& perf = doc["performance"];
  doc["db"] = store.path();
  store.finish_job(rec.id, state, reason, doc.dump());

  if (p.json) {
    write_json(out, doc);
    out << "\n";
  } else {
    if (state == "FAILED") err << "twist " << rec.id << ": FAILED: " << reason << "\n";
    out << "twist " << rec.id << ": " << state << " after " << sys.steps() << " steps ("
        << sys.time() << " ps)\n";
    if (state != "FAILED") {
      const json& s = doc["summary"];
      out << "  morphology " << s["morphology"].get<std::string>() << ", twist angle "
          << s["twist_angle_deg"].get<double>() << " deg, end shift "
          << s["shift_angle_deg"].get<double>() << " deg\n"
          << "  topological charge Q = " << s["topological_charge"].get<long>() << " (max "
          << s["max_topological_charge"].get<long>() << "), rope radius "
          << s["rope_radius_nm"].get<double>() << " nm (initial "
          << s["initial_rope_radius_nm"].get<double>() << "), length "
          << s["length_nm"].get<double>() << " nm\n"
          << "  grip torque " << s["applied_torque_nNnm"].get<double>() << " nN·nm applied, "
          << s["grip_reaction_nNnm"].get<double>() << " nN·nm reaction\n"
          << "  energy balance error " << acc["energy_balance_error"].get<double>() << ", dt "
          << sys.dt() * 1000 << " fs = " << sys.dt() / sys.critical_dt() << " x critical step\n";
    }
    out << "  " << wall << " s wall, " << perf["element_steps_per_s"].get<double>()
        << " element-steps/s\n"
        << "  results: mdem show " << rec.id << " --db " << store.path() << "\n";
  }
  return state == "SUCCEEDED" ? kOk : kJobFailed;
}

}  // namespace

int run_twist(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  for (const std::string& a : args)
    if (a == "--help" || a == "-h") {
      print_twist_help(out);
      return kOk;
    }
  Parsed p;
  try {
    p = parse_twist_args(args);
  } catch (const spec::SpecError& e) {
    err << "mdem run twist: invalid job spec:\n"
        << describe(e) << "Run 'mdem run twist --help' for the flags.\n";
    return kUsage;
  } catch (const UsageError& e) {
    err << "mdem run twist: " << e.what() << "\nRun 'mdem run twist --help' for the flags.\n";
    return kUsage;
  }
  return guarded_run(
      "mdem run twist", [&] { return execute(p, out, err); }, err);
}

}  // namespace mdem::cli
