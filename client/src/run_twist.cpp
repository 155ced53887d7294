// `mdem run twist`: the twist job in this process, from flags and/or a JSON/YAML spec file, with
// a progress bar on a terminal (plain lines when piped), results in the local database and a
// summary (text, or one JSON object with --json).
#include <chrono>

#include "console.h"
#include "flags.h"
#include "jobs.h"
#include "mdem/cli.h"
#include "mdem/spec.h"
#include "mdem/spec_job.h"
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
        "database (see `mdem ls`, `mdem show`, `mdem export`, `mdem plot`). To run it on an\n"
        "mdemd daemon instead, use the same flags with `mdem submit twist`.\n"
        "\n"
     << kTwistSpecFlagsHelp
     << "Output:\n"
        "  --db PATH            results database (default $MDEM_DB, else\n"
        "                       ~/.local/share/mdem/results.db)\n"
        "  --json               print one JSON object: job_id, state, summary, accuracy,\n"
        "                       performance\n"
        "\n"
        "Exit codes: 0 success, 1 the job failed (e.g. numerical instability) or was cancelled\n"
        "(Ctrl-C keeps what was computed), 2 usage error (bad flag or spec value).\n";
}

struct Parsed {
  v1::JobSpec spec;
  std::string db;
  bool json = false;
};

Parsed parse_twist_args(const std::vector<std::string>& args) {
  FlagSpec fs = twist_flag_spec();
  fs.with_value.push_back("--db");
  fs.switches.push_back("--json");
  const auto given = parse_flags(args, fs);
  Parsed p;
  p.spec = twist_spec_from_flags(given);
  p.db = given.count("--db") ? given.at("--db") : ResultsStore::default_path();
  p.json = given.count("--json") > 0;
  return p;
}

int execute(const Parsed& p, std::ostream& out, std::ostream& err) {
  TwistJob job(twist_job_spec(p.spec), integrator_settings(p.spec));
  const TwistLoading& loading = twist_job_spec(p.spec).loading;
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
        << (loading.boundary == TwistBoundary::ConstantMoment ? "constant-moment"
                                                              : "twist-relaxation")
        << ")\n";

  std::vector<SeriesFrame> pending;
  ProgressReporter progress(err, is_terminal(err), p.json);
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
  InterruptGuard interrupt;
  obs.cancelled = [] { return InterruptGuard::interrupted(); };

  const auto t0 = std::chrono::steady_clock::now();
  std::string state = "SUCCEEDED", reason;
  try {
    if (run_job(job, job_cadence(p.spec), obs).cancelled) {
      state = "CANCELLED";
      reason = "interrupted by the user; results up to t = " + std::to_string(job.system().time()) +
               " ps are kept";
    }
  } catch (const NumericalError& e) {
    state = "FAILED";
    reason = e.what();
  }
  progress.finish();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!pending.empty()) store.append_frames(rec.id, pending);

  json doc = job_report(job, rec.id, state, reason, wall);
  doc["db"] = store.path();
  store.finish_job(rec.id, state, reason, doc.dump());

  if (p.json) {
    write_json(out, doc);
    out << "\n";
  } else {
    print_report(out, err, doc, job.system().time());
  }
  return state == "SUCCEEDED" ? kOk : kJobFailed;
}

}  // namespace

int run_twist(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (wants_help(args)) {
    print_twist_help(out);
    return kOk;
  }
  Parsed p;
  try {
    p = parse_twist_args(args);
  } catch (const spec::SpecError& e) {
    err << "mdem run twist: invalid job spec:\n"
        << describe_spec_error(e) << "Run 'mdem run twist --help' for the flags.\n";
    return kUsage;
  } catch (const UsageError& e) {
    err << "mdem run twist: " << e.what() << "\nRun 'mdem run twist --help' for the flags.\n";
    return kUsage;
  }
  return guarded_run(
      "mdem run twist", [&] { return execute(p, out, err); }, err);
}

}  // namespace mdem::cli
