#pragma once
// The daemon's single source of truth (service.md "Durability"): one SQLite database in WAL mode
// holding every job, its state and its sequenced event log. Every change of state is written in
// the same transaction as the event that announces it, so the log and the jobs table never
// disagree, and reconcile() makes them consistent with "nothing is running" after a restart.
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/event_order.h"  // event_order: frames and snapshots by (stage, step)
#include "mdem/job_state.h"
#include "mdem/sqlite_db.h"
#include "mdem/v1/service.pb.h"

namespace mdem::server {

// A per-user limit refused a submit; the message names the limit.
struct LimitError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct JobRow {
  std::string id, user, request_id, kind, name;
  v1::JobSpec spec;  // finalized
  v1::JobState state = v1::QUEUED;
  std::string reason;
  std::string created_at, started_at, finished_at;
  long elements = 0, total_steps = 0, step = 0, last_seq = 0;
  int threads = 1;  // fixed at submit: a resumed run must use the same count to be bit-identical
  int resumes = 0;
  long checkpoint_step = 0;  // 0: no checkpoint
  double wall_s = 0;         // running time up to the checkpoint (at the end: in all)
  double time_limit_s = 0;   // limit on wall_s, every run added up; 0 = none
  long peak_bytes = 0;       // the job's data at its peak (System::memory_bytes), as last recorded
  long daemon_rss_peak_bytes = 0;  // the daemon's peak resident set then (getrusage)
  // The last frame and snapshot logged, as event_order(stage, step); the last progress step
  // (progress counts steps over all stages).
  long last_frame_step = -1, last_snapshot_step = -1, last_progress_step = -1;
  bool columns_logged = false;
  std::string report_json;
  v1::StudyRun study;  // empty study_id: a lone job

  // Ended (TIMEOUT included: only a ResumeJob queues it again).
  bool finished() const { return is_final(state); }
  v1::JobInfo info() const;
};

struct SubmitResult {
  JobRow job;
  bool created = false;
};

// A job's id and its user.
struct JobOwner {
  std::string id, user;
};

class JobStore {
 public:
  // Opens or creates the database (synchronous=FULL: an accepted job survives power loss too).
  // Throws SqliteError naming the file.
  explicit JobStore(const std::string& path);

  // Queues a job, or returns the one this (user, request_id) created before. Throws LimitError
  // when the user already has max_active queued or running jobs. study: the study the job is a
  // run of (empty study_id: none), kept with the job and listed by list().
  SubmitResult submit(const std::string& user, const std::string& request_id,
                      const v1::JobSpec& spec, const v1::StudyRun& study, const std::string& kind,
                      long elements, long total_steps, int threads, long max_active,
                      double time_limit_s = 0);
  std::optional<JobRow> get(const std::string& id);
  // Newest first; user empty = everyone's; study_id empty = every job, else that study's.
  std::vector<JobRow> list(const std::string& user, int limit, const std::string& study_id = "");

  // After a restart: every RUNNING job goes back to QUEUED (a state event says from which
  // checkpoint it will resume). Returns their ids.
  std::vector<std::string> reconcile();
  // The next job to run, marked RUNNING: among queued jobs, those of the user with the fewest
  // running jobs, ties to the user who least recently started one, then the oldest job.
  std::optional<JobRow> claim_next();
  // The ids of the queued jobs in the order claim_next takes them (the queue, first to run
  // first), and of the running jobs in the order they started.
  std::vector<JobOwner> queue();
  std::vector<JobOwner> running();
  // Cancels a job that is still queued; false when it is not queued.
  bool cancel_queued(const std::string& id, const std::string& reason);

  // Appends events in one transaction and returns the last sequence number. A StateChange also
  // sets the job's state and reason (and started/finished times), a FinalReport its report, and
  // frames, snapshots, progress and columns advance what the job has logged. The events get
  // their seq and time (set again by a retry when the transaction failed).
  long append(const std::string& job_id, std::vector<v1::JobEvent>& events);
  // Events with seq >= from_seq, in order: at most max_count, and stopping once max_bytes is
  // exceeded (at least one event is returned when any exists).
  std::vector<v1::JobEvent> events(const std::string& job_id, long from_seq, int max_count,
                                   std::size_t max_bytes);
  // Records that a checkpoint of the job at `step` is on disk, with its running time then.
  void set_checkpoint(const std::string& job_id, long step, double wall_s);
  // Records the job's running time and memory peaks (each peak only raised, never lowered).
  void set_usage(const std::string& job_id, double wall_s, long peak_bytes,
                 long daemon_rss_peak_bytes);
  // Queues a TIMEOUT job again (a state event with `reason`), its limit becoming its running time
  // so far plus grant_s (grant_s 0: no limit). False when the job is not in TIMEOUT.
  bool requeue_timeout(const std::string& job_id, double grant_s, const std::string& reason);
  long count(v1::JobState state);

  static std::string now();  // ISO 8601 UTC with milliseconds

 private:
  std::optional<JobRow> get_locked(const std::string& id);
  long append_locked(const std::string& job_id, std::vector<v1::JobEvent>& events);
  SqliteDb db_;
};

}  // namespace mdem::server
