// The study tables of the results database, on mdem_sqlite.
#include "study_store.h"

#include <chrono>
#include <cmath>
#include <ctime>
#include <limits>

#include "mdem/job_id.h"
#include "mdem/sqlite_db.h"
#include "results_store.h"

namespace mdem::cli {
namespace {

constexpr const char* kStudySchema = R"sql(
CREATE TABLE IF NOT EXISTS studies (
  id TEXT PRIMARY KEY NOT NULL,
  kind TEXT NOT NULL,
  spec_json TEXT NOT NULL,
  vary_json TEXT NOT NULL,
  server TEXT NOT NULL DEFAULT '',
  created_at TEXT NOT NULL,
  reference TEXT NOT NULL DEFAULT ''
);
CREATE TABLE IF NOT EXISTS study_runs (
  study_id TEXT NOT NULL REFERENCES studies (id) ON DELETE CASCADE,
  seq INTEGER NOT NULL,
  job_id TEXT NOT NULL,
  point_json TEXT NOT NULL,
  PRIMARY KEY (study_id, seq)
) WITHOUT ROWID;
CREATE INDEX IF NOT EXISTS study_runs_job ON study_runs (job_id);
CREATE TABLE IF NOT EXISTS study_errors (
  study_id TEXT NOT NULL,
  seq INTEGER NOT NULL,
  result TEXT NOT NULL,
  unit TEXT NOT NULL,
  value REAL,
  reference REAL,
  error REAL,
  relative_error REAL,
  observed_order REAL,
  extrapolated INTEGER NOT NULL,
  wall_s REAL,
  balance_error REAL,
  PRIMARY KEY (study_id, seq, result),
  FOREIGN KEY (study_id, seq) REFERENCES study_runs (study_id, seq) ON DELETE CASCADE
) WITHOUT ROWID;
)sql";

std::string now_iso() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

// NULL (SQLite's NaN) reads back as NaN.
double real_or_nan(sqlite3_stmt* s, int col) {
  return sqlite3_column_type(s, col) == SQLITE_NULL ? std::numeric_limits<double>::quiet_NaN()
                                                    : sqlite3_column_double(s, col);
}

constexpr const char* kStudyColumns =
    "id, kind, spec_json, vary_json, server, created_at, reference";

StudyRecord read_study(Query& q) {
  return {q.text(0), q.text(1), q.text(2), q.text(3), q.text(4), q.text(5), q.text(6)};
}

}  // namespace

struct StudyStore::Impl : SqliteDb {
  using SqliteDb::SqliteDb;
  template <class F>
  auto call(F&& f) {
    std::lock_guard<std::mutex> lock(mutex());
    try {
      return f(*this);
    } catch (const SqliteError& e) {
      throw StoreError(e.what());
    }
  }
};

StudyStore::StudyStore(const std::string& path) {
  try {
    impl_ = std::make_unique<Impl>(path, "results database");
  } catch (const SqliteError& e) {
    throw StoreError(e.what());
  }
  impl_->call([](Impl& db) {
    if (!db.has_table("studies") || !db.has_table("study_errors"))
      db.exec(kStudySchema, "cannot create the study tables");
  });
}

StudyStore::~StudyStore() = default;

std::string StudyStore::new_study_id() { return "s" + mdem::new_job_id(4).substr(1); }

bool is_study_id(const std::string& id) { return id.rfind("s-", 0) == 0; }

void StudyStore::create_study(const StudyRecord& s) {
  impl_->call([&](Impl& db) {
    Query(db, std::string("INSERT INTO studies (") + kStudyColumns + ") VALUES (?,?,?,?,?,?,?)",
          "cannot record the study " + s.id)
        .bind(1, s.id)
        .bind(2, s.kind)
        .bind(3, s.spec_json)
        .bind(4, s.vary_json)
        .bind(5, s.server)
        .bind(6, s.created_at.empty() ? now_iso() : s.created_at)
        .bind(7, s.reference)
        .run();
  });
}

void StudyStore::add_run(const std::string& study_id, const StudyRunRecord& run) {
  impl_->call([&](Impl& db) {
    Query(db, "INSERT INTO study_runs (study_id, seq, job_id, point_json) VALUES (?,?,?,?)",
          "cannot record a run of the study " + study_id)
        .bind(1, study_id)
        .bind(2, static_cast<long>(run.seq))
        .bind(3, run.job_id)
        .bind(4, run.point_json)
        .run();
  });
}

void StudyStore::set_errors(const std::string& study_id, const std::string& reference,
                            const std::vector<StudyErrorRow>& rows) {
  impl_->call([&](Impl& db) {
    Transaction tx(db);
    const std::string what = "cannot store the errors of the study " + study_id;
    Query(db, "DELETE FROM study_errors WHERE study_id = ?", what).bind(1, study_id).run();
    Query(db, "UPDATE studies SET reference = ? WHERE id = ?", what)
        .bind(1, reference)
        .bind(2, study_id)
        .run();
    for (const StudyErrorRow& r : rows)
      Query(db,
            "INSERT INTO study_errors (study_id, seq, result, unit, value, reference, error, "
            "relative_error, observed_order, extrapolated, wall_s, balance_error) VALUES "
            "(?,?,?,?,?,?,?,?,?,?,?,?)",
            what)
          .bind(1, study_id)
          .bind(2, static_cast<long>(r.seq))
          .bind(3, r.result)
          .bind(4, r.unit)
          .bind(5, r.value)  // NaN binds as NULL
          .bind(6, r.reference)
          .bind(7, r.error)
          .bind(8, r.relative_error)
          .bind(9, r.order)
          .bind(10, static_cast<long>(r.extrapolated))
          .bind(11, r.wall_s)
          .bind(12, r.balance_error)
          .run();
    tx.commit();
  });
}

std::vector<StudyRecord> StudyStore::list() const {
  return impl_->call([](Impl& db) {
    std::vector<StudyRecord> out;
    Query q(db, std::string("SELECT ") + kStudyColumns + " FROM studies ORDER BY id DESC",
            "cannot list the studies");
    while (q.step()) out.push_back(read_study(q));
    return out;
  });
}

std::optional<StudyRecord> StudyStore::find(const std::string& id_or_prefix) const {
  return impl_->call([&](Impl& db) -> std::optional<StudyRecord> {
    std::vector<StudyRecord> found;
    Query q(db,
            std::string("SELECT ") + kStudyColumns +
                " FROM studies WHERE id = ?1 OR substr(id, 1, length(?1)) = ?1 ORDER BY id",
            "cannot read the studies");
    q.bind(1, id_or_prefix);
    while (q.step()) found.push_back(read_study(q));
    for (const StudyRecord& s : found)
      if (s.id == id_or_prefix) return s;
    if (found.size() > 1)
      throw StoreError("study id '" + id_or_prefix + "' is ambiguous: it starts " +
                       std::to_string(found.size()) + " studies (" + found[0].id + ", " +
                       found[1].id + ", ...); give more of it");
    if (found.empty()) return std::nullopt;
    return found.front();
  });
}

std::vector<StudyRunRecord> StudyStore::runs(const std::string& study_id) const {
  return impl_->call([&](Impl& db) {
    std::vector<StudyRunRecord> out;
    Query q(db, "SELECT seq, job_id, point_json FROM study_runs WHERE study_id = ? ORDER BY seq",
            "cannot read the runs of the study " + study_id);
    q.bind(1, study_id);
    while (q.step()) out.push_back({static_cast<int>(q.integer(0)), q.text(1), q.text(2)});
    return out;
  });
}

std::vector<StudyErrorRow> StudyStore::errors(const std::string& study_id) const {
  return impl_->call([&](Impl& db) {
    std::vector<StudyErrorRow> out;
    const std::string sql =
        "SELECT seq, result, unit, value, reference, error, relative_error, observed_order, "
        "extrapolated, wall_s, balance_error FROM study_errors WHERE study_id = ? ORDER BY seq";
    sqlite3_stmt* s = db.prepare(sql);
    Query q(db, sql, "cannot read the errors of the study " + study_id);
    q.bind(1, study_id);
    while (q.step()) {
      StudyErrorRow r;
      r.seq = static_cast<int>(q.integer(0));
      r.result = q.text(1);
      r.unit = q.text(2);
      r.value = real_or_nan(s, 3);
      r.reference = real_or_nan(s, 4);
      r.error = real_or_nan(s, 5);
      r.relative_error = real_or_nan(s, 6);
      r.order = real_or_nan(s, 7);
      r.extrapolated = q.integer(8) != 0;
      r.wall_s = real_or_nan(s, 9);
      r.balance_error = real_or_nan(s, 10);
      out.push_back(std::move(r));
    }
    return out;
  });
}

}  // namespace mdem::cli
