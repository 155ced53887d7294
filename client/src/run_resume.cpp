// `mdem run --resume ID`: a local job that was stopped (Ctrl-C, SIGTERM, SIGHUP: CANCELLED) or
// killed (kill -9, a crash: INTERRUPTED) continues from its last checkpoint (local_checkpoint.h)
// under its own id, to the same results as a run that was never stopped: what the run stored
// after its checkpoint is dropped and computed again, the log is appended to. Refused, with
// nothing changed, for an unknown id, a job that finished or still runs, a daemon's job, and a
// checkpoint that is missing, damaged, of another job, kind or spec, or that this build's engine
// cannot read.
#include <filesystem>

#include "console.h"
#include "jobs.h"
#include "mdem/cli.h"
#include "mdem/job_state.h"
#include "mdem/spec.h"
#include "results_store.h"

namespace mdem::cli {
namespace {

namespace fs = std::filesystem;

void print_help(std::ostream& os) {
  os << "Usage: mdem run --resume ID [flags]\n"
        "\n"
        "Continues a job `mdem run KIND` started that was stopped (Ctrl-C, SIGTERM, SIGHUP:\n"
        "CANCELLED) or killed (INTERRUPTED) from its last checkpoint, <db dir>/checkpoints/\n"
        "<ID>.ckpt, to the same results as a run that was never stopped: summary, frames and\n"
        "snapshots equal bit for bit. ID may be a unique prefix of the job's id (see `mdem ls`).\n"
        "The job's log (if it had one) is appended to.\n"
        "\n"
        "Flags:\n"
        "  --db PATH            results database (default $MDEM_DB, else\n"
        "                       ~/.local/share/mdem/results.db)\n"
        "  --json               print one JSON object, as `mdem run KIND --json`\n"
        "  --log PATH           append what the terminal shows to PATH (default: the job's log)\n"
        "  --no-log             write no log file\n"
        "  --checkpoint-every S checkpoint every S seconds of wall time (default 300)\n"
        "  --no-checkpoint      write no further checkpoint\n"
        "\n"
        "Exit codes: 0 success, 1 the job failed or was stopped again, 2 usage error or the job\n"
        "cannot be resumed (unknown id, finished or still running, its checkpoint missing,\n"
        "damaged or not of this job; nothing is changed then).\n";
}

// The job's id and the flags, from `--resume ID ...` or `--resume=ID ...`.
std::pair<std::string, std::map<std::string, std::string>> parse_args(
    std::vector<std::string> args) {
  if (args.front().rfind("--resume=", 0) == 0)
    args.front() = args.front().substr(9);
  else
    args.erase(args.begin());
  FlagSpec fs{{"--db", "--log"}, {"--json", "--no-log"}};
  add_checkpoint_flags(fs);
  return parse_id_and_flags(args, fs);
}

// The job `id` names, if it can be resumed.
JobRecord resumable_job(const ResultsStore& store, const std::string& id) {
  const std::optional<JobRecord> found = store.find(id);
  const std::string where = " in " + store.path();
  if (!found)
    throw ResumeError("no job '" + id + "'" + where + " (`mdem ls --db " + store.path() +
                      "` lists them)");
  const JobRecord& rec = *found;
  if (!rec.server.empty())
    throw ResumeError("job '" + rec.id + "' runs on the daemon at " + rec.server +
                      ", which resumes its jobs itself (`mdem watch " + rec.id + "`)");
  const auto state = parse_job_state(rec.state);
  if (state == v1::SUCCEEDED || state == v1::FAILED)
    throw ResumeError("job '" + rec.id + "' has finished (" + rec.state +
                      "): there is nothing to resume; `mdem show " + rec.id + "` shows it");
  // TIMEOUT: a job stopped at its wall-time limit keeps its checkpoint as a cancelled one does.
  if (state != v1::CANCELLED && state != v1::INTERRUPTED && rec.state != "TIMEOUT")
    throw ResumeError("job '" + rec.id + "' is " + rec.state +
                      (state == v1::RUNNING ? " in another process (" + rec.runner +
                                                  "); stop it first (Ctrl-C there)"
                                            : std::string()) +
                      "; only a stopped (CANCELLED) or killed (INTERRUPTED) job can be resumed");
  return rec;
}

int resume_local(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  const auto [id, given] = parse_args(args);
  SpecRunOptions p;
  p.db = given.count("--db") ? given.at("--db") : ResultsStore::default_path();
  p.json = given.count("--json") > 0;
  p.no_log = given.count("--no-log") > 0;
  if (given.count("--log")) {
    if (p.no_log) throw UsageError("--log and --no-log: give one of them");
    p.log = given.at("--log");
  }
  p.checkpoint = parse_checkpoint_flags(given);
  std::error_code ec;
  if (!fs::exists(p.db, ec))
    throw ResumeError("no results database at '" + p.db + "' (give the --db the job ran with)");
  ResumePoint point;
  JobRecord rec;
  {
    const ResultsStore store(p.db);
    rec = resumable_job(store, id);
  }
  const SpecKind* kind = find_spec_kind(rec.kind);
  if (!kind)
    throw ResumeError("job '" + rec.id + "' is a '" + rec.kind +
                      "' job, which has no checkpoints (allowed: " + spec_kind_names() + ")");
  p.spec = spec::finalize(spec::parse_json(rec.spec_json));
  point.path = local_checkpoint_path(p.db, rec.id);
  point.checkpoint = read_local_checkpoint(point.path, rec.id, rec.kind, rec.spec_json);
  {
    // The rows the checkpoint counted must still be there (the resume drops only later ones).
    const ResultsStore store(p.db);
    const LocalCheckpointRecord& r = point.checkpoint.record;
    const auto frames = static_cast<long>(store.frame_count(rec.id));
    const auto snapshots = static_cast<long>(store.snapshot_count(rec.id));
    if (frames < r.frames || snapshots < r.snapshots)
      throw ResumeError("job '" + rec.id + "' has " + std::to_string(frames) + " frames and " +
                        std::to_string(snapshots) + " snapshots in " + p.db + ", fewer than the " +
                        std::to_string(r.frames) + " and " + std::to_string(r.snapshots) +
                        " its checkpoint " + point.path.string() +
                        " was written after (were rows deleted?); it cannot be resumed");
  }
  // The log the job had, unless another (or none) is asked for.
  const std::string& log = point.checkpoint.record.log;
  if (!p.log && !p.no_log) {
    if (log.empty())
      p.no_log = true;
    else
      p.log = log;
  }
  return run_spec_job(*kind, p, out, err, nullptr, &point);
}

}  // namespace

int run_resume(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (wants_help(args)) {
    print_help(out);
    return kOk;
  }
  return guarded_run(
      "mdem run --resume", [&] { return resume_local(args, out, err); }, err);
}

}  // namespace mdem::cli
