#include "job_store.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <random>

#include "mdem/job_id.h"
#include "mdem/time_text.h"

namespace mdem::server {
namespace {

constexpr int kSchemaVersion = 1;

constexpr const char* kSchema = R"sql(
CREATE TABLE schema_version (version INTEGER NOT NULL);
CREATE TABLE jobs (
  id TEXT PRIMARY KEY NOT NULL,
  user TEXT NOT NULL,
  request_id TEXT NOT NULL,
  kind TEXT NOT NULL,
  name TEXT NOT NULL,
  spec BLOB NOT NULL,
  state INTEGER NOT NULL,
  reason TEXT NOT NULL DEFAULT '',
  created_at TEXT NOT NULL,
  started_at TEXT NOT NULL DEFAULT '',
  finished_at TEXT NOT NULL DEFAULT '',
  elements INTEGER NOT NULL,
  total_steps INTEGER NOT NULL,
  step INTEGER NOT NULL DEFAULT 0,
  last_seq INTEGER NOT NULL DEFAULT 0,
  threads INTEGER NOT NULL,
  resumes INTEGER NOT NULL DEFAULT 0,
  start_order INTEGER NOT NULL DEFAULT 0,
  checkpoint_step INTEGER NOT NULL DEFAULT 0,
  wall_s REAL NOT NULL DEFAULT 0,
  last_frame_step INTEGER NOT NULL DEFAULT -1,
  last_snapshot_step INTEGER NOT NULL DEFAULT -1,
  last_progress_step INTEGER NOT NULL DEFAULT -1,
  columns_logged INTEGER NOT NULL DEFAULT 0,
  report_json TEXT NOT NULL DEFAULT '',
  study_id TEXT NOT NULL DEFAULT '',
  study BLOB NOT NULL DEFAULT x'',
  time_limit_s REAL NOT NULL DEFAULT 0,
  peak_bytes INTEGER NOT NULL DEFAULT 0,
  daemon_rss_peak_bytes INTEGER NOT NULL DEFAULT 0,
  UNIQUE (user, request_id)
);
CREATE INDEX jobs_state ON jobs (state, user);
CREATE INDEX jobs_study ON jobs (user, study_id);
CREATE TABLE events (
  job_id TEXT NOT NULL REFERENCES jobs (id),
  seq INTEGER NOT NULL,
  body BLOB NOT NULL,
  PRIMARY KEY (job_id, seq)
) WITHOUT ROWID;
)sql";

constexpr const char* kJobColumns =
    "id, user, request_id, kind, name, spec, state, reason, created_at, started_at, finished_at, "
    "elements, total_steps, step, last_seq, threads, resumes, checkpoint_step, wall_s, "
    "last_frame_step, last_snapshot_step, last_progress_step, columns_logged, report_json, study, "
    "time_limit_s, peak_bytes, daemon_rss_peak_bytes";

// A job database of an mdemd before wall-time limits and memory peaks gains them: its jobs had
// no limit, and their peaks were not measured (0, shown as unknown).
constexpr const char* kUsageColumns = R"sql(
ALTER TABLE jobs ADD COLUMN time_limit_s REAL NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN peak_bytes INTEGER NOT NULL DEFAULT 0;
ALTER TABLE jobs ADD COLUMN daemon_rss_peak_bytes INTEGER NOT NULL DEFAULT 0;
)sql";

// A job database of an mdemd before studies (no study columns) gains them: its jobs are lone jobs.
constexpr const char* kStudyColumns = R"sql(
ALTER TABLE jobs ADD COLUMN study_id TEXT NOT NULL DEFAULT '';
ALTER TABLE jobs ADD COLUMN study BLOB NOT NULL DEFAULT x'';
CREATE INDEX jobs_study ON jobs (user, study_id);
)sql";

JobRow read_row(const Query& q) {
  JobRow r;
  r.id = q.text(0);
  r.user = q.text(1);
  r.request_id = q.text(2);
  r.kind = q.text(3);
  r.name = q.text(4);
  r.spec.ParseFromString(q.blob(5));
  r.state = static_cast<v1::JobState>(q.integer(6));
  r.reason = q.text(7);
  r.created_at = q.text(8);
  r.started_at = q.text(9);
  r.finished_at = q.text(10);
  r.elements = q.integer(11);
  r.total_steps = q.integer(12);
  r.step = q.integer(13);
  r.last_seq = q.integer(14);
  r.threads = static_cast<int>(q.integer(15));
  r.resumes = static_cast<int>(q.integer(16));
  r.checkpoint_step = q.integer(17);
  r.wall_s = q.real(18);
  r.last_frame_step = q.integer(19);
  r.last_snapshot_step = q.integer(20);
  r.last_progress_step = q.integer(21);
  r.columns_logged = q.integer(22) != 0;
  r.report_json = q.text(23);
  r.study.ParseFromString(q.blob(24));
  r.time_limit_s = q.real(25);
  r.peak_bytes = q.integer(26);
  r.daemon_rss_peak_bytes = q.integer(27);
  return r;
}

v1::JobEvent state_event(v1::JobState s, const std::string& reason) {
  v1::JobEvent e;
  e.mutable_state()->set_state(s);
  e.mutable_state()->set_reason(reason);
  return e;
}

}  // namespace

v1::JobInfo JobRow::info() const {
  v1::JobInfo i;
  i.set_job_id(id);
  i.set_user(user);
  i.set_kind(kind);
  i.set_name(name);
  i.set_state(state);
  i.set_reason(reason);
  *i.mutable_spec() = spec;
  // Stored to the millisecond (the queue's order); shown to the second, as everywhere.
  i.set_created_at(shown_time(created_at));
  i.set_started_at(shown_time(started_at));
  i.set_finished_at(shown_time(finished_at));
  i.set_elements(elements);
  i.set_total_steps(total_steps);
  i.set_step(step);
  i.set_last_seq(last_seq);
  i.set_report_json(report_json);
  i.set_resumes(resumes);
  i.set_time_limit_s(time_limit_s);
  i.set_elapsed_s(wall_s);
  i.set_job_data_peak_bytes(peak_bytes);
  i.set_daemon_rss_peak_bytes(daemon_rss_peak_bytes);
  if (!study.study_id().empty()) *i.mutable_study() = study;
  return i;
}

std::string JobStore::now() {
  const auto t = std::chrono::system_clock::now();
  const std::time_t s = std::chrono::system_clock::to_time_t(t);
  const long ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(t.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&s, &tm);
  char buf[64];
  const std::size_t n = std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  std::snprintf(buf + n, sizeof buf - n, ".%03ldZ", ms);
  return buf;
}

JobStore::JobStore(const std::string& path) : db_(path, "job database", "FULL") {
  std::lock_guard lock(db_.mutex());
  if (db_.has_table("schema_version")) {
    Query q(db_, "SELECT MAX(version) FROM schema_version", "cannot read the schema version");
    const long v = q.step() ? q.integer(0) : 0;
    if (v != kSchemaVersion)
      throw SqliteError(db_.where() + ": schema version " + std::to_string(v) +
                        ", but this mdemd reads version " + std::to_string(kSchemaVersion));
    if (!db_.has_column("jobs", "study_id")) {
      Transaction t(db_);
      db_.exec(kStudyColumns, "cannot add the study columns");
      t.commit();
    }
    if (!db_.has_column("jobs", "time_limit_s")) {
      Transaction t(db_);
      db_.exec(kUsageColumns, "cannot add the time-limit and memory columns");
      t.commit();
    }
    return;
  }
  Transaction t(db_);
  db_.exec(kSchema, "cannot create the schema");
  Query(db_, "INSERT INTO schema_version (version) VALUES (?)", "cannot create the schema")
      .bind(1, static_cast<long>(kSchemaVersion))
      .run();
  t.commit();
}

std::optional<JobRow> JobStore::get_locked(const std::string& id) {
  Query q(db_, std::string("SELECT ") + kJobColumns + " FROM jobs WHERE id = ?",
          "cannot read a job");
  q.bind(1, id);
  if (!q.step()) return std::nullopt;
  return read_row(q);
}

std::optional<JobRow> JobStore::get(const std::string& id) {
  std::lock_guard lock(db_.mutex());
  return get_locked(id);
}

SubmitResult JobStore::submit(const std::string& user, const std::string& request_id,
                              const v1::JobSpec& spec, const v1::StudyRun& study,
                              const std::string& kind, long elements, long total_steps, int threads,
                              long max_active, double time_limit_s) {
  std::lock_guard lock(db_.mutex());
  Transaction t(db_);
  {
    Query q(db_, "SELECT id FROM jobs WHERE user = ? AND request_id = ?", "cannot read a job");
    q.bind(1, user).bind(2, request_id);
    if (q.step()) {
      const std::string id = q.text(0);
      return {*get_locked(id), false};
    }
  }
  {
    Query q(db_, "SELECT COUNT(*) FROM jobs WHERE user = ? AND state IN (?, ?)",
            "cannot count jobs");
    q.bind(1, user).bind(2, static_cast<long>(v1::QUEUED)).bind(3, static_cast<long>(v1::RUNNING));
    q.step();
    if (q.integer(0) >= max_active)
      throw LimitError("user '" + user + "' already has " + std::to_string(q.integer(0)) +
                       " queued or running jobs (limit max_queued_per_user = " +
                       std::to_string(max_active) + "); wait for one to finish or cancel one");
  }
  std::string spec_bytes;
  spec.SerializeToString(&spec_bytes);
  std::string study_bytes;
  if (!study.study_id().empty()) study.SerializeToString(&study_bytes);
  const std::string id = new_job_id(6);  // a shared queue: many submits a second
  Query(db_,
        "INSERT INTO jobs (id, user, request_id, kind, name, spec, state, created_at, elements, "
        "total_steps, threads, study_id, study) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
        "cannot queue the job")
      .bind(1, id)
      .bind(2, user)
      .bind(3, request_id)
      .bind(4, kind)
      .bind(5, spec.name())
      .bind_blob(6, spec_bytes)
      .bind(7, static_cast<long>(v1::QUEUED))
      .bind(8, now())
      .bind(9, elements)
      .bind(10, total_steps)
      .bind(11, static_cast<long>(threads))
      .bind(12, study.study_id())
      .bind_blob(13, study_bytes)
      .run();
  Query(db_, "UPDATE jobs SET time_limit_s = ? WHERE id = ?", "cannot queue the job")
      .bind(1, time_limit_s)
      .bind(2, id)
      .run();
  std::vector<v1::JobEvent> ev{state_event(v1::QUEUED, "submitted")};
  append_locked(id, ev);
  t.commit();
  return {*get_locked(id), true};
}

std::vector<JobRow> JobStore::list(const std::string& user, int limit,
                                   const std::string& study_id) {
  std::lock_guard lock(db_.mutex());
  std::vector<JobRow> out;
  Query q(db_,
          std::string("SELECT ") + kJobColumns +
              " FROM jobs WHERE (?1 = '' OR user = ?1) AND (?2 = '' OR study_id = ?2) "
              "ORDER BY created_at DESC, id DESC LIMIT ?3",
          "cannot list jobs");
  q.bind(1, user).bind(2, study_id).bind(3, static_cast<long>(limit));
  while (q.step()) out.push_back(read_row(q));
  return out;
}

std::vector<std::string> JobStore::reconcile() {
  std::lock_guard lock(db_.mutex());
  Transaction t(db_);
  std::vector<std::pair<std::string, long>> running;
  {
    Query q(db_, "SELECT id, checkpoint_step FROM jobs WHERE state = ?", "cannot read jobs");
    q.bind(1, static_cast<long>(v1::RUNNING));
    while (q.step()) running.emplace_back(q.text(0), q.integer(1));
  }
  std::vector<std::string> ids;
  for (const auto& [id, ckpt] : running) {
    std::vector<v1::JobEvent> ev{
        state_event(v1::QUEUED, "the daemon stopped while the job ran; it resumes from " +
                                    (ckpt > 0 ? "its checkpoint at step " + std::to_string(ckpt)
                                              : std::string("the start (no checkpoint yet)")))};
    append_locked(id, ev);
    ids.push_back(id);
  }
  t.commit();
  return ids;
}

// The queued jobs in the order claim_next takes them: the user with the fewest running jobs
// first, then the user who started a job longest ago, then the oldest job.
constexpr const char* kQueueOrder =
    "SELECT id, user FROM jobs j WHERE state = ?1 ORDER BY "
    "(SELECT COUNT(*) FROM jobs r WHERE r.user = j.user AND r.state = ?2), "
    "(SELECT MAX(start_order) FROM jobs r WHERE r.user = j.user), created_at, id";

std::vector<JobOwner> JobStore::queue() {
  std::lock_guard lock(db_.mutex());
  Query q(db_, kQueueOrder, "cannot read the queue");
  q.bind(1, static_cast<long>(v1::QUEUED)).bind(2, static_cast<long>(v1::RUNNING));
  std::vector<JobOwner> jobs;
  while (q.step()) jobs.push_back({q.text(0), q.text(1)});
  return jobs;
}

std::vector<JobOwner> JobStore::running() {
  std::lock_guard lock(db_.mutex());
  Query q(db_, "SELECT id, user FROM jobs WHERE state = ? ORDER BY start_order",
          "cannot read the jobs");
  q.bind(1, static_cast<long>(v1::RUNNING));
  std::vector<JobOwner> jobs;
  while (q.step()) jobs.push_back({q.text(0), q.text(1)});
  return jobs;
}

std::optional<JobRow> JobStore::claim_next() {
  std::lock_guard lock(db_.mutex());
  Transaction t(db_);
  std::string id;
  {
    Query q(db_, std::string(kQueueOrder) + " LIMIT 1", "cannot pick the next job");
    q.bind(1, static_cast<long>(v1::QUEUED)).bind(2, static_cast<long>(v1::RUNNING));
    if (!q.step()) return std::nullopt;
    id = q.text(0);
  }
  const JobRow before = *get_locked(id);
  Query(db_,
        "UPDATE jobs SET start_order = (SELECT MAX(start_order) + 1 FROM jobs), "
        "resumes = resumes + ? WHERE id = ?",
        "cannot start the job")
      .bind(1, static_cast<long>(before.started_at.empty() ? 0 : 1))
      .bind(2, id)
      .run();
  std::vector<v1::JobEvent> ev{state_event(
      v1::RUNNING,
      before.checkpoint_step > 0
          ? "resumed from the checkpoint at step " + std::to_string(before.checkpoint_step)
          : (before.started_at.empty() ? "started" : "restarted from the start"))};
  append_locked(id, ev);
  t.commit();
  return get_locked(id);
}

bool JobStore::cancel_queued(const std::string& id, const std::string& reason) {
  std::lock_guard lock(db_.mutex());
  Transaction t(db_);
  const auto row = get_locked(id);
  if (!row || row->state != v1::QUEUED) return false;
  std::vector<v1::JobEvent> ev{state_event(v1::CANCELLED, reason)};
  append_locked(id, ev);
  t.commit();
  return true;
}

long JobStore::append(const std::string& job_id, std::vector<v1::JobEvent>& events) {
  std::lock_guard lock(db_.mutex());
  Transaction t(db_);
  const long last = append_locked(job_id, events);
  t.commit();
  return last;
}

long JobStore::append_locked(const std::string& job_id, std::vector<v1::JobEvent>& events) {
  const auto row = get_locked(job_id);
  if (!row) throw SqliteError(db_.where() + ": no job " + job_id);
  JobRow r = *row;
  const std::string t = now();
  std::string body;
  for (v1::JobEvent& e : events) {
    e.set_seq(++r.last_seq);
    e.set_time(t);
    switch (e.event_case()) {
      case v1::JobEvent::kState:
        r.state = e.state().state();
        r.reason = e.state().reason();
        if (r.state == v1::RUNNING && r.started_at.empty()) r.started_at = t;
        if (r.finished()) r.finished_at = t;
        if (r.state == v1::QUEUED) r.finished_at.clear();  // a TIMEOUT job resumed
        break;
      case v1::JobEvent::kProgress:
        r.last_progress_step = e.progress().step();
        r.step = std::max(r.step, e.progress().step());
        if (e.progress().total_steps() > 0) r.total_steps = e.progress().total_steps();
        if (e.progress().elements() > 0) r.elements = e.progress().elements();
        break;
      case v1::JobEvent::kColumns:
        r.columns_logged = true;
        break;
      case v1::JobEvent::kFrame:
        r.last_frame_step = event_order(e.frame().stage(), e.frame().step());
        r.step = std::max(r.step, e.frame().step());
        break;
      case v1::JobEvent::kSnapshot:
        if (e.snapshot().index() + 1 == e.snapshot().count())
          r.last_snapshot_step = event_order(e.snapshot().stage(), e.snapshot().step());
        break;
      case v1::JobEvent::kReport:
        r.report_json = e.report().json();
        break;
      default:
        break;
    }
    body.clear();
    e.SerializeToString(&body);
    Query(db_, "INSERT INTO events (job_id, seq, body) VALUES (?, ?, ?)", "cannot log an event")
        .bind(1, job_id)
        .bind(2, r.last_seq)
        .bind_blob(3, body)
        .run();
  }
  Query(db_,
        "UPDATE jobs SET state = ?, reason = ?, started_at = ?, finished_at = ?, step = ?, "
        "last_seq = ?, last_frame_step = ?, last_snapshot_step = ?, last_progress_step = ?, "
        "columns_logged = ?, report_json = ?, total_steps = ?, elements = ? WHERE id = ?",
        "cannot update the job")
      .bind(1, static_cast<long>(r.state))
      .bind(2, r.reason)
      .bind(3, r.started_at)
      .bind(4, r.finished_at)
      .bind(5, r.step)
      .bind(6, r.last_seq)
      .bind(7, r.last_frame_step)
      .bind(8, r.last_snapshot_step)
      .bind(9, r.last_progress_step)
      .bind(10, static_cast<long>(r.columns_logged))
      .bind(11, r.report_json)
      .bind(12, r.total_steps)
      .bind(13, r.elements)
      .bind(14, job_id)
      .run();
  return r.last_seq;
}

std::vector<v1::JobEvent> JobStore::events(const std::string& job_id, long from_seq, int max_count,
                                           std::size_t max_bytes) {
  std::lock_guard lock(db_.mutex());
  std::vector<v1::JobEvent> out;
  Query q(db_, "SELECT body FROM events WHERE job_id = ? AND seq >= ? ORDER BY seq LIMIT ?",
          "cannot read events");
  q.bind(1, job_id).bind(2, from_seq).bind(3, static_cast<long>(max_count));
  std::size_t bytes = 0;
  while (q.step()) {
    const std::string body = q.blob(0);
    v1::JobEvent e;
    if (!e.ParseFromString(body))
      throw SqliteError(db_.where() + ": event of job " + job_id + " is damaged");
    e.set_time(shown_time(e.time()));  // logged to the millisecond, shown to the second
    bytes += body.size();
    out.push_back(std::move(e));
    if (bytes > max_bytes) break;
  }
  return out;
}

void JobStore::set_checkpoint(const std::string& job_id, long step, double wall_s) {
  std::lock_guard lock(db_.mutex());
  Query(db_, "UPDATE jobs SET checkpoint_step = ?, wall_s = ? WHERE id = ?",
        "cannot record the checkpoint")
      .bind(1, step)
      .bind(2, wall_s)
      .bind(3, job_id)
      .run();
}

void JobStore::set_usage(const std::string& job_id, double wall_s, long peak_bytes,
                         long daemon_rss_peak_bytes) {
  std::lock_guard lock(db_.mutex());
  Query(db_,
        "UPDATE jobs SET wall_s = ?, peak_bytes = MAX(peak_bytes, ?), "
        "daemon_rss_peak_bytes = MAX(daemon_rss_peak_bytes, ?) WHERE id = ?",
        "cannot record the job's usage")
      .bind(1, wall_s)
      .bind(2, peak_bytes)
      .bind(3, daemon_rss_peak_bytes)
      .bind(4, job_id)
      .run();
}

bool JobStore::requeue_timeout(const std::string& job_id, double grant_s,
                               const std::string& reason) {
  std::lock_guard lock(db_.mutex());
  Transaction t(db_);
  const auto row = get_locked(job_id);
  if (!row || row->state != v1::TIMEOUT) return false;
  Query(db_, "UPDATE jobs SET time_limit_s = ? WHERE id = ?", "cannot resume the job")
      .bind(1, grant_s > 0 ? row->wall_s + grant_s : 0.0)
      .bind(2, job_id)
      .run();
  std::vector<v1::JobEvent> ev{state_event(v1::QUEUED, reason)};
  append_locked(job_id, ev);
  t.commit();
  return true;
}

long JobStore::count(v1::JobState state) {
  std::lock_guard lock(db_.mutex());
  Query q(db_, "SELECT COUNT(*) FROM jobs WHERE state = ?", "cannot count jobs");
  q.bind(1, static_cast<long>(state));
  q.step();
  return q.integer(0);
}

}  // namespace mdem::server
