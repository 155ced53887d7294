// `mdem run <kind>` for the kinds built from a job spec (spec_kinds(): twist, compression): the
// job in this process, from flags and/or a JSON/YAML spec file, with a progress bar on a
// terminal (plain lines when piped), results in the local database and a summary (text, or one
// JSON object with --json).
#include <filesystem>
#include <optional>

#include "console.h"
#include "flags.h"
#include "jobs.h"
#include "local_checkpoint.h"
#include "loop_timing.h"
#include "mdem/cli.h"
#include "mdem/job_runner.h"
#include "mdem/job_state.h"
#include "mdem/spec.h"
#include "results_store.h"
#include "run_log.h"
#include "spec_flags.h"
#include "thermo.h"

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
        "                       performance, timing (and log)\n"
        "  --thermo-every X     a thermo table row every X ps of simulated time (default:\n"
        "                       about 15 rows a run, a multiple of --energy-every; rows are\n"
        "                       the stored frames, so X >= --energy-every)\n"
        "  --log PATH           copy of what the terminal shows (default: <db dir>/logs/<job\n"
        "                       id>.log)\n"
        "  --no-log             write no log file\n"
        "  --checkpoint-every S checkpoint every S seconds of wall time (default 300), and at\n"
        "                       the end of a stage another follows and when stopped, into\n"
        "                       <db dir>/checkpoints/<job id>.ckpt; `mdem run --resume ID`\n"
        "                       continues the job from there\n"
        "  --no-checkpoint      write no checkpoint (the job cannot be resumed)\n"
        "\n"
        "Exit codes: 0 success, 1 the job failed (e.g. numerical instability) or was cancelled\n"
        "(Ctrl-C, SIGTERM or SIGHUP keep what was computed), 2 usage error (bad flag or spec\n"
        "value). A job whose process was killed outright (kill -9) is listed as INTERRUPTED.\n";
}

using Parsed = SpecRunOptions;

Parsed parse_args(const SpecKind& kind, const std::vector<std::string>& args) {
  FlagSpec fs = spec_flag_spec(kind);
  fs.with_value.push_back("--db");
  fs.with_value.push_back("--thermo-every");
  fs.with_value.push_back("--log");
  fs.switches.push_back("--json");
  fs.switches.push_back("--no-log");
  add_checkpoint_flags(fs);
  const auto given = parse_flags(args, fs);
  Parsed p;
  p.spec = spec_from_flags(kind, given);
  p.db = given.count("--db") ? given.at("--db") : ResultsStore::default_path();
  p.json = given.count("--json") > 0;
  p.no_log = given.count("--no-log") > 0;
  p.checkpoint = parse_checkpoint_flags(given);
  if (given.count("--log")) {
    if (p.no_log) throw UsageError("--log and --no-log: give one of them");
    p.log = given.at("--log");
  }
  if (given.count("--thermo-every")) {
    const std::string& text = given.at("--thermo-every");
    const double frame = p.spec.outputs().energy_every_ps();
    p.thermo_every_ps = parse_in_range("--thermo-every", text, 1e-6, 1e9, "ps");
    // Rows are the stored frames: a finer interval would print nothing more.
    if (*p.thermo_every_ps < frame * (1 - 1e-9))
      throw UsageError("--thermo-every: " + text + " ps is below the frame interval " +
                       std::to_string(frame) +
                       " ps (thermo rows are the stored frames; allowed: at least the frame "
                       "interval, or lower --energy-every)");
  }
  return p;
}

// The thermo table of a run: its header once the first frame comes (the job's system and
// duration are known then, after any scene-building stage), then the rows due.
class ThermoPrinter {
 public:
  ThermoPrinter(Job& job, const std::string& kind, const Parsed& p)
      : job_(job),
        kind_(kind),
        every_(p.thermo_every_ps),
        frame_ps_(p.spec.outputs().energy_every_ps()) {}

  // Prints the frame's row when due; the header before the first.
  void frame(const SeriesFrame& f, ProgressReporter& progress, std::ostream& out) {
    if (!table_) {
      table_.emplace(thermo_columns(kind_, job_.columns()),
                     every_ ? *every_ : default_thermo_every(job_.duration(), frame_ps_),
                     frame_ps_);
      progress.clear();
      out << table_->header() << "\n";
    }
    last_ = f;
    if (!table_->due(f)) return;
    progress.clear();
    out << table_->row(f, job_.system().energy_balance_error()) << "\n" << std::flush;
  }
  bool started() const { return table_.has_value(); }
  // The last frame's row, when it was not printed (a run's end between two rows).
  void finish(std::ostream& out) {
    if (table_ && last_ && table_->last_step() != last_->step)
      out << table_->row(*last_, job_.system().energy_balance_error()) << "\n";
  }

 private:
  Job& job_;
  std::string kind_;
  std::optional<double> every_;
  double frame_ps_;
  std::optional<ThermoTable> table_;
  std::optional<SeriesFrame> last_;
};

}  // namespace

int run_spec_job(const SpecKind& kind, const SpecRunOptions& p, std::ostream& term_out,
                 std::ostream& term_err, std::string* job_id, const ResumePoint* resume) {
  const LocalCheckpointRecord* resumed = resume ? &resume->checkpoint.record : nullptr;
  const std::string id = resumed ? resumed->job_id : ResultsStore::new_job_id();
  if (job_id) *job_id = id;
  // A log path given opens first: one that cannot be written stops the run before anything
  // exists. The default one (beside the database) opens once the database did, so that the
  // database's own errors come first; what was shown before is held for it.
  // A resumed job's log goes on where it stopped.
  RunLog log(term_out, term_err);
  if (p.log) log.open(*p.log, resumed != nullptr);
  std::ostream& out = log.out();
  std::ostream& err = log.err();
  bool recorded = resumed != nullptr;  // a resumed job's log is never discarded
  try {
    if (!p.json)
      if (const std::string line = kind.building(p.spec); !line.empty())
        err << kind.name << ": " << line << "\n";
    JobRunner runner(p.spec, resumed ? resumed->threads : 0);
    Job& job = runner.job();
    // A time step above the safe limit is refused here, before anything is stored; a resumed job
    // is refused here when its checkpoint does not load.
    if (resume)
      load_local_checkpoint(resume->path, resume->checkpoint, job);
    else
      check_time_step(job);
    // From before the record exists: SIGINT, SIGTERM or SIGHUP stop the job as cancelled.
    InterruptGuard interrupt;
    ResultsStore store(p.db);
    if (!p.log && !p.no_log) log.open(default_log_path(p.db, id), resumed != nullptr);
    JobRecord rec;
    rec.id = id;
    rec.kind = kind.name;
    rec.spec_json = spec::to_json(p.spec, false);
    rec.state = job_state_name(v1::RUNNING);
    RunCheckpoints checkpoints(
        p.checkpoint, local_checkpoint_path(store.path(), id),
        {id, kind.name, rec.spec_json, job.system().threads(), 0, 0, 0, -1, -1, 0,
         log.enabled() ? std::filesystem::absolute(log.path()).string() : std::string()},
        resumed);
    if (resumed) {
      store.resume_job(id, static_cast<std::size_t>(resumed->frames),
                       static_cast<std::size_t>(resumed->snapshots));
      err << resumed_line(kind.name, id, *resumed, job) << "\n";
    } else {
      store.create_job(rec);
      recorded = true;
      store.set_columns(rec.id, job.columns());
    }
    if (!p.json) err << kind.name << " " << rec.id << ": " << kind.describe(job, p.spec) << "\n";

    std::vector<SeriesFrame> pending;
    // The bar on the terminal only; plain progress lines into the log as well.
    const bool tty = is_terminal(term_err);
    ProgressReporter progress(term_err, tty, p.json, &err);
    ThermoPrinter thermo(job, kind.name, p);
    LoopTiming timing;
    using Event = LoopTiming::Event;
    JobObserver obs;
    auto flush = [&] {
      if (!pending.empty()) store.append_frames(rec.id, pending);
      pending.clear();
    };
    obs.frame = [&](const SeriesFrame& f) {
      if (!checkpoints.take_frame(static_cast<int>(job.stage_index()), f.step)) return;
      timing.enter(Event::Frame);
      pending.push_back(f);
      if (pending.size() >= 64) {
        store.append_frames(rec.id, pending);
        pending.clear();
      }
      timing.split(LoopTiming::kStore);
      if (!p.json) thermo.frame(f, progress, out);
      timing.leave(LoopTiming::kTerminal);
    };
    obs.snapshot = [&](const Snapshot& s) {
      if (!checkpoints.take_snapshot(static_cast<int>(job.stage_index()), s.step)) return;
      timing.enter(Event::Snapshot);
      store.append_snapshot(rec.id, s);
      timing.leave(LoopTiming::kStore);
    };
    int stage_seen = 0;
    obs.progress = [&](const JobProgress& pr) {
      timing.enter(Event::Progress);
      // A job whose first stage builds the scene (the compression's packing) is described again
      // once built, with what the build made (grains, bonds).
      if (pr.stage_index != stage_seen && !p.json) {
        stage_seen = pr.stage_index;
        progress.note(kind.name + " " + rec.id + ": " + kind.describe(job, p.spec));
      }
      // Piped, the table's rows say where the run is: plain progress lines only before it starts
      // (a scene-building stage).
      // The run's last row before the bar's last draw (the end's frame came just before).
      if (pr.step == pr.total_steps && !p.json) {
        progress.clear();
        thermo.finish(out);
      }
      if (tty || !thermo.started()) progress(pr);
      timing.leave(LoopTiming::kTerminal);
    };
    obs.cancelled = [&] {
      timing.enter(Event::Poll);
      const bool stop = InterruptGuard::interrupted();
      timing.leave(LoopTiming::kOther);
      return stop;
    };
    // A checkpoint that cannot be written (a full disk): the job goes on, a resume starts from
    // the last good one.
    auto checkpoint = [&] {
      flush();
      try {
        checkpoints.write(job);
        return true;
      } catch (const CheckpointFileError& e) {
        progress.clear();
        err << kind.name << " " << id << ": warning: " << e.what()
            << "; the job goes on, a resume starts from the last good checkpoint\n";
        return false;
      }
    };
    obs.checkpoint = [&](long) {
      if (checkpoints.due(job)) checkpoint();
    };

    timing.begin();
    JobOutcome outcome = runner.run(obs, [](Job& j) {
      return std::string("interrupted (") + InterruptGuard::signal_name() +
             "); results up to t = " + std::to_string(j.system().time()) + " ps are kept";
    });
    progress.finish();
    flush();
    timing.end();
    // Stopped: a checkpoint to resume from; ended otherwise: none is needed any more.
    if (outcome.cancelled && checkpoints.enabled() && checkpoint())
      outcome.reason += "; resume with: " + resume_command(id, p.db);
    else if (!outcome.cancelled)
      checkpoints.remove();
    if (!p.json) thermo.finish(out);

    json doc = runner.report(rec.id, outcome, resumed ? resumed->wall_s : 0);
    doc["db"] = store.path();
    const System& sys = job.system();
    const JobWork work = job.work();
    LoopFigures figures;
    figures.steps = work.steps;
    figures.elements = static_cast<long>(sys.elements().size());
    figures.threads = sys.threads();
    figures.simulated_ps = sys.time();
    figures.element_steps_per_s = doc["performance"].value("element_steps_per_s", 0.0);
    json t;
    for (int k = 0; k < LoopTiming::kSections; ++k)
      t[LoopTiming::key(static_cast<LoopTiming::Section>(k))] =
          timing.seconds(static_cast<LoopTiming::Section>(k));
    doc["timing"] = t;
    if (log.enabled()) doc["log"] = log.path().string();
    store.finish_job(rec.id, job_state_name(outcome.state), outcome.reason, doc.dump());

    if (p.json) {
      write_json(out, doc);
      out << "\n";
    } else {
      print_report(out, err, doc, sys.time());
      out << "\n";
      print_loop_timing(out, timing, figures, &work.timers);
      if (log.enabled()) out << "\nlog: " << log.path().string() << "\n";
    }
    return outcome.state == v1::SUCCEEDED ? kOk : kJobFailed;
  } catch (...) {
    // A job that never started leaves no log behind (its error is on the terminal).
    if (!recorded) log.discard();
    throw;
  }
}

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
      command, [&] { return run_spec_job(kind, p, out, err); }, err);
}

}  // namespace mdem::cli
