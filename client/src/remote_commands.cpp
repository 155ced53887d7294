// The commands on the mdemd daemon: `mdem submit`, `mdem watch`, `mdem cancel`, and `mdem ls` /
// `mdem show` with --server. What they learn of a job goes into the local results database, the
// same one `mdem run` fills, so `mdem export` and `mdem plot` work on both alike.
#include "remote_commands.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <mutex>
#include <thread>

#include "console.h"
#include "flags.h"
#include "mdem/cli.h"
#include "mdem/job_state.h"
#include "mdem/snapshot_proto.h"
#include "mdem/spec.h"
#include "mdem/spec_job.h"
#include "mdem/time_text.h"
#include "remote.h"
#include "results_store.h"
#include "spec_flags.h"
#include "study_commands.h"

namespace mdem::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr double kDefaultReconnectTimeoutS = 60;
constexpr std::size_t kFrameBatch = 64;                   // frames per transaction
constexpr auto kFlushInterval = std::chrono::seconds(1);  // at the latest, when events arrive

constexpr const char* kDbHelp =
    "  --db PATH            the local results database (default: $MDEM_DB, else\n"
    "                       $XDG_DATA_HOME/mdem/results.db, else ~/.local/share/mdem/results.db)\n";

constexpr const char* kRemoteExitHelp =
    "Exit codes: 0 success; 1 the job failed or was cancelled, the token was refused, the job\n"
    "is not yours or does not exist, or a per-user limit was hit; 2 usage error (a bad flag,\n"
    "config file or token file, or a spec the daemon refused: INVALID_ARGUMENT); 3 the daemon\n"
    "could not be reached or did not answer (UNAVAILABLE, a deadline), or the connection was\n"
    "lost for good while watching.\n";

constexpr const char* kTimeLimitHelp =
    "  --time-limit T       wall-time limit on the job's running time (queue time not counted;\n"
    "                       resumes add up), as Slurm's --time: 90s, 15m, 2h, 1.5d, MM, MM:SS,\n"
    "                       HH:MM:SS, D-HH, D-HH:MM, D-HH:MM:SS; above 0, at most 30 days and the\n"
    "                       daemon's max_time_limit (default: the daemon's default_time_limit).\n"
    "                       Reaching it ends the job in TIMEOUT with its checkpoint kept;\n"
    "                       `mdem resume ID --time-limit T` continues it.\n";

// The help of `mdem submit`: with a job kind first in `args`, that kind's flags.
void print_submit_help(const std::vector<std::string>& args, std::ostream& os) {
  const SpecKind* kind = args.empty() ? nullptr : find_spec_kind(args.front());
  const std::string name = kind ? kind->name : "KIND";
  os << "Usage: mdem submit " << name
     << " [--spec FILE] [flags] [--request-id ID] [--watch] [--json]\n"
        "                          [--db PATH] [--server HOST:PORT] [connection flags]\n"
        "\n"
        "Queues a job on the mdemd daemon: the spec is built and checked exactly as by\n"
        "`mdem run "
     << name
     << "` (same flags, same errors), sent with a request id, and recorded in the\n"
        "local results database under the daemon's job id. Prints the job id (stdout). A\n"
        "request id submitted twice yields one job, so a submit that failed on the way can be\n"
        "retried with the request id it printed. With --watch it then follows the job like\n"
        "`mdem watch`.\n"
        "\n";
  if (kind)
    os << spec_flags_help(*kind);
  else
    os << "Kinds: " << spec_kind_names() << " (`mdem submit KIND --help`: the flags of one)\n\n"
       << all_spec_flags_help();
  os << "Submit:\n"
        "  --request-id ID      1..128 characters of [A-Za-z0-9._:-] (default: a random one,\n"
        "                       printed so a retry can reuse it)\n"
        "  --watch              follow the job until it ends (see `mdem watch --help`)\n"
     << kTimeLimitHelp
     << "  --reconnect-timeout S  with --watch: give up reconnecting after S seconds (default "
        "60)\n"
        "  --json               print one JSON object: job_id, request_id, created, state, server\n"
        "                       (with --watch: the final report, as `mdem watch --json`)\n"
     << kDbHelp << "  -h, --help           show this help\n"
     << kConnectionHelp << "\n"
     << kRemoteExitHelp;
}

void print_watch_help(std::ostream& os) {
  os << "Usage: mdem watch ID [--json] [--reconnect-timeout S] [--db PATH] [connection flags]\n"
        "       mdem watch --study ID [same flags]   (each job of a study, then its table)\n"
        "\n"
        "Follows a daemon's job until it ends, storing its energy frames, snapshots, state and\n"
        "final report in the local results database as they arrive (then `mdem export` and\n"
        "`mdem plot` work on it as on a job of `mdem run`). Shows a progress bar on a terminal,\n"
        "plain lines when piped, and the daemon's log lines and notices (e.g. frames it skipped\n"
        "because its event log fell behind). Resumes where the database stops: watching again,\n"
        "or after a lost connection, fetches nothing twice and misses nothing. A job already\n"
        "finished and fully stored is just printed. The daemon is the one recorded with the\n"
        "job (from `mdem submit`) unless --server names another.\n"
        "Ctrl-C stops watching; it never cancels the job (`mdem cancel ID` does).\n"
        "\n"
        "Flags:\n"
        "  --json               print the final report as one JSON object (as `mdem run --json`)\n"
        "  --reconnect-timeout S  when the daemon cannot be reached or the connection is lost\n"
        "                       (before or after the first event), retry (every 0.2 s, doubling\n"
        "                       to 5 s) for S seconds, 0..86400 (default 60). A job not yet\n"
        "                       recorded in the database is first looked up once, without retry.\n"
     << kDbHelp << "  -h, --help           show this help\n"
     << kConnectionHelp
     << "\n"
        "Exit codes: 0 the job SUCCEEDED; 1 it FAILED or was CANCELLED (or the token was\n"
        "refused, the job is not yours or does not exist); 2 usage error; 3 the daemon could not\n"
        "be reached, or the connection was lost for longer than --reconnect-timeout (the job\n"
        "goes on; watch again to resume); 130 stopped by Ctrl-C.\n";
}

void print_cancel_help(std::ostream& os) {
  os << "Usage: mdem cancel ID [--json] [--db PATH] [connection flags]\n"
        "       mdem cancel --study ID [--db PATH] [connection flags]   (every job of a study)\n"
        "\n"
        "Cancels a queued or running job on the daemon; a running one stops within a second and\n"
        "keeps what it produced (`mdem watch ID` fetches it). Cancelling a finished job changes\n"
        "nothing. ID is passed to the daemon as given, or completed from the local database when\n"
        "it is a prefix of a job recorded there.\n"
        "\n"
        "Flags:\n"
        "  --json               print one JSON object: job_id, state, reason\n"
     << kDbHelp << "  -h, --help           show this help\n"
     << kConnectionHelp << "\n"
     << kRemoteExitHelp;
}

void print_resume_help(std::ostream& os) {
  os << "Usage: mdem resume ID [--time-limit T] [--watch] [--json] [--db PATH] [connection flags]\n"
        "\n"
        "Queues a daemon's job that ended in TIMEOUT (its wall-time limit reached) again: it\n"
        "continues from the checkpoint it wrote when it stopped, to the same result as a run\n"
        "that was never stopped, with T more running time (its limit becomes its running time\n"
        "so far plus T). ID may be a prefix of a job in the local database, as for watch.\n"
        "\n"
        "Flags:\n"
     << kTimeLimitHelp
     << "  --watch              then follow the job until it ends (see `mdem watch --help`)\n"
        "  --reconnect-timeout S  with --watch: give up reconnecting after S seconds (default "
        "60)\n"
        "  --json               print one JSON object: job_id, state, reason, time_limit_s\n"
        "                       (with --watch: the final report, as `mdem watch --json`)\n"
     << kDbHelp << "  -h, --help           show this help\n"
     << kConnectionHelp << "\n"
     << kRemoteExitHelp;
}

// Prints the command's help when asked for, else runs its body, turning what it throws into a
// message prefixed with the command and an exit code.
template <class Help, class Body>
int guarded(const std::string& cmd, const std::vector<std::string>& args, std::ostream& out,
            std::ostream& err, Help&& print_help, Body&& body) {
  if (wants_help(args)) {
    print_help(out);
    return kOk;
  }
  const std::string name = "mdem " + cmd;
  try {
    return body();
  } catch (const spec::SpecError& e) {
    err << name << ": invalid job spec:\n"
        << describe_spec_error(e) << "Run '" << name << " --help' for the flags.\n";
    return kUsage;
  } catch (const SettingsError& e) {
    err << name << ": " << e.what() << "\nRun '" << name
        << " --help' for the connection settings.\n";
    return kUsage;
  } catch (const UsageError& e) {
    err << name << ": " << e.what() << "\nRun '" << name << " --help' for the flags.\n";
    return kUsage;
  } catch (const RemoteError& e) {
    err << name << ": " << e.what() << "\n";
    return e.exit_code;
  } catch (const std::exception& e) {
    err << name << ": error: " << e.what() << "\n";
    return kJobFailed;
  }
}

std::string db_path(const std::map<std::string, std::string>& given) {
  const auto it = given.find("--db");
  return it != given.end() ? it->second : ResultsStore::default_path();
}

// --time-limit as Slurm's --time takes it, in seconds; 0 when not given (the daemon's default).
double time_limit_flag(const std::map<std::string, std::string>& given) {
  const auto it = given.find("--time-limit");
  if (it == given.end()) return 0;
  try {
    return parse_time_limit(it->second, "--time-limit");
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
}

double reconnect_timeout(const std::map<std::string, std::string>& given) {
  const auto it = given.find("--reconnect-timeout");
  if (it == given.end()) return kDefaultReconnectTimeoutS;
  return parse_in_range("--reconnect-timeout", it->second, 0, 86400, "s");
}

}  // namespace

JobRecord record_of(const v1::JobInfo& info, const ConnectionSettings& settings,
                    const std::string& state) {
  JobRecord r;
  r.id = info.job_id();
  r.kind = info.kind().empty() ? std::string(job_kind_name(info.spec())) : info.kind();
  r.spec_json = info.has_spec() ? spec::to_json(info.spec(), false) : "{}";
  r.state = state;
  r.created_at = shown_time(info.created_at());
  r.server = settings.server;
  r.token_file = settings.token_file;  // watch and cancel use it again; the token is not stored
  return r;
}

namespace {

json info_json(const v1::JobInfo& info) {
  return json{
      {"job_id", info.job_id()},
      {"user", info.user()},
      {"kind", info.kind()},
      {"name", info.name()},
      {"state", job_state_name(info.state())},
      {"reason", info.reason()},
      {"created_at", shown_time(info.created_at())},
      {"started_at", shown_time(info.started_at())},
      {"finished_at", shown_time(info.finished_at())},
      {"elapsed_s", info.elapsed_s()},
      {"time_limit_s", info.time_limit_s()},
      {"job_data_peak_bytes", info.job_data_peak_bytes()},
      {"daemon_rss_peak_bytes", info.daemon_rss_peak_bytes()},
      {"elements", info.elements()},
      {"step", info.step()},
      {"total_steps", info.total_steps()},
      {"last_seq", info.last_seq()},
      {"resumes", info.resumes()},
      {"queue_position", info.queue_position()},
      {"waiting_for", info.waiting_for()},
      {"spec", info.has_spec() ? parse_or_text(spec::to_json(info.spec(), false)) : json(nullptr)},
      {"report", parse_or_text(info.report_json())}};
}

// ---- watch ------------------------------------------------------------------------------------

// Prints a finished job from the local database (its report, as text or JSON) and returns the
// exit code of its state.
int print_finished(const ResultsStore& store, const JobRecord& rec, bool as_json, std::ostream& out,
                   std::ostream& err) {
  json doc = parse_or_text(rec.summary_json);
  if (!doc.is_object()) {
    doc = json::object();
    doc["job_id"] = rec.id;
    doc["kind"] = rec.kind;
    doc["state"] = rec.state;
    if (!rec.reason.empty()) doc["reason"] = rec.reason;
  }
  if (!doc.contains("state")) doc["state"] = rec.state;
  if (!rec.server.empty()) doc["server"] = rec.server;
  doc["db"] = store.path();
  if (as_json) {
    write_json(out, doc);
    out << "\n";
  } else {
    print_report(out, err, doc, std::nullopt);
  }
  return parse_job_state(rec.state) == v1::SUCCEEDED ? kOk : kJobFailed;
}

// Follows one job's event stream into the local database. Events are applied in batches, each
// one transaction together with the sequence number of its last event (ResultsStore::
// apply_remote); a snapshot's chunks are held until the last one arrives, so a batch never ends
// inside a snapshot and a watch stopped at any moment resumes from its first chunk.
class Watcher {
 public:
  Watcher(JobClient& client, ResultsStore& store, std::string id, bool as_json,
          double reconnect_timeout_s, std::ostream& out, std::ostream& err)
      : client_(client),
        store_(store),
        id_(std::move(id)),
        json_(as_json),
        reconnect_timeout_s_(reconnect_timeout_s),
        out_(out),
        err_(err),
        progress_(err, is_terminal(err), as_json) {}

  int run() {
    committed_ = applied_ = store_.last_seq(id_);
    batch_.last_seq = committed_;
    const std::string& server = client_.settings().server;
    if (!json_)
      err_ << "watching " << id_ << " on " << server
           << (committed_ > 0 ? " from event " + std::to_string(committed_ + 1) : "")
           << " (Ctrl-C stops watching, not the job)\n";
    InterruptGuard interrupt;
    std::thread canceller([this] { cancel_on_interrupt(); });
    int code = kConnection;
    try {
      code = follow();
    } catch (...) {
      stop_canceller(canceller);
      throw;
    }
    stop_canceller(canceller);
    return code;
  }

 private:
  // A snapshot whose chunks are arriving.
  struct Assembly {
    long first_seq = 0, step = 0;
    int count = 0, next = 0;
    std::string bytes;
  };

  int follow() {
    const std::string& server = client_.settings().server;
    bool lost = false;  // since lost_since, without a stream that delivered events
    Clock::time_point lost_since;
    double backoff_s = 0.2;
    bool ever_connected = false;
    while (true) {
      grpc::Status status;
      bool got_events = false;
      {
        auto ctx = client_.stream_context();
        set_context(ctx.get());
        if (InterruptGuard::interrupted()) ctx->TryCancel();
        v1::WatchJobRequest request;
        request.set_job_id(id_);
        request.set_from_seq(committed_ + 1);
        applied_ = committed_;  // what was held back (a partial snapshot) comes again
        auto reader = client_.stub().WatchJob(ctx.get(), request);
        v1::JobEvent ev;
        while (reader->Read(&ev)) {
          if (!got_events && lost)
            progress_.note("reconnected to " + server + "; resuming from event " +
                           std::to_string(committed_ + 1));
          got_events = ever_connected = true;
          lost = false;
          backoff_s = 0.2;
          handle(ev);
        }
        status = reader->Finish();
        set_context(nullptr);
      }
      // Whatever ended the stream: a snapshot still missing chunks is not stored (the next
      // watch asks again from its first chunk), everything before it is.
      snapshot_.reset();
      flush();
      if (InterruptGuard::interrupted()) {
        progress_.finish();
        err_ << "stopped watching " << id_ << "; the job goes on on mdemd at " << server
             << " (`mdem watch " << id_ << "` resumes, `mdem cancel " << id_ << "` stops it)\n";
        return kInterrupted;
      }
      if (status.ok()) {
        if (const auto code = finish()) return *code;
        // The stream ended but the daemon says the job goes on: follow it again.
      } else {
        const bool retryable = status.error_code() == grpc::StatusCode::UNAVAILABLE ||
                               status.error_code() == grpc::StatusCode::CANCELLED;
        if (!retryable) {
          progress_.finish();
          throw RemoteError(describe_status(status, client_.settings()), status.error_code(),
                            exit_code_for(status.error_code()));
        }
      }
      if (!lost) {
        lost = true;
        lost_since = Clock::now();
        if (!status.ok())
          progress_.note((ever_connected ? "lost the connection to mdemd at " + server
                                         : "cannot reach mdemd at " + server + " yet") +
                         " (" + status.error_message() + "); " +
                         (ever_connected ? "reconnecting" : "retrying") + " for up to " +
                         seconds_text(reconnect_timeout_s_) + "...");
      }
      const double lost_s = std::chrono::duration<double>(Clock::now() - lost_since).count();
      if (lost_s >= reconnect_timeout_s_) {
        progress_.finish();
        if (!ever_connected && !status.ok())
          err_ << "mdem watch: " << describe_status(status, client_.settings())
               << "\nmdem watch: gave up after " << seconds_text(lost_s)
               << " (--reconnect-timeout); `mdem watch " << id_ << "` tries again\n";
        else
          err_ << "mdem watch: gave up after " << seconds_text(lost_s) << " without mdemd at "
               << server << (status.ok() ? "" : " (" + status.error_message() + ")")
               << "; everything received is stored, and the job goes on there: `mdem watch " << id_
               << "` resumes\n";
        return kConnection;
      }
      wait_to_reconnect(std::min(backoff_s, reconnect_timeout_s_ - lost_s));
      backoff_s = std::min(backoff_s * 2, 5.0);
    }
  }

  // After a stream that ended OK: the job should be over. Returns the exit code then, or
  // nullopt when the daemon says it is not (the caller follows it again).
  std::optional<int> finish() {
    std::optional<JobRecord> rec = store_.find(id_);
    if (!rec) throw StoreError("job '" + id_ + "' vanished from " + store_.path());
    if (!is_final(rec->state) || rec->summary_json.empty()) {
      // A job cancelled while queued has no report; a daemon may end a stream early. Ask it.
      const v1::JobInfo info = client_.get(id_);
      const std::string state = job_state_name(info.state());
      if (is_final(state)) {
        RemoteUpdate u;
        u.last_seq = committed_;
        if (!is_final(rec->state)) {
          u.state = state;
          u.reason = info.reason();
          u.finished_at = shown_time(info.finished_at());
        }
        if (rec->summary_json.empty() && !info.report_json().empty())
          u.report_json = info.report_json();
        store_.apply_remote(id_, u);
        rec = store_.find(id_);
      } else if (!is_final(rec->state)) {
        return std::nullopt;
      }
    }
    progress_.finish();
    if (coalesced_frames_ + coalesced_snapshots_ > 0 && !json_)
      err_ << "note: the daemon skipped " << coalesced_frames_ << " frame(s) and "
           << coalesced_snapshots_ << " snapshot(s) of this job in all\n";
    return print_finished(store_, *rec, json_, out_, err_);
  }

  void handle(const v1::JobEvent& ev) {
    const long seq = ev.seq();
    if (seq <= applied_) return;  // seen already (a daemon resending): never applied twice
    if (seq > applied_ + 1 && applied_ > 0)
      progress_.note("warning: events " + std::to_string(applied_ + 1) + ".." +
                     std::to_string(seq - 1) + " of " + id_ + " did not arrive");
    applied_ = seq;
    if (snapshot_ && ev.event_case() != v1::JobEvent::kSnapshot) drop_snapshot("interrupted");
    switch (ev.event_case()) {
      case v1::JobEvent::kState: {
        const std::string state = job_state_name(ev.state().state());
        batch_.state = state;
        batch_.reason = ev.state().reason();
        if (is_final(state)) batch_.finished_at = shown_time(ev.time());
        if (!json_)
          progress_.note(id_ + ": " + state +
                         (ev.state().reason().empty() ? "" : " (" + ev.state().reason() + ")"));
        mark(seq, true);
        break;
      }
      case v1::JobEvent::kProgress: {
        const v1::Progress& p = ev.progress();
        progress_(JobProgress{p.step(), p.total_steps(), p.time_ps(), p.phase()});
        mark(seq, false);
        break;
      }
      case v1::JobEvent::kColumns:
        batch_.columns =
            std::vector<std::string>(ev.columns().names().begin(), ev.columns().names().end());
        mark(seq, true);
        break;
      case v1::JobEvent::kFrame: {
        const v1::EnergyFrame& f = ev.frame();
        batch_.frames.push_back(SeriesFrame{
            f.step(), f.time_ps(), std::vector<double>(f.values().begin(), f.values().end())});
        mark(seq, batch_.frames.size() >= kFrameBatch);
        break;
      }
      case v1::JobEvent::kSnapshot:
        chunk(seq, ev.snapshot());
        break;
      case v1::JobEvent::kLog:
        if (!json_ || ev.log().level() != "info")
          progress_.note("[" + ev.log().level() + "] " + ev.log().text());
        mark(seq, false);
        break;
      case v1::JobEvent::kReport: {
        batch_.report_json = ev.report().json();
        const json doc = json::parse(ev.report().json(), nullptr, false);
        if (doc.is_object() && doc.contains("state") && doc["state"].is_string() &&
            is_final(doc["state"].get<std::string>())) {
          batch_.state = doc["state"].get<std::string>();
          batch_.reason = doc.contains("reason") && doc["reason"].is_string()
                              ? doc["reason"].get<std::string>()
                              : "";
          if (batch_.finished_at.empty()) batch_.finished_at = shown_time(ev.time());
        }
        mark(seq, true);
        break;
      }
      case v1::JobEvent::kCoalesced: {
        const v1::Coalesced& c = ev.coalesced();
        coalesced_frames_ += c.frames();
        coalesced_snapshots_ += c.snapshots();
        progress_.note("daemon skipped " + std::to_string(c.frames()) + " frames, " +
                       std::to_string(c.snapshots()) + " snapshots up to step " +
                       std::to_string(c.up_to_step()) +
                       " (its event log fell behind the job; the job was not slowed)");
        mark(seq, false);
        break;
      }
      default:  // an event this mdem does not know: skipped
        mark(seq, false);
        break;
    }
  }

  void chunk(long seq, const v1::SnapshotChunk& c) {
    if (c.count() <= 0 || c.index() < 0 || c.index() >= c.count()) {
      drop_snapshot("malformed chunk");
      progress_.note("warning: malformed snapshot chunk (event " + std::to_string(seq) +
                     "); skipped");
      mark(seq, false);
      return;
    }
    if (c.index() == 0) {
      if (snapshot_) drop_snapshot("a new one began");
      flush();  // everything before the snapshot; a resume starts at its first chunk
      snapshot_ = Assembly{seq, c.step(), c.count(), 0, {}};
    }
    if (!snapshot_ || c.index() != snapshot_->next || c.count() != snapshot_->count ||
        c.step() != snapshot_->step) {
      drop_snapshot("chunks out of order");
      progress_.note("warning: snapshot chunk " + std::to_string(c.index() + 1) + " of " +
                     std::to_string(c.count()) + " at step " + std::to_string(c.step()) +
                     " arrived out of order; skipped");
      mark(seq, false);
      return;
    }
    snapshot_->bytes += c.data();
    if (++snapshot_->next < snapshot_->count) return;  // not marked: resume from the first chunk
    v1::SnapshotData data;
    const long step = snapshot_->step;
    const bool parsed = data.ParseFromString(snapshot_->bytes);
    snapshot_.reset();
    try {
      if (!parsed) throw std::invalid_argument("not a SnapshotData message");
      batch_.snapshots.push_back(snapshot_from_proto(data));
    } catch (const std::invalid_argument& e) {
      progress_.note("warning: the snapshot at step " + std::to_string(step) + " cannot be read (" +
                     e.what() + "); skipped");
    }
    mark(seq, true);
  }

  void drop_snapshot(const std::string& why) {
    if (!snapshot_) return;
    progress_.note("warning: the snapshot at step " + std::to_string(snapshot_->step) +
                   " is incomplete (" + std::to_string(snapshot_->next) + " of " +
                   std::to_string(snapshot_->count) + " chunks; " + why + "); skipped");
    snapshot_.reset();
  }

  // The batch now covers the events up to seq; store it when `now` or when it has waited long.
  void mark(long seq, bool now) {
    batch_.last_seq = seq;
    if (now || Clock::now() - last_flush_ >= kFlushInterval) flush();
  }

  void flush() {
    last_flush_ = Clock::now();
    if (batch_.last_seq <= committed_) return;
    store_.apply_remote(id_, batch_);
    committed_ = batch_.last_seq;
    batch_ = RemoteUpdate{};
    batch_.last_seq = committed_;
  }

  // Ctrl-C: the signal handler only sets a flag; this thread cancels the stream's call.
  void cancel_on_interrupt() {
    std::unique_lock lock(mu_);
    while (!stop_) {
      if (InterruptGuard::interrupted() && ctx_) ctx_->TryCancel();
      cv_.wait_for(lock, std::chrono::milliseconds(50));
    }
  }
  void stop_canceller(std::thread& t) {
    {
      std::lock_guard lock(mu_);
      stop_ = true;
    }
    cv_.notify_all();
    t.join();
  }
  void set_context(grpc::ClientContext* ctx) {
    std::lock_guard lock(mu_);
    ctx_ = ctx;
  }

  // Waits up to s seconds before the next attempt, ending early (after at least 0.2 s) once the
  // channel connects, so a daemon that comes back is followed at once, not at the end of a
  // backoff; Ctrl-C ends the wait.
  void wait_to_reconnect(double s) {
    const auto start = Clock::now();
    const auto until = start + std::chrono::duration<double>(std::max(0.0, s));
    const auto least = start + std::chrono::milliseconds(200);
    while (Clock::now() < until && !InterruptGuard::interrupted()) {
      if (Clock::now() >= least &&
          client_.wait_connected(std::chrono::system_clock::now() + std::chrono::milliseconds(50)))
        return;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  static std::string seconds_text(double s) {
    std::ostringstream o;
    o << static_cast<long>(s + 0.5) << " s";
    return o.str();
  }

  JobClient& client_;
  ResultsStore& store_;
  const std::string id_;
  const bool json_;
  const double reconnect_timeout_s_;
  std::ostream& out_;
  std::ostream& err_;
  ProgressReporter progress_;

  long committed_ = 0;  // the last event stored (with its data) in the database
  long applied_ = 0;    // the last event handled (stored, in the batch, or in `snapshot_`)
  RemoteUpdate batch_;
  std::optional<Assembly> snapshot_;
  Clock::time_point last_flush_ = Clock::now();
  long coalesced_frames_ = 0, coalesced_snapshots_ = 0;

  std::mutex mu_;
  std::condition_variable cv_;
  grpc::ClientContext* ctx_ = nullptr;
  bool stop_ = false;
};

// ---- the commands -----------------------------------------------------------------------------

int run_submit(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (args.empty() || args.front().rfind("-", 0) == 0)
    throw UsageError("missing the job kind (allowed: " + spec_kind_names() +
                     "), e.g. `mdem submit twist --layers 4`");
  const SpecKind* kind = find_spec_kind(args.front());
  if (!kind)
    throw UsageError("unknown job kind '" + args.front() + "' (allowed: " + spec_kind_names() +
                     ")");
  FlagSpec fs = spec_flag_spec(*kind);
  fs.with_value.insert(fs.with_value.end(),
                       {"--request-id", "--db", "--reconnect-timeout", "--time-limit"});
  fs.switches.insert(fs.switches.end(), {"--watch", "--json"});
  add_connection_flags(fs);
  const auto given = parse_flags({args.begin() + 1, args.end()}, fs);
  const v1::JobSpec spec = spec_from_flags(*kind, given);
  const bool as_json = given.count("--json") > 0, follow = given.count("--watch") > 0;
  std::string request_id;
  if (given.count("--request-id")) {
    request_id = given.at("--request-id");
    check_request_id(request_id);
  } else {
    request_id = new_request_id();
  }
  const double timeout = reconnect_timeout(given);
  const double time_limit_s = time_limit_flag(given);
  ConnectionSettings settings = resolve_connection(given, process_env());
  ResultsStore store(db_path(given));  // before submitting: a job is never left unrecorded

  if (!as_json)
    err << "submitting a " << kind->name << " job to mdemd at " << settings.server
        << " (request id " << request_id << ")\n";
  JobClient client(settings);
  v1::SubmitJobRequest request;
  request.set_request_id(request_id);
  *request.mutable_spec() = spec;
  request.set_time_limit_s(time_limit_s);
  v1::SubmitJobResponse response;
  try {
    response = client.submit(request);
  } catch (const RemoteError& e) {
    if (e.exit_code != kConnection) throw;
    throw RemoteError(std::string(e.what()) + "\nIf it was queued after all, retrying with " +
                          "--request-id " + request_id + " does not queue it twice.",
                      e.code, e.exit_code);
  }
  const v1::JobInfo& info = response.job();
  JobRecord rec = record_of(info, settings, job_state_name(info.state()));
  if (!info.has_spec()) rec.spec_json = spec::to_json(spec, false);
  if (rec.kind.empty()) rec.kind = kind->name;
  store.upsert_remote_job(rec);

  if (as_json && !follow) {
    write_json(out, json{{"job_id", info.job_id()},
                         {"request_id", request_id},
                         {"created", response.created()},
                         {"state", job_state_name(info.state())},
                         {"server", settings.server},
                         {"db", store.path()}});
    out << "\n";
    return kOk;
  }
  if (!as_json) {
    out << info.job_id() << "\n" << std::flush;
    err << (response.created() ? "queued " : "already submitted with this request id: ")
        << info.job_id() << " (" << job_state_name(info.state()) << ")";
    if (!follow) err << "; follow it with `mdem watch " << info.job_id() << "`";
    err << "\n";
  }
  if (!follow) return kOk;
  return Watcher(client, store, info.job_id(), as_json, timeout, out, err).run();
}

// The job `id` (or a unique prefix) names in the local database; nullopt when none; UsageError for
// an ambiguous prefix.
std::optional<JobRecord> recorded_job(const ResultsStore& store, const std::string& id) {
  try {
    return store.find(id);
  } catch (const StoreError& e) {  // an ambiguous prefix
    throw UsageError(e.what());
  }
}

int run_resume_timeout(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  FlagSpec fs{{"--db", "--reconnect-timeout", "--time-limit"}, {"--json", "--watch"}};
  add_connection_flags(fs);
  auto [given_id, given] = parse_id_and_flags(args, fs);
  const bool as_json = given.count("--json") > 0, follow = given.count("--watch") > 0;
  const double grant_s = time_limit_flag(given);
  const double timeout = reconnect_timeout(given);
  ResultsStore store(db_path(given));
  std::optional<JobRecord> rec = recorded_job(store, given_id);
  if (rec && rec->server.empty())
    throw UsageError("job '" + rec->id + "' in " + store.path() +
                     " ran in a process of its own (`mdem run`), not on a daemon; only a "
                     "daemon's job ends in TIMEOUT");
  const ConnectionSettings settings =
      resolve_connection(given, process_env(), rec ? rec->server : "", rec ? rec->token_file : "");
  JobClient client(settings);
  const v1::JobInfo info = client.resume(rec ? rec->id : given_id, grant_s);
  if (rec)
    store.set_state(info.job_id(), job_state_name(info.state()), info.reason());
  else
    store.upsert_remote_job(record_of(info, settings, job_state_name(info.state())));
  if (as_json && !follow) {
    write_json(out, json{{"job_id", info.job_id()},
                         {"state", job_state_name(info.state())},
                         {"reason", info.reason()},
                         {"time_limit_s", info.time_limit_s()}});
    out << "\n";
    return kOk;
  }
  if (!as_json)
    err << "queued " << info.job_id() << " again: " << info.reason()
        << (follow ? "" : "; follow it with `mdem watch " + info.job_id() + "`") << "\n";
  if (!follow) return kOk;
  return Watcher(client, store, info.job_id(), as_json, timeout, out, err).run();
}

int run_watch(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  FlagSpec fs{{"--db", "--reconnect-timeout"}, {"--json"}};
  add_connection_flags(fs);
  auto [given_id, given] = parse_id_and_flags(args, fs);
  const bool as_json = given.count("--json") > 0;
  const double timeout = reconnect_timeout(given);
  ResultsStore store(db_path(given));
  std::optional<JobRecord> rec = recorded_job(store, given_id);
  if (rec && rec->server.empty()) {
    if (is_final(rec->state)) return print_finished(store, *rec, as_json, out, err);
    throw UsageError("job '" + rec->id + "' in " + store.path() +
                     " runs in a process of its own (`mdem run`), not on a daemon: there is "
                     "nothing to watch (see `mdem show " +
                     rec->id + "`)");
  }
  if (rec && is_final(rec->state) && !rec->summary_json.empty())
    return print_finished(store, *rec, as_json, out, err);  // everything is here already

  const ConnectionSettings settings =
      resolve_connection(given, process_env(), rec ? rec->server : "", rec ? rec->token_file : "");
  JobClient client(settings);
  std::string id = rec ? rec->id : given_id;
  if (!rec) {
    const v1::JobInfo info = client.get(id);
    id = info.job_id();
    store.upsert_remote_job(record_of(info, settings));
  }
  return Watcher(client, store, id, as_json, timeout, out, err).run();
}

int run_cancel(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  FlagSpec fs{{"--db"}, {"--json"}};
  add_connection_flags(fs);
  auto [given_id, given] = parse_id_and_flags(args, fs);
  const std::string path = db_path(given);
  std::unique_ptr<ResultsStore> store;
  std::optional<JobRecord> rec;
  std::error_code ec;
  if (fs::exists(path, ec)) {
    store = std::make_unique<ResultsStore>(path);
    try {
      rec = store->find(given_id);
    } catch (const StoreError&) {  // an ambiguous prefix: the daemon decides
    }
    if (rec && rec->server.empty()) rec.reset();  // a job of `mdem run`, not the daemon's
  }
  const ConnectionSettings settings =
      resolve_connection(given, process_env(), rec ? rec->server : "", rec ? rec->token_file : "");
  JobClient client(settings);
  const v1::JobInfo info = client.cancel(rec ? rec->id : given_id);
  const std::string state = job_state_name(info.state());
  if (rec && !is_final(rec->state) && is_final(state))
    store->set_state(rec->id, state, info.reason());
  if (given.count("--json")) {
    write_json(out, json{{"job_id", info.job_id()}, {"state", state}, {"reason", info.reason()}});
    out << "\n";
    return kOk;
  }
  if (parse_job_state(state) == v1::CANCELLED && info.started_at().empty())
    out << "cancelled " << info.job_id() << " before it started; it produced nothing\n";
  else if (parse_job_state(state) == v1::CANCELLED)
    out << "cancelled " << info.job_id() << "; what it produced is kept (`mdem watch "
        << info.job_id() << "` fetches it)\n";
  else if (is_final(state))
    out << info.job_id() << " had already finished (" << state << "); nothing to cancel\n";
  else
    out << "cancelling " << info.job_id() << " (" << state << "; it stops within a second)\n";
  return kOk;
}

// Running time of a job as Slurm's sacct prints Elapsed ([D-]HH:MM:SS): queue time not
// counted, every run and resume added up; "-" before it first ran.
std::string elapsed_text(const v1::JobInfo& info) {
  return info.started_at().empty() ? "-" : duration_text(info.elapsed_s());
}

// Its wall-time limit ([D-]HH:MM:SS), "none" without one.
std::string time_limit_text(const v1::JobInfo& info) {
  return info.time_limit_s() > 0 ? duration_text(info.time_limit_s()) : "none";
}

// Bytes in kB, MB or GB (powers of 1000); "-" for 0 (not measured).
std::string bytes_text(long bytes) {
  if (bytes <= 0) return "-";
  char buf[32];
  const double b = static_cast<double>(bytes);
  if (b < 1e6)
    std::snprintf(buf, sizeof buf, "%.1f kB", b / 1e3);
  else if (b < 1e9)
    std::snprintf(buf, sizeof buf, "%.1f MB", b / 1e6);
  else
    std::snprintf(buf, sizeof buf, "%.2f GB", b / 1e9);
  return buf;
}

// Memory as sacct's MaxRSS would mean it for a job of its own, named for what it is: the peak of
// the job's simulation data, and the daemon's (all jobs') peak resident set for context.
std::string memory_text(const v1::JobInfo& info) {
  if (info.job_data_peak_bytes() <= 0 && info.daemon_rss_peak_bytes() <= 0) return "-";
  return "job data peak " + bytes_text(info.job_data_peak_bytes()) + "; daemon RSS peak " +
         bytes_text(info.daemon_rss_peak_bytes());
}

std::string progress_text(const v1::JobInfo& info) {
  if (info.total_steps() <= 0) return "-";
  return std::to_string(info.step() * 100 / info.total_steps()) + "%";
}

std::string note_text(const v1::JobInfo& info) {
  std::string text = info.name();
  if (info.queue_position() > 0)  // why it waits, as squeue's REASON column
    text += (text.empty() ? "" : "; ") + std::string("#") + std::to_string(info.queue_position()) +
            " in queue: " + info.waiting_for();
  else if (!info.reason().empty())
    text += (text.empty() ? "" : "; ") + info.reason();
  constexpr std::size_t kMax = 60;
  return text.size() > kMax ? text.substr(0, kMax - 3) + "..." : text;
}

// The daemon's id of the job that `id` names: the id itself, or the one of the caller's jobs on
// the daemon whose id starts with it (UsageError when several do; the daemon's NOT_FOUND when
// none does).
std::string daemon_job_id(JobClient& client, const std::string& id) {
  try {
    return client.get(id).job_id();
  } catch (const RemoteError& e) {
    if (e.code != grpc::StatusCode::NOT_FOUND) throw;
    std::vector<std::string> matches;
    const v1::ListJobsResponse mine = client.list(false, 1000);
    for (const v1::JobInfo& info : mine.jobs())
      if (info.job_id().rfind(id, 0) == 0) matches.push_back(info.job_id());
    if (matches.empty()) throw;
    if (matches.size() > 1) {
      std::string list;
      for (const std::string& m : matches) list += (list.empty() ? "" : ", ") + m;
      throw UsageError("job id prefix '" + id + "' names " + std::to_string(matches.size()) +
                       " jobs on mdemd at " + client.settings().server + " (" + list +
                       "): give more of the id");
    }
    return matches.front();
  }
}

}  // namespace

int remote_ls(const std::map<std::string, std::string>& given, std::ostream& out,
              std::ostream& err) {
  const int limit = given.count("--limit")
                        ? static_cast<int>(parse_integer("--limit", given.at("--limit"), 1, 1000))
                        : 0;
  const bool all = given.count("--all") > 0;
  JobClient client(resolve_connection(given, process_env()));
  const v1::ListJobsResponse response = client.list(all, limit);
  if (given.count("--json")) {
    json jobs = json::array();
    for (const v1::JobInfo& info : response.jobs()) jobs.push_back(info_json(info));
    out << jobs.dump(2) << '\n';
    return kOk;
  }
  if (response.jobs().empty()) {
    err << "no jobs on mdemd at " << client.settings().server << '\n';
    return kOk;
  }
  std::vector<std::vector<std::string>> rows;
  rows.push_back({"ID"});
  if (all) rows.back().push_back("USER");
  rows.back().insert(rows.back().end(), {"KIND", "STATE", "CREATED", "ELAPSED", "LIMIT", "MEM",
                                         "DONE", "NAME / REASON"});
  for (const v1::JobInfo& info : response.jobs()) {
    rows.push_back({info.job_id()});
    if (all) rows.back().push_back(info.user());
    rows.back().insert(
        rows.back().end(),
        {info.kind(), job_state_name(info.state()), shown_time(info.created_at()),
         elapsed_text(info), time_limit_text(info), bytes_text(info.job_data_peak_bytes()),
         progress_text(info), note_text(info)});
  }
  print_table(out, rows);
  return kOk;
}

int remote_show(const std::string& id, const std::map<std::string, std::string>& given,
                std::ostream& out, std::ostream& err) {
  // A job recorded here (an id or a prefix, as `mdem watch` takes) brings its token file.
  std::optional<JobRecord> rec;
  try {
    const std::string path = ResultsStore::default_path();
    if (std::error_code ec; fs::exists(path, ec)) rec = ResultsStore(path).find(id);
  } catch (const StoreError&) {  // ambiguous or unreadable here: the daemon decides
  }
  ConnectionSettings settings =
      resolve_connection(given, process_env(), rec ? rec->server : "", rec ? rec->token_file : "");
  if (rec && rec->server != settings.server) {  // another daemon's job of the same prefix
    rec.reset();
    settings = resolve_connection(given, process_env());
  }
  JobClient client(settings);
  const v1::JobInfo info = client.get(rec ? rec->id : daemon_job_id(client, id));
  if (given.count("--json")) {
    json j = info_json(info);
    j["server"] = client.settings().server;
    write_json(out, j);
    out << '\n';
    return kOk;
  }
  std::vector<std::vector<std::string>> rows = {{"id:", info.job_id()},
                                                {"server:", client.settings().server},
                                                {"user:", info.user()},
                                                {"kind:", info.kind()},
                                                {"state:", job_state_name(info.state())}};
  if (!info.name().empty()) rows.push_back({"name:", info.name()});
  if (!info.reason().empty()) rows.push_back({"reason:", info.reason()});
  if (info.queue_position() > 0)
    rows.push_back({"waiting:", "position " + std::to_string(info.queue_position()) +
                                    " in the queue; " + info.waiting_for()});
  rows.push_back({"created:", shown_time(info.created_at())});
  rows.push_back({"started:", info.started_at().empty() ? "-" : shown_time(info.started_at())});
  rows.push_back({"finished:", info.finished_at().empty() ? "-" : shown_time(info.finished_at())});
  rows.push_back({"elapsed:", elapsed_text(info) + " (running time)"});
  rows.push_back({"time limit:", time_limit_text(info)});
  rows.push_back({"memory:", memory_text(info)});
  rows.push_back({"progress:", std::to_string(info.step()) + " / " +
                                   std::to_string(info.total_steps()) + " steps"});
  rows.push_back({"elements:", std::to_string(info.elements())});
  rows.push_back({"events:", std::to_string(info.last_seq())});
  if (info.resumes() > 0) rows.push_back({"resumes:", std::to_string(info.resumes())});
  print_table(out, rows);
  out << "spec:\n";
  if (info.has_spec())
    write_json(out, parse_or_text(spec::to_json(info.spec(), false)));
  else
    out << "  (none)";
  out << "\nreport:\n";
  if (info.report_json().empty())
    out << "  (none yet; `mdem watch " << info.job_id() << "` fetches the results)";
  else
    write_json(out, parse_or_text(info.report_json()));
  out << '\n';
  return kOk;
}

int submit(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  return guarded(
      "submit", args, out, err, [&](std::ostream& os) { print_submit_help(args, os); },
      [&] { return run_submit(args, out, err); });
}

int watch(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (names_study(args) && !wants_help(args)) return watch_study(args, out, err);
  return guarded("watch", args, out, err, print_watch_help,
                 [&] { return run_watch(args, out, err); });
}

int resume_remote(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  return guarded("resume", args, out, err, print_resume_help,
                 [&] { return run_resume_timeout(args, out, err); });
}

int cancel(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (names_study(args) && !wants_help(args)) return cancel_study(args, out, err);
  return guarded("cancel", args, out, err, print_cancel_help,
                 [&] { return run_cancel(args, out, err); });
}

}  // namespace mdem::cli
