// `mdem run <kind>` for the kinds built from a job spec (spec_kinds(): twist, compression): the
// job in this process, from flags and/or a JSON/YAML spec file, with a progress bar on a
// terminal (plain lines when piped), results in the local database and a summary (text, or one
// JSON object with --json).
#include "console.h"
#include "flags.h"
#include "jobs.h"
#include "mdem/cli.h"
#include "mdem/job_runner.h"
#include "mdem/job_state.h"
#include "mdem/spec.h"
#include "results_store.h"
#include "spec_flags.h"

namespace mdem::cli {
namespace {

void print_help(const SpecKind& kind, std::ostream& os) {
  os << "Usage: mdem run " << kind.name << " [--spec FILE] [flags]\n\n"
     << kind.about
     << "Stores spec, energies and snapshots in the results database (see `mdem ls`, `mdem "
        "show`,\n"
        "`mdem export`, `mdem plot`). To run it on an mdemd daemon instead, use the same flags\n"
        "with `mdem submit "
     << kind.name << "`.\n\n"
     << spec_flags_help(kind)
     << "Output:\n"
        "  --db PATH            results database (default $MDEM_DB, else\n"
        "                       ~/.local/share/mdem/results.db)\n"
        "  --json               print one JSON object: job_id, state, summary, accuracy,\n"
        "                       performance\n"
        "\n"
        "Exit codes: 0 success, 1 the job failed (e.g. numerical instability) or was cancelled\n"
        "(Ctrl-C, SIGTERM or SIGHUP keep what was computed), 2 usage error (bad flag or spec\n"
        "value). A job whose process was killed outright (kill -9) is listed as INTERRUPTED.\n";
}

struct Parsed {
  v1::JobSpec spec;
  std::string db;
  bool json = false;
};

Parsed parse_args(const SpecKind& kind, const std::vector<std::string>& args) {
  FlagSpec fs = spec_flag_spec(kind);
  fs.with_value.push_back("--db");
  fs.switches.push_back("--json");
  const auto given = parse_flags(args, fs);
  Parsed p;
  p.spec = spec_from_flags(kind, given);
  p.db = given.count("--db") ? given.at("--db") : ResultsStore::default_path();
  p.json = given.count("--json") > 0;
  return p;
}

int execute(const SpecKind& kind, const Parsed& p, std::ostream& out, std::ostream& err) {
  if (!p.json)
    if (const std::string line = kind.building(p.spec); !line.empty())
      err << kind.name << ": " << line << "\n";
  JobRunner runner(p.spec);
  Job& job = runner.job();
  // A time step above the safe limit is refused here, before anything is stored.
  check_time_step(job);
  // From before the record exists: SIGINT, SIGTERM or SIGHUP stop the job as cancelled.
  InterruptGuard interrupt;
  ResultsStore store(p.db);
  JobRecord rec;
  rec.id = ResultsStore::new_job_id();
  rec.kind = kind.name;
  rec.spec_json = spec::to_json(p.spec, false);
  rec.state = job_state_name(v1::RUNNING);
  store.create_job(rec);
  store.set_columns(rec.id, job.columns());
  if (!p.json) err << kind.name << " " << rec.id << ": " << kind.describe(job, p.spec) << "\n";

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
  int stage_seen = 0;
  obs.progress = [&](const JobProgress& pr) {
    // A job whose first stage builds the scene (the compression's packing) is described again
    // once built, with what the build made (grains, bonds).
    if (pr.stage_index != stage_seen && !p.json) {
      stage_seen = pr.stage_index;
      err << kind.name << " " << rec.id << ": " << kind.describe(job, p.spec) << "\n";
    }
    progress(pr);
  };
  obs.cancelled = [] { return InterruptGuard::interrupted(); };

  const JobOutcome outcome = runner.run(obs, [](Job& j) {
    return std::string("interrupted (") + InterruptGuard::signal_name() +
           "); results up to t = " + std::to_string(j.system().time()) + " ps are kept";
  });
  progress.finish();
  if (!pending.empty()) store.append_frames(rec.id, pending);

  json doc = runner.report(rec.id, outcome);
  doc["db"] = store.path();
  store.finish_job(rec.id, job_state_name(outcome.state), outcome.reason, doc.dump());

  if (p.json) {
    write_json(out, doc);
    out << "\n";
  } else {
    print_report(out, err, doc, job.system().time());
  }
  return outcome.state == v1::SUCCEEDED ? kOk : kJobFailed;
}

}  // namespace

int run_spec_kind(const SpecKind& kind, const std::vector<std::string>& args, std::ostream& out,
                  std::ostream& err) {
  if (wants_help(args)) {
    print_help(kind, out);
    return kOk;
  }
  const std::string command = "mdem run " + kind.name;
  Parsed p;
  try {
    p = parse_args(kind, args);
  } catch (const spec::SpecError& e) {
    err << command << ": invalid job spec:\n"
        << describe_spec_error(e) << "Run '" << command << " --help' for the flags.\n";
    return kUsage;
  } catch (const UsageError& e) {
    err << command << ": " << e.what() << "\nRun '" << command << " --help' for the flags.\n";
    return kUsage;
  }
  return guarded_run(
      command, [&] { return execute(kind, p, out, err); }, err);
}

}  // namespace mdem::cli
