#pragma once
// The local results database (SQLite): every job run by `mdem` with its spec, state, summary,
// time series and snapshots. One file per user by default; `--db PATH` picks another.
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/observe/snapshot.h"

namespace mdem::cli {

// A database that cannot be opened, created, read or written; the message names the file and
// what went wrong (exit code kJobFailed for commands, never a crash).
struct StoreError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct JobRecord {
  std::string id;            // e.g. "j-20261124-153012-3f9a" (unique, sortable by creation)
  std::string kind;          // "twist", "bundle", ...
  std::string spec_json;     // the full job spec, Protobuf JSON mapping, defaults filled in
  std::string state;         // QUEUED | RUNNING | SUCCEEDED | FAILED | CANCELLED, or (read
                             // only, never stored) INTERRUPTED: see ResultsStore::list
  std::string reason;        // why it failed (empty otherwise)
  std::string summary_json;  // the final JSON document `--json` prints ("" until finished)
  std::string created_at;    // ISO 8601 UTC
  std::string finished_at;   // ISO 8601 UTC, "" while running
  std::string server;        // the mdemd (HOST:PORT) that runs it; "" for a job run in-process
  long last_seq = 0;         // of a daemon's job: the last event applied here (0: none yet)
  std::string runner;        // of a job run in-process: "HOST BOOT-ID PID START-TIME" of the
                             // process that runs it (set by create_job); "" when unknown
  std::string token_file;    // of a daemon's job: the token file (absolute path, never the
                             // token) it was submitted or first watched with; "" when none
};

// Events of a daemon's job (mdem watch) applied together, in one transaction with the sequence
// number of the last event they cover, so that a watcher stopped at any moment resumes from
// last_seq + 1 with no gap and no duplicate.
struct RemoteUpdate {
  std::optional<std::vector<std::string>> columns;  // SeriesColumns (before any frame)
  std::vector<SeriesFrame> frames;
  std::vector<Snapshot> snapshots;
  std::optional<std::string> state;        // the latest state (a StateChange or the report's state)
  std::string reason;                      // with `state`
  std::string finished_at;                 // when `state` is final: the event's time ("" = now)
  std::optional<std::string> report_json;  // the FinalReport, stored as summary_json
  long last_seq = 0;                       // the last event covered (must not go down)
};

// Calls on one ResultsStore are serialised (safe from several threads); several processes may
// share a file (WAL; a writer waits up to 10 s for another's transaction).
class ResultsStore {
 public:
  // Opens (creating the file, its parent directories and the schema if needed) the database at
  // `path`. WAL mode. Throws StoreError.
  explicit ResultsStore(const std::string& path);
  ~ResultsStore();
  ResultsStore(const ResultsStore&) = delete;
  ResultsStore& operator=(const ResultsStore&) = delete;

  // $MDEM_DB if set, else $XDG_DATA_HOME/mdem/results.db, else $HOME/.local/share/mdem/results.db.
  static std::string default_path();
  const std::string& path() const;

  // A new unique job id.
  static std::string new_job_id();

  // State as given (normally RUNNING). A RUNNING job of no daemon is recorded as run by this
  // process (JobRecord::runner; job.runner is ignored).
  void create_job(const JobRecord& job);
  void finish_job(const std::string& id, const std::string& state, const std::string& reason,
                  const std::string& summary_json);
  // A job run in-process taken up again by `mdem run --resume` (this process): the frames and
  // snapshots past the first `frames` and `snapshots` (in the order written) are deleted - what
  // the run stored after its checkpoint, which the resumed run stores again - and the job is
  // RUNNING again, run by this process, with no reason, summary or finish time; one transaction.
  // StoreError for an unknown job or fewer rows than asked to keep.
  void resume_job(const std::string& id, std::size_t frames, std::size_t snapshots);
  // Sets the state and reason only (not the summary; finished_at only cleared, for a state
  // that has not ended: a daemon's TIMEOUT job queued again by `mdem resume`).
  void set_state(const std::string& id, const std::string& state, const std::string& reason);

  // A daemon's job (job.server set): inserted when new; when the id exists, its kind, spec,
  // server and creation time (and its token file, when job.token_file is set) are updated and its
  // state, results and last_seq are kept.
  void upsert_remote_job(const JobRecord& job);
  // The last event of a daemon's job applied here (0: none; StoreError for an unknown job).
  long last_seq(const std::string& id) const;
  void set_last_seq(const std::string& id, long seq);
  // Applies columns, frames, snapshots, the state and the report, and records u.last_seq, in one
  // transaction: all of it or (on any error) nothing. StoreError when u.last_seq is below the
  // job's last_seq (events applied twice).
  void apply_remote(const std::string& id, const RemoteUpdate& u);
  // Column names of the job's series (set once, before the first frame).
  void set_columns(const std::string& id, const std::vector<std::string>& columns);
  // Appends frames / a snapshot (each call one transaction; values must be finite: a non-finite
  // value throws StoreError naming the column, so nothing non-finite is ever written).
  void append_frames(const std::string& id, const std::vector<SeriesFrame>& frames);
  void append_snapshot(const std::string& id, const Snapshot& snap);

  // All jobs, newest first. A RUNNING job of no daemon whose process is gone without finishing
  // it (kill -9, a crash, a reboot; known for processes of this host) reads as INTERRUPTED, with
  // a reason naming the process; nothing is written (the database may be read-only). find()
  // alike.
  std::vector<JobRecord> list() const;
  // The job with this id, or the only job whose id starts with `id_or_prefix`; nullopt when
  // none; StoreError when the prefix is ambiguous.
  std::optional<JobRecord> find(const std::string& id_or_prefix) const;
  std::vector<std::string> columns(const std::string& id) const;
  std::vector<SeriesFrame> frames(const std::string& id) const;
  std::size_t frame_count(const std::string& id) const;
  std::size_t snapshot_count(const std::string& id) const;
  std::vector<Snapshot> snapshots(const std::string& id) const;
  // The k-th snapshot (0-based, in the order written), or nullopt past the end: lets a reader go
  // through a long job one snapshot at a time instead of holding all of them in memory.
  std::optional<Snapshot> snapshot(const std::string& id, std::size_t k) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mdem::cli
