// The local results database on mdem_sqlite (the SQLite layer shared with the daemon): WAL
// journal, a versioned schema, cached prepared statements, one transaction per write, and every
// failure a StoreError that names the file and SQLite's message. Arrays are stored as BLOBs of
// little-endian float64 / int32 values, so doubles come back bit for bit.
#include "results_store.h"

#include <unistd.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>
#include <utility>

#include "mdem/job_id.h"
#include "mdem/job_state.h"
#include "mdem/sqlite_db.h"
#include "mdem/time_text.h"

namespace mdem::cli {
namespace {

namespace fs = std::filesystem;

constexpr int kSchemaVersion = 1;
constexpr int kBusyTimeoutMs = 10000;

// time_ps columns have no declared type on purpose: a REAL column may store a whole-valued double
// as an integer, which turns -0.0 into 0; without affinity the 8-byte IEEE value is kept as is.
constexpr const char* kSchema = R"sql(
CREATE TABLE schema_version (version INTEGER NOT NULL);
CREATE TABLE jobs (
  id TEXT PRIMARY KEY NOT NULL,
  kind TEXT NOT NULL,
  spec_json TEXT NOT NULL,
  state TEXT NOT NULL CHECK (state IN ('QUEUED', 'RUNNING', 'SUCCEEDED', 'FAILED', 'CANCELLED', 'TIMEOUT')),
  reason TEXT NOT NULL DEFAULT '',
  summary_json TEXT NOT NULL DEFAULT '',
  created_at TEXT NOT NULL,
  finished_at TEXT NOT NULL DEFAULT '',
  columns_json TEXT NOT NULL DEFAULT '[]',
  server TEXT NOT NULL DEFAULT '',
  last_seq INTEGER NOT NULL DEFAULT 0,
  runner TEXT NOT NULL DEFAULT '',
  token_file TEXT NOT NULL DEFAULT ''
);
CREATE TABLE frames (
  job_id TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  seq INTEGER NOT NULL,
  step INTEGER NOT NULL,
  time_ps NOT NULL,
  vals BLOB NOT NULL,
  PRIMARY KEY (job_id, seq)
) WITHOUT ROWID;
CREATE TABLE snapshots (
  job_id TEXT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,
  seq INTEGER NOT NULL,
  step INTEGER NOT NULL,
  time_ps NOT NULL,
  n INTEGER NOT NULL,
  x BLOB NOT NULL,
  q BLOB NOT NULL,
  radius BLOB NOT NULL,
  kind BLOB NOT NULL,
  tube BLOB NOT NULL,
  idx BLOB NOT NULL,
  scalar_names TEXT NOT NULL,
  scalars BLOB NOT NULL,
  v BLOB NOT NULL DEFAULT x'',
  bonds BLOB NOT NULL DEFAULT x'',
  UNIQUE (job_id, seq)
);
)sql";
// jobs.server and jobs.last_seq (a daemon's job: where it runs, the last event applied),
// jobs.runner (a job run in-process: the process running it, see this_process()) and
// jobs.token_file (a daemon's job: the token file it was submitted with, never the token) came
// after version 1 was released: an older file gets them by ALTER TABLE when opened (kMigrations),
// so the version stays 1 and an older mdem still reads the file.
//
// frames.vals: float64 per column. snapshots: x = float64 x,y,z per element; q = float64
// w,x,y,z; radius float64; kind, tube, idx int32; scalar_names a JSON array; scalars float64,
// n values per name in the order of the names; v float64 vx,vy,vz per element (empty: not
// recorded); bonds int32 i, j, state (0 intact, 1 yielded, 2 broken) per bond. snapshots.v and
// snapshots.bonds came after version 1 too (kSnapshotMigrations).

// The series in a long form that plain SQL reads (docs/results-db.md): frame_values holds frame
// seq's value of column col (its index in jobs.columns_json) beside the packed frames.vals (which
// stays the form mdem reads), and the view frames_long names each value and its unit (from the
// column name's suffix). Added after version 1 was released, so created (and filled from the
// BLOBs) when a writable file of an older mdem is opened; value has no type affinity, as time_ps.
constexpr const char* kLongSchema = R"sql(
CREATE TABLE IF NOT EXISTS frame_values (
  job_id TEXT NOT NULL,
  seq INTEGER NOT NULL,
  col INTEGER NOT NULL,
  value NOT NULL,
  PRIMARY KEY (job_id, seq, col),
  FOREIGN KEY (job_id, seq) REFERENCES frames (job_id, seq) ON DELETE CASCADE
) WITHOUT ROWID;
CREATE VIEW IF NOT EXISTS frames_long (job_id, seq, step, time_ps, name, value, unit) AS
SELECT f.job_id, f.seq, f.step, f.time_ps, c.value, v.value,
  CASE
    WHEN c.value GLOB '*_eV' THEN 'eV'
    WHEN c.value GLOB '*_nNnm' THEN 'nN·nm'
    WHEN c.value GLOB '*_nN' THEN 'nN'
    WHEN c.value GLOB '*_GPa' THEN 'GPa'
    WHEN c.value GLOB '*_nm' THEN 'nm'
    WHEN c.value GLOB '*_ps' THEN 'ps'
    WHEN c.value GLOB '*_deg' THEN 'deg'
    WHEN c.value GLOB '*_K' THEN 'K'
    ELSE ''
  END
FROM frames AS f
JOIN frame_values AS v ON v.job_id = f.job_id AND v.seq = f.seq
JOIN jobs AS j ON j.id = f.job_id
JOIN json_each(j.columns_json) AS c ON c.key = v.col;
)sql";

// The columns of the first schema; the columns of kMigrations follow them in a JobRecord.
constexpr const char* kFirstJobColumns =
    "id, kind, spec_json, state, reason, summary_json, created_at, finished_at";
constexpr const char* kRemoteJobColumns =
    "id, kind, spec_json, state, reason, summary_json, created_at, finished_at, server, last_seq, "
    "token_file";

struct Migration {
  const char* column;
  const char* definition;
  const char* fallback;  // read in its place from a read-only file that lacks it
};
// Columns added to the jobs table since the first schema, in JobRecord's order.
constexpr Migration kMigrations[] = {
    {"server", "server TEXT NOT NULL DEFAULT ''", "''"},
    {"last_seq", "last_seq INTEGER NOT NULL DEFAULT 0", "0"},
    {"runner", "runner TEXT NOT NULL DEFAULT ''", "''"},
    {"token_file", "token_file TEXT NOT NULL DEFAULT ''", "''"},
};

// Columns added to the snapshots table since the first schema, in the order they are read.
constexpr Migration kSnapshotMigrations[] = {
    {"v", "v BLOB NOT NULL DEFAULT x''", "x''"},
    {"bonds", "bonds BLOB NOT NULL DEFAULT x''", "x''"},
};

constexpr const char* kSnapshotColumns =
    "step, time_ps, n, x, q, radius, kind, tube, idx, scalar_names, scalars";

// ---- little-endian encoding -------------------------------------------------------------------

void put_u(std::string& out, std::uint64_t u, int bytes) {
  for (int b = 0; b < bytes; ++b) out.push_back(static_cast<char>((u >> (8 * b)) & 0xff));
}

std::uint64_t get_u(const std::string& in, std::size_t at, int bytes) {
  std::uint64_t u = 0;
  for (int b = 0; b < bytes; ++b)
    u |= static_cast<std::uint64_t>(static_cast<unsigned char>(in[at + b])) << (8 * b);
  return u;
}

void put_f64(std::string& out, double v) { put_u(out, std::bit_cast<std::uint64_t>(v), 8); }
void put_i32(std::string& out, std::int32_t v) { put_u(out, std::bit_cast<std::uint32_t>(v), 4); }
double get_f64(const std::string& in, std::size_t k) {
  return std::bit_cast<double>(get_u(in, 8 * k, 8));
}
std::int32_t get_i32(const std::string& in, std::size_t k) {
  return std::bit_cast<std::int32_t>(static_cast<std::uint32_t>(get_u(in, 4 * k, 4)));
}

std::string encode(const std::vector<double>& v) {
  std::string out;
  out.reserve(8 * v.size());
  for (double d : v) put_f64(out, d);
  return out;
}

std::string encode(const std::vector<std::int32_t>& v) {
  std::string out;
  out.reserve(4 * v.size());
  for (std::int32_t i : v) put_i32(out, i);
  return out;
}

// ---- time and ids -----------------------------------------------------------------------------

std::string utc_now(const char* format) {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, format, &tm);
  return buf;
}

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

// ---- the process running a job ---------------------------------------------------------------

std::string first_line(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  return line;
}

// Field 22 of /proc/PID/stat: the process's start time in clock ticks since boot ("" when there
// is no such process). With the boot id it names one process for good, unlike the pid alone.
std::string start_time(long pid) {
  const std::string stat = first_line("/proc/" + std::to_string(pid) + "/stat");
  const std::size_t paren = stat.rfind(')');
  if (paren == std::string::npos) return "";
  std::istringstream rest(stat.substr(paren + 2));  // field 3 onwards
  std::string f;
  for (int k = 3; k <= 22 && rest >> f; ++k)
    if (k == 22) return f;
  return "";
}

std::string host_name() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0) return "";
  return buf;
}

constexpr const char* kBootId = "/proc/sys/kernel/random/boot_id";

// "HOST BOOT-ID PID START-TIME" of this process; "" where /proc cannot tell.
std::string this_process() {
  const std::string host = host_name(), boot = first_line(kBootId);
  const std::string start = start_time(static_cast<long>(getpid()));
  if (host.empty() || host.find(' ') != std::string::npos || boot.empty() || start.empty())
    return "";
  return host + " " + boot + " " + std::to_string(getpid()) + " " + start;
}

// True when `runner` (this_process() of another process) names a process of this host that is
// gone: another boot, or no process of that pid and start time. A runner of another host, or
// one that cannot be read, is taken to be alive.
bool runner_gone(const std::string& runner) {
  std::istringstream in(runner);
  std::string host, boot, start;
  long pid = 0;
  if (!(in >> host >> boot >> pid >> start) || host != host_name()) return false;
  const std::string my_boot = first_line(kBootId);
  if (my_boot.empty()) return false;
  return boot != my_boot || start_time(pid) != start;
}

// "pid 123 on host" of a runner, for messages.
std::string runner_text(const std::string& runner) {
  std::istringstream in(runner);
  std::string host, boot, pid;
  in >> host >> boot >> pid;
  return "pid " + pid + " on " + host;
}

// ---- the connection ---------------------------------------------------------------------------

// The connection (mdem_sqlite: statement cache, queries, transactions) and what this store knows
// of the file's schema. ResultsStore::Impl is this, named outside the class so that the helpers
// below can take it. The layer's SqliteError becomes StoreError at the public interface (call).
struct StoreDb : SqliteDb {
  std::set<std::string> missing;           // columns of kMigrations an old read-only file lacks
  std::set<std::string> missing_snapshot;  // columns of kSnapshotMigrations it lacks
  bool remote_columns = true;  // jobs has server and last_seq (false: an old read-only file)

  explicit StoreDb(std::string path)
      : SqliteDb(std::move(path), "results database", "NORMAL", kBusyTimeoutMs, refuse_foreign) {}
  // The columns of a JobRecord, in its order (a fallback value for a missing one).
  std::string job_columns() const {
    std::string cols = kFirstJobColumns;
    for (const Migration& m : kMigrations)
      cols += std::string(", ") + (missing.count(m.column) ? m.fallback : m.column);
    return cols;
  }
  // The columns of a snapshot, in read_snapshot's order.
  std::string snapshot_columns() const {
    std::string cols = kSnapshotColumns;
    for (const Migration& m : kSnapshotMigrations)
      cols += std::string(", ") + (missing_snapshot.count(m.column) ? m.fallback : m.column);
    return cols;
  }
  void require_remote_columns() const {
    if (!remote_columns)
      throw StoreError(where() +
                       ": read-only and of an older schema (no server/last_seq columns); open it "
                       "writable once to upgrade it");
  }
  // A database with tables but none of ours is someone else's: refused before anything (even
  // the switch to WAL) changes it.
  static void refuse_foreign(SqliteDb& db);
};

using Impl = StoreDb;

// Runs f, turning an error of the SQLite layer into a StoreError with the same message.
template <class F>
decltype(auto) store_errors(F&& f) {
  try {
    return f();
  } catch (const SqliteError& e) {
    throw StoreError(e.what());
  }
}

long table_count(SqliteDb& db) {
  Query q(db, "SELECT COUNT(*) FROM sqlite_master WHERE type = 'table'", "cannot read");
  q.step();
  return q.integer(0);
}

void StoreDb::refuse_foreign(SqliteDb& db) {
  if (!db.has_table("schema_version") && table_count(db) > 0)
    throw SqliteError(db.where() +
                      ": not an mdem results database (it has other tables and no "
                      "schema_version); it is left unchanged. Give --db (or $MDEM_DB) a new file "
                      "or an mdem results database");
}

void check_schema_version(Impl& db) {
  Query q(db, "SELECT MAX(version) FROM schema_version", "cannot read the schema version");
  const long v = q.step() ? q.integer(0) : 0;
  if (v != kSchemaVersion)
    throw StoreError(db.where() + ": schema version " + std::to_string(v) +
                     ", but this mdem reads version " + std::to_string(kSchemaVersion) +
                     (v > kSchemaVersion ? " (written by a newer mdem)" : ""));
}

// TIMEOUT (a daemon's job that reached its wall-time limit) joined the states the jobs table's
// CHECK allows after version 1. An older file's CHECK is widened in place: SQLite documents
// editing the stored schema text (writable_schema, then a new schema_version) for changes that
// leave the stored records as they are, which widening a CHECK does
// (https://www.sqlite.org/lang_altertable.html#otheralter).
constexpr const char* kStatesBefore = "'FAILED', 'CANCELLED'))";
constexpr const char* kStatesNow = "'FAILED', 'CANCELLED', 'TIMEOUT'))";

std::string jobs_table_sql(Impl& db) {
  Query q(db, "SELECT sql FROM sqlite_master WHERE type = 'table' AND name = 'jobs'",
          "cannot read the schema");
  return q.step() ? q.text(0) : std::string();
}

bool lacks_timeout_state(Impl& db) {
  const std::string sql = jobs_table_sql(db);
  return sql.find(kStatesBefore) != std::string::npos;
}

// Inside the migration's transaction.
void widen_state_check(Impl& db) {
  std::string sql = jobs_table_sql(db);
  const std::size_t at = sql.find(kStatesBefore);
  if (at == std::string::npos) return;  // widened meanwhile
  sql.replace(at, std::string(kStatesBefore).size(), kStatesNow);
  long version = 0;
  {
    Query q(db, "PRAGMA schema_version", "cannot read the schema version");
    if (q.step()) version = q.integer(0);
  }
  db.exec("PRAGMA writable_schema = ON", "cannot allow the TIMEOUT state");
  Query(db, "UPDATE sqlite_master SET sql = ? WHERE type = 'table' AND name = 'jobs'",
        "cannot allow the TIMEOUT state")
      .bind(1, sql)
      .run();
  db.exec(("PRAGMA schema_version = " + std::to_string(version + 1)).c_str(),
          "cannot allow the TIMEOUT state");
  db.exec("PRAGMA writable_schema = OFF", "cannot allow the TIMEOUT state");
}

bool needs_migration(Impl& db) {
  if (lacks_timeout_state(db)) return true;
  for (const Migration& m : kMigrations)
    if (!db.has_column("jobs", m.column)) return true;
  for (const Migration& m : kSnapshotMigrations)
    if (!db.has_column("snapshots", m.column)) return true;
  return !db.has_table("frame_values");
}

void insert_frame_values(Impl& db, const std::string& id, long seq,
                         const std::vector<double>& values) {
  for (std::size_t c = 0; c < values.size(); ++c) {
    Query q(db, "INSERT INTO frame_values (job_id, seq, col, value) VALUES (?, ?, ?, ?)",
            "cannot write a frame value of job '" + id + "'");
    q.bind(1, id).bind(2, seq).bind(3, static_cast<long>(c)).bind(4, values[c]).run();
  }
}

std::vector<double> decode_frame_values(const Impl& db, const std::string& vals) {
  if (vals.size() % 8 != 0) throw StoreError(db.where() + ": corrupt frame values");
  std::vector<double> values(vals.size() / 8);
  for (std::size_t k = 0; k < values.size(); ++k) values[k] = get_f64(vals, k);
  return values;
}

// Creates the long form of the series and fills it from the BLOBs of frames that have no rows
// in it (all of them in a file of an older mdem); in the caller's transaction.
void add_long_series(Impl& db) {
  db.exec(kLongSchema, "cannot create the frame_values table and frames_long view");
  struct Pending {
    std::string id;
    long seq;
    std::vector<double> values;
  };
  std::vector<Pending> pending;
  {
    Query q(db,
            "SELECT f.job_id, f.seq, f.vals FROM frames AS f WHERE length(f.vals) > 0 AND NOT "
            "EXISTS (SELECT 1 FROM frame_values AS v WHERE v.job_id = f.job_id AND v.seq = f.seq)",
            "cannot read the frames");
    while (q.step())
      pending.push_back({q.text(0), q.integer(1), decode_frame_values(db, q.blob(2))});
  }
  for (const Pending& p : pending) insert_frame_values(db, p.id, p.seq, p.values);
}

// Adds the columns of kMigrations that a file of an older mdem lacks. A read-only file (opened
// read-only by SQLite when the file is write-protected) is left as it is and read with defaults
// for the missing columns.
void migrate(Impl& db) {
  if (!needs_migration(db)) return;
  if (sqlite3_db_readonly(db.handle(), "main") == 1) {
    for (const Migration& m : kMigrations)
      if (!db.has_column("jobs", m.column)) db.missing.insert(m.column);
    for (const Migration& m : kSnapshotMigrations)
      if (!db.has_column("snapshots", m.column)) db.missing_snapshot.insert(m.column);
    db.remote_columns = !db.missing.count("server") && !db.missing.count("last_seq") &&
                        !db.missing.count("token_file");
    return;
  }
  Transaction t(db);
  widen_state_check(db);
  for (const Migration& m : kMigrations)
    if (!db.has_column("jobs", m.column))  // another process may have added it meanwhile
      db.exec((std::string("ALTER TABLE jobs ADD COLUMN ") + m.definition).c_str(),
              std::string("cannot add the column '") + m.column + "' to the jobs table");
  for (const Migration& m : kSnapshotMigrations)
    if (!db.has_column("snapshots", m.column))
      db.exec((std::string("ALTER TABLE snapshots ADD COLUMN ") + m.definition).c_str(),
              std::string("cannot add the column '") + m.column + "' to the snapshots table");
  add_long_series(db);
  t.commit();
}

// Checks the schema of an existing database (reading only, so a read-only file can be listed;
// a writable file of an older schema is upgraded), or creates it in a new one.
void ensure_schema(Impl& db) {
  if (db.has_table("schema_version")) {
    check_schema_version(db);
    return migrate(db);
  }
  Transaction t(db);
  if (db.has_table("schema_version")) {  // created meanwhile
    check_schema_version(db);
    t.commit();
    return migrate(db);
  }
  StoreDb::refuse_foreign(db);
  db.exec(kSchema, "cannot create the schema");
  db.exec(kLongSchema, "cannot create the schema");
  Query(db, "INSERT INTO schema_version (version) VALUES (?)", "cannot create the schema")
      .bind(1, static_cast<long>(kSchemaVersion))
      .run();
  t.commit();
}

// ---- validation -------------------------------------------------------------------------------

void require_finite(const Impl& db, double v, const std::string& what) {
  if (!std::isfinite(v))
    throw StoreError(db.where() + ": refusing to write the non-finite value " + std::to_string(v) +
                     " of " + what);
}

std::string at_step(long step) { return " at step " + std::to_string(step); }

void check_frame(const Impl& db, const SeriesFrame& f, const std::vector<std::string>& columns,
                 const std::string& id) {
  if (f.values.size() != columns.size())
    throw StoreError(db.where() + ": job '" + id + "': a frame" + at_step(f.step) + " has " +
                     std::to_string(f.values.size()) + " values for " +
                     std::to_string(columns.size()) + " columns (set_columns first)");
  require_finite(db, f.time_ps, "time_ps" + at_step(f.step));
  for (std::size_t k = 0; k < columns.size(); ++k)
    require_finite(db, f.values[k], "column '" + columns[k] + "'" + at_step(f.step));
}

void check_size(const Impl& db, std::size_t got, std::size_t n, const std::string& field) {
  if (got != n)
    throw StoreError(db.where() + ": snapshot field '" + field + "' has " + std::to_string(got) +
                     " entries for " + std::to_string(n) + " elements");
}

void check_snapshot_sizes(const Impl& db, const Snapshot& s) {
  const std::size_t n = s.size();
  check_size(db, s.q.size(), n, "q");
  check_size(db, s.radius.size(), n, "radius");
  check_size(db, s.kind.size(), n, "kind");
  check_size(db, s.tube.size(), n, "tube");
  check_size(db, s.index.size(), n, "index");
  if (!s.v.empty()) check_size(db, s.v.size(), n, "v");
  for (const SnapshotBond& b : s.bonds)
    if (b.i < 0 || b.j < 0 || static_cast<std::size_t>(std::max(b.i, b.j)) >= n)
      throw StoreError(db.where() + ": snapshot bond " + std::to_string(b.i) + "-" +
                       std::to_string(b.j) + " names no element of " + std::to_string(n));
  std::set<std::string> names;
  for (const auto& [name, values] : s.scalars) {
    check_size(db, values.size(), n, name);
    if (name.empty() || !names.insert(name).second)
      throw StoreError(db.where() + ": snapshot scalar names must be unique and non-empty ('" +
                       name + "')");
  }
}

void check_snapshot_values(const Impl& db, const Snapshot& s) {
  const std::string at = at_step(s.step);
  require_finite(db, s.time_ps, "snapshot time_ps" + at);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const std::string el = " of element " + std::to_string(i) + at;
    for (int k = 0; k < 3; ++k) require_finite(db, s.x[i][k], "snapshot field 'x'" + el);
    for (int k = 0; k < 4; ++k) require_finite(db, s.q[i].coeffs()[k], "snapshot field 'q'" + el);
    require_finite(db, s.radius[i], "snapshot field 'radius'" + el);
    if (!s.v.empty())
      for (int k = 0; k < 3; ++k) require_finite(db, s.v[i][k], "snapshot field 'v'" + el);
    for (const auto& [name, values] : s.scalars)
      require_finite(db, values[i], "snapshot scalar '" + name + "'" + el);
  }
}

// ---- rows <-> records -------------------------------------------------------------------------

// Times as every table shows them, to the second (a daemon's job recorded by an older mdem kept
// the daemon's milliseconds).
JobRecord read_job(const Query& q) {
  return JobRecord{q.text(0),
                   q.text(1),
                   q.text(2),
                   q.text(3),
                   q.text(4),
                   q.text(5),
                   shown_time(q.text(6)),
                   shown_time(q.text(7)),
                   q.text(8),
                   q.integer(9),
                   q.text(10),
                   q.text(11)};
}

// A job run in-process whose process is gone without finishing it (killed outright, or its
// machine went down) is shown INTERRUPTED. Its state is read again once the process is known to
// be gone, so a job that finished meanwhile shows as it finished.
void show_interrupted(Impl& db, JobRecord& job) {
  const std::string running = job_state_name(v1::RUNNING);
  if (job.state != running || !job.server.empty() || job.runner.empty() || !runner_gone(job.runner))
    return;
  Query q(db, "SELECT state, reason FROM jobs WHERE id = ?", "cannot read the jobs");
  q.bind(1, job.id);
  if (!q.step()) return;
  job.state = q.text(0);
  job.reason = q.text(1);
  if (job.state != running) return;
  job.state = job_state_name(v1::INTERRUPTED);
  job.reason = "the process running it (" + runner_text(job.runner) +
               ") ended without finishing it (killed?); what it stored is kept";
}

std::vector<std::string> read_columns(Impl& db, const std::string& id) {
  Query q(db, "SELECT columns_json FROM jobs WHERE id = ?", "cannot read the columns");
  q.bind(1, id);
  if (!q.step()) return {};
  const auto j = nlohmann::json::parse(q.text(0), nullptr, false);
  if (!j.is_array()) throw StoreError(db.where() + ": job '" + id + "': corrupt column list");
  return j.get<std::vector<std::string>>();
}

bool job_exists(Impl& db, const std::string& id) {
  Query q(db, "SELECT 1 FROM jobs WHERE id = ?", "cannot read the jobs");
  q.bind(1, id);
  return q.step();
}

void require_job(Impl& db, const std::string& id) {
  if (!job_exists(db, id)) throw StoreError(db.where() + ": no job '" + id + "'");
}

long next_seq(Impl& db, const char* table, const std::string& id) {
  Query q(db, std::string("SELECT COALESCE(MAX(seq) + 1, 0) FROM ") + table + " WHERE job_id = ?",
          "cannot read");
  q.bind(1, id);
  q.step();
  return q.integer(0);
}

std::size_t count_rows(Impl& db, const char* table, const std::string& id) {
  Query q(db, std::string("SELECT COUNT(*) FROM ") + table + " WHERE job_id = ?", "cannot read");
  q.bind(1, id);
  q.step();
  return static_cast<std::size_t>(q.integer(0));
}

void check_blob(const Impl& db, const std::string& blob, std::size_t bytes, const char* field) {
  if (blob.size() != bytes)
    throw StoreError(db.where() + ": corrupt snapshot: field '" + field + "' has " +
                     std::to_string(blob.size()) + " bytes, expected " + std::to_string(bytes));
}

void decode_geometry(const Impl& db, const Query& q, std::size_t n, Snapshot& s) {
  const std::string x = q.blob(3), qq = q.blob(4), r = q.blob(5);
  check_blob(db, x, 24 * n, "x");
  check_blob(db, qq, 32 * n, "q");
  check_blob(db, r, 8 * n, "radius");
  s.x.resize(n);
  s.q.resize(n);
  s.radius.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    s.x[i] = Vec3(get_f64(x, 3 * i), get_f64(x, 3 * i + 1), get_f64(x, 3 * i + 2));
    s.q[i] = Quat(get_f64(qq, 4 * i), get_f64(qq, 4 * i + 1), get_f64(qq, 4 * i + 2),
                  get_f64(qq, 4 * i + 3));
    s.radius[i] = get_f64(r, i);
  }
}

std::vector<std::int32_t> decode_ints(const Impl& db, const std::string& blob, std::size_t n,
                                      const char* field) {
  check_blob(db, blob, 4 * n, field);
  std::vector<std::int32_t> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = get_i32(blob, i);
  return v;
}

void decode_scalars(const Impl& db, const Query& q, std::size_t n, Snapshot& s) {
  const auto names = nlohmann::json::parse(q.text(9), nullptr, false);
  if (!names.is_array()) throw StoreError(db.where() + ": corrupt snapshot: scalar names");
  const std::string blob = q.blob(10);
  check_blob(db, blob, 8 * n * names.size(), "scalars");
  std::size_t k = 0;
  for (const auto& name : names) {
    std::vector<double> values(n);
    for (std::size_t i = 0; i < n; ++i) values[i] = get_f64(blob, k++);
    s.scalars.emplace_back(name.get<std::string>(), std::move(values));
  }
}

// Velocities (columns 11: none or n) and bonds (12).
void decode_motion(const Impl& db, const Query& q, std::size_t n, Snapshot& s) {
  const std::string v = q.blob(11), bonds = q.blob(12);
  if (!v.empty()) {
    check_blob(db, v, 24 * n, "v");
    s.v.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      s.v[i] = Vec3(get_f64(v, 3 * i), get_f64(v, 3 * i + 1), get_f64(v, 3 * i + 2));
  }
  if (bonds.size() % 12 != 0) check_blob(db, bonds, bonds.size() / 12 * 12, "bonds");
  for (std::size_t k = 0; k < bonds.size() / 12; ++k) {
    const SnapshotBond b{get_i32(bonds, 3 * k), get_i32(bonds, 3 * k + 1),
                         static_cast<BondState>(get_i32(bonds, 3 * k + 2))};
    if (b.i < 0 || b.j < 0 || static_cast<std::size_t>(std::max(b.i, b.j)) >= n)
      throw StoreError(db.where() + ": corrupt snapshot: a bond names no element");
    s.bonds.push_back(b);
  }
}

Snapshot read_snapshot(const Impl& db, const Query& q) {
  Snapshot s;
  s.step = q.integer(0);
  s.time_ps = q.real(1);
  const std::size_t n = static_cast<std::size_t>(q.integer(2));
  decode_geometry(db, q, n, s);
  s.kind = decode_ints(db, q.blob(6), n, "kind");
  s.tube = decode_ints(db, q.blob(7), n, "tube");
  s.index = decode_ints(db, q.blob(8), n, "index");
  decode_scalars(db, q, n, s);
  decode_motion(db, q, n, s);
  return s;
}

void bind_snapshot(Query& q, const Snapshot& s) {
  std::string x, qq, scalars;
  x.reserve(24 * s.size());
  qq.reserve(32 * s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    for (int k = 0; k < 3; ++k) put_f64(x, s.x[i][k]);
    for (double c : {s.q[i].w(), s.q[i].x(), s.q[i].y(), s.q[i].z()}) put_f64(qq, c);
  }
  nlohmann::json names = nlohmann::json::array();
  for (const auto& [name, values] : s.scalars) {
    names.push_back(name);
    scalars += encode(values);
  }
  q.bind(3, s.step).bind(4, s.time_ps).bind(5, static_cast<long>(s.size()));
  q.bind_blob(6, x).bind_blob(7, qq).bind_blob(8, encode(s.radius));
  q.bind_blob(9, encode(s.kind)).bind_blob(10, encode(s.tube)).bind_blob(11, encode(s.index));
  q.bind(12, names.dump()).bind_blob(13, scalars);
  std::string v, bonds;
  v.reserve(24 * s.v.size());
  for (const Vec3& vi : s.v)
    for (int k = 0; k < 3; ++k) put_f64(v, vi[k]);
  for (const SnapshotBond& b : s.bonds)
    for (std::int32_t x : {b.i, b.j, static_cast<std::int32_t>(b.state)}) put_i32(bonds, x);
  q.bind_blob(14, v).bind_blob(15, bonds);
}

void check_state(const Impl& db, const std::string& id, const std::string& state) {
  const std::optional<JobState> s = parse_job_state(state);
  if (!s || !is_stored(*s))
    throw StoreError(db.where() + ": job '" + id + "': " +
                     (s ? "state '" + state + "' is shown, never stored"
                        : "unknown state '" + state + "' (allowed: " + job_state_names() + ")"));
}

// The writes below run inside the caller's transaction.

void write_columns(Impl& db, const std::string& id, const std::vector<std::string>& columns) {
  if (count_rows(db, "frames", id) > 0 && read_columns(db, id) != columns)
    throw StoreError(db.where() + ": job '" + id +
                     "': the columns cannot change after frames were written");
  Query(db, "UPDATE jobs SET columns_json = ? WHERE id = ?", "cannot set the columns")
      .bind(1, nlohmann::json(columns).dump())
      .bind(2, id)
      .run();
}

void write_frames(Impl& db, const std::string& id, const std::vector<SeriesFrame>& frames) {
  if (frames.empty()) return;
  const std::vector<std::string> columns = read_columns(db, id);
  for (const SeriesFrame& f : frames) check_frame(db, f, columns, id);
  long seq = next_seq(db, "frames", id);
  for (const SeriesFrame& f : frames) {
    Query q(db, "INSERT INTO frames (job_id, seq, step, time_ps, vals) VALUES (?, ?, ?, ?, ?)",
            "cannot write a frame of job '" + id + "'");
    q.bind(1, id).bind(2, seq).bind(3, f.step).bind(4, f.time_ps).bind_blob(5, encode(f.values));
    q.run();
    insert_frame_values(db, id, seq++, f.values);
  }
}

// The snapshot was checked (check_snapshot_sizes, check_snapshot_values) before.
void write_snapshot(Impl& db, const std::string& id, const Snapshot& snap) {
  Query q(db,
          std::string("INSERT INTO snapshots (job_id, seq, ") + kSnapshotColumns +
              ", v, bonds) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
          "cannot write a snapshot of job '" + id + "'");
  q.bind(1, id).bind(2, next_seq(db, "snapshots", id));
  bind_snapshot(q, snap);
  q.run();
}

void write_state(Impl& db, const std::string& id, const std::string& state,
                 const std::string& reason) {
  // A job that has not ended (again: a TIMEOUT job resumed) has no end time.
  Query q(db,
          "UPDATE jobs SET state = ?1, reason = ?2, finished_at = CASE WHEN ?4 THEN finished_at "
          "ELSE '' END WHERE id = ?3",
          "cannot set the state of job '" + id + "'");
  q.bind(1, state).bind(2, reason).bind(3, id).bind(4, static_cast<long>(is_final(state)));
  q.run();
}

long read_last_seq(Impl& db, const std::string& id) {
  Query q(
      db,
      std::string("SELECT ") + (db.remote_columns ? "last_seq" : "0") + " FROM jobs WHERE id = ?",
      "cannot read the jobs");
  q.bind(1, id);
  if (!q.step()) throw StoreError(db.where() + ": no job '" + id + "'");
  return q.integer(0);
}

void write_last_seq(Impl& db, const std::string& id, long seq) {
  db.require_remote_columns();
  Query q(db, "UPDATE jobs SET last_seq = ? WHERE id = ?",
          "cannot record the last event of job '" + id + "'");
  q.bind(1, seq).bind(2, id);
  q.run();
}

}  // namespace

struct ResultsStore::Impl : StoreDb {
  using StoreDb::StoreDb;

  // Runs f(db) as the only call on this connection, an error of the SQLite layer a StoreError.
  template <class F>
  decltype(auto) call(F&& f) {
    std::lock_guard lock(mutex());
    return store_errors([&]() -> decltype(auto) { return f(static_cast<StoreDb&>(*this)); });
  }
  // Runs write(db) in one transaction on job `id`, which must exist.
  template <class F>
  void write_job(const std::string& id, F&& write) {
    call([&](StoreDb& db) {
      Transaction t(db);
      require_job(db, id);
      write(db);
      t.commit();
    });
  }
};

// ---- public interface -------------------------------------------------------------------------

ResultsStore::ResultsStore(const std::string& path)
    : impl_(store_errors([&] { return std::make_unique<Impl>(path); })) {
  impl_->call([](StoreDb& db) { ensure_schema(db); });
}

ResultsStore::~ResultsStore() = default;

std::string ResultsStore::default_path() {
  if (const std::string db = env("MDEM_DB"); !db.empty()) return db;
  // XDG: an empty or relative $XDG_DATA_HOME is ignored.
  if (const std::string xdg = env("XDG_DATA_HOME"); !xdg.empty() && xdg.front() == '/')
    return (fs::path(xdg) / "mdem" / "results.db").string();
  const std::string home = env("HOME");
  if (home.empty())
    throw StoreError(
        "results database: neither $MDEM_DB, $XDG_DATA_HOME nor $HOME is set; give "
        "the database with --db PATH");
  return (fs::path(home) / ".local" / "share" / "mdem" / "results.db").string();
}

const std::string& ResultsStore::path() const { return impl_->path(); }

std::string ResultsStore::new_job_id() { return mdem::new_job_id(4); }

void ResultsStore::create_job(const JobRecord& job) {
  if (job.id.empty()) throw StoreError(impl_->where() + ": a job needs an id");
  check_state(*impl_, job.id, job.state);
  impl_->call([&](StoreDb& db) {
    const bool own = job.state == job_state_name(v1::RUNNING) && job.server.empty() &&
                     !db.missing.count("runner");
    Query q(db,
            std::string("INSERT INTO jobs (") + kFirstJobColumns + (own ? ", runner" : "") +
                ") VALUES (?, ?, ?, ?, ?, ?, ?, ?" + (own ? ", ?" : "") + ")",
            "cannot create job '" + job.id + "'");
    q.bind(1, job.id).bind(2, job.kind).bind(3, job.spec_json).bind(4, job.state);
    q.bind(5, job.reason).bind(6, job.summary_json);
    q.bind(7, job.created_at.empty() ? utc_now("%Y-%m-%dT%H:%M:%SZ") : job.created_at);
    q.bind(8, job.finished_at);
    if (own) q.bind(9, this_process());
    q.run();
  });
}

void ResultsStore::finish_job(const std::string& id, const std::string& state,
                              const std::string& reason, const std::string& summary_json) {
  if (!parse_job_state(state))
    throw StoreError(impl_->where() + ": job '" + id + "': unknown state '" + state + "'");
  impl_->call([&](StoreDb& db) {
    Query q(db,
            "UPDATE jobs SET state = ?, reason = ?, summary_json = ?, finished_at = ? WHERE id = ?",
            "cannot finish job '" + id + "'");
    q.bind(1, state).bind(2, reason).bind(3, summary_json);
    q.bind(4, utc_now("%Y-%m-%dT%H:%M:%SZ")).bind(5, id);
    q.run();
    if (sqlite3_changes(db.handle()) == 0) throw StoreError(db.where() + ": no job '" + id + "'");
  });
}

namespace {

// Deletes the rows of `table` (frames or snapshots) of job `id` past the first `keep` by seq.
void keep_first(Impl& db, const char* table, const std::string& id, std::size_t keep) {
  const std::size_t have = count_rows(db, table, id);
  if (have < keep)
    throw StoreError(db.where() + ": job '" + id + "' has " + std::to_string(have) + " " + table +
                     ", fewer than the " + std::to_string(keep) +
                     " its checkpoint was taken with (rows were deleted?)");
  if (have == keep) return;
  Query at(
      db,
      std::string("SELECT seq FROM ") + table + " WHERE job_id = ? ORDER BY seq LIMIT 1 OFFSET ?",
      "cannot read");
  at.bind(1, id).bind(2, static_cast<long>(keep));
  at.step();
  const long first_dropped = at.integer(0);
  if (std::string(table) == "frames")
    Query(db, "DELETE FROM frame_values WHERE job_id = ? AND seq >= ?", "cannot delete frames")
        .bind(1, id)
        .bind(2, first_dropped)
        .run();
  Query(db, std::string("DELETE FROM ") + table + " WHERE job_id = ? AND seq >= ?",
        std::string("cannot delete ") + table)
      .bind(1, id)
      .bind(2, first_dropped)
      .run();
}

}  // namespace

void ResultsStore::resume_job(const std::string& id, std::size_t frames, std::size_t snapshots) {
  impl_->write_job(id, [&](StoreDb& db) {
    keep_first(db, "frames", id, frames);
    keep_first(db, "snapshots", id, snapshots);
    const bool own = !db.missing.count("runner");
    Query q(db,
            std::string("UPDATE jobs SET state = ?, reason = '', summary_json = '', finished_at = "
                        "''") +
                (own ? ", runner = ?" : "") + " WHERE id = ?",
            "cannot resume job '" + id + "'");
    q.bind(1, job_state_name(v1::RUNNING));
    if (own)
      q.bind(2, this_process()).bind(3, id);
    else
      q.bind(2, id);
    q.run();
  });
}

void ResultsStore::set_state(const std::string& id, const std::string& state,
                             const std::string& reason) {
  check_state(*impl_, id, state);
  impl_->write_job(id, [&](StoreDb& db) { write_state(db, id, state, reason); });
}

void ResultsStore::upsert_remote_job(const JobRecord& job) {
  impl_->require_remote_columns();
  if (job.id.empty()) throw StoreError(impl_->where() + ": a job needs an id");
  if (job.server.empty())
    throw StoreError(impl_->where() + ": job '" + job.id + "': a daemon's job needs its server");
  check_state(*impl_, job.id, job.state);
  impl_->call([&](StoreDb& db) {
    Query q(db,
            std::string("INSERT INTO jobs (") + kRemoteJobColumns +
                ") VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT (id) DO UPDATE SET kind = "
                "excluded.kind, spec_json = excluded.spec_json, server = excluded.server, "
                "created_at = excluded.created_at, token_file = CASE WHEN excluded.token_file "
                "<> '' THEN excluded.token_file ELSE token_file END",
            "cannot record job '" + job.id + "'");
    q.bind(1, job.id).bind(2, job.kind).bind(3, job.spec_json).bind(4, job.state);
    q.bind(5, job.reason).bind(6, job.summary_json);
    q.bind(7, job.created_at.empty() ? utc_now("%Y-%m-%dT%H:%M:%SZ") : job.created_at);
    q.bind(8, job.finished_at).bind(9, job.server).bind(10, job.last_seq);
    q.bind(11, job.token_file);
    q.run();
  });
}

long ResultsStore::last_seq(const std::string& id) const {
  return impl_->call([&](StoreDb& db) { return read_last_seq(db, id); });
}

void ResultsStore::set_last_seq(const std::string& id, long seq) {
  impl_->write_job(id, [&](StoreDb& db) { write_last_seq(db, id, seq); });
}

void ResultsStore::apply_remote(const std::string& id, const RemoteUpdate& u) {
  impl_->require_remote_columns();
  if (u.state) check_state(*impl_, id, *u.state);
  for (const Snapshot& s : u.snapshots) {
    check_snapshot_sizes(*impl_, s);
    check_snapshot_values(*impl_, s);
  }
  impl_->call([&](StoreDb& db) {
    Transaction t(db);
    const long before = read_last_seq(db, id);
    if (u.last_seq < before)
      throw StoreError(db.where() + ": job '" + id + "': events up to " +
                       std::to_string(u.last_seq) + " arrive after event " +
                       std::to_string(before) + " was applied");
    if (u.columns) write_columns(db, id, *u.columns);
    write_frames(db, id, u.frames);
    for (const Snapshot& s : u.snapshots) write_snapshot(db, id, s);
    if (u.state) {
      write_state(db, id, *u.state, u.reason);
      if (is_final(*u.state)) {
        Query q(db, "UPDATE jobs SET finished_at = ? WHERE id = ? AND finished_at = ''",
                "cannot finish job '" + id + "'");
        q.bind(1, u.finished_at.empty() ? utc_now("%Y-%m-%dT%H:%M:%SZ") : u.finished_at);
        q.bind(2, id).run();
      }
    }
    if (u.report_json) {
      Query q(db, "UPDATE jobs SET summary_json = ? WHERE id = ?",
              "cannot store the report of job '" + id + "'");
      q.bind(1, *u.report_json).bind(2, id).run();
    }
    write_last_seq(db, id, u.last_seq);
    t.commit();
  });
}

void ResultsStore::set_columns(const std::string& id, const std::vector<std::string>& columns) {
  impl_->write_job(id, [&](StoreDb& db) { write_columns(db, id, columns); });
}

void ResultsStore::append_frames(const std::string& id, const std::vector<SeriesFrame>& frames) {
  impl_->write_job(id, [&](StoreDb& db) { write_frames(db, id, frames); });
}

void ResultsStore::append_snapshot(const std::string& id, const Snapshot& snap) {
  check_snapshot_sizes(*impl_, snap);
  check_snapshot_values(*impl_, snap);
  impl_->write_job(id, [&](StoreDb& db) { write_snapshot(db, id, snap); });
}

std::vector<JobRecord> ResultsStore::list() const {
  return impl_->call([&](StoreDb& db) {
    Query q(db, "SELECT " + db.job_columns() + " FROM jobs ORDER BY created_at DESC, rowid DESC",
            "cannot list the jobs");
    std::vector<JobRecord> jobs;
    while (q.step()) jobs.push_back(read_job(q));
    for (JobRecord& job : jobs) show_interrupted(db, job);
    return jobs;
  });
}

std::optional<JobRecord> ResultsStore::find(const std::string& id_or_prefix) const {
  if (id_or_prefix.empty()) return std::nullopt;
  constexpr long kShown = 20;
  const std::vector<JobRecord> matches = impl_->call([&](StoreDb& db) {
    {
      Query q(db, "SELECT " + db.job_columns() + " FROM jobs WHERE id = ?", "cannot read the jobs");
      q.bind(1, id_or_prefix);
      if (q.step()) {
        std::vector<JobRecord> found{read_job(q)};
        show_interrupted(db, found.front());
        return found;
      }
    }
    Query q(db,
            "SELECT " + db.job_columns() +
                " FROM jobs WHERE substr(id, 1, length(?1)) = ?1 ORDER BY id LIMIT ?2",
            "cannot read the jobs");
    q.bind(1, id_or_prefix).bind(2, kShown + 1);
    std::vector<JobRecord> found;
    while (q.step()) found.push_back(read_job(q));
    if (found.size() == 1) show_interrupted(db, found.front());
    return found;
  });
  if (matches.empty()) return std::nullopt;
  if (matches.size() == 1) return matches.front();
  std::string list;
  for (std::size_t k = 0; k < matches.size() && k < kShown; ++k)
    list += (k ? ", " : "") + matches[k].id;
  if (matches.size() > kShown) list += ", ...";
  throw StoreError("job id prefix '" + id_or_prefix + "' is ambiguous in '" + impl_->path() +
                   "': it matches " + list);
}

std::vector<std::string> ResultsStore::columns(const std::string& id) const {
  return impl_->call([&](StoreDb& db) { return read_columns(db, id); });
}

std::vector<SeriesFrame> ResultsStore::frames(const std::string& id) const {
  return impl_->call([&](StoreDb& db) {
    Query q(db, "SELECT step, time_ps, vals FROM frames WHERE job_id = ? ORDER BY seq",
            "cannot read the frames of job '" + id + "'");
    q.bind(1, id);
    std::vector<SeriesFrame> frames;
    while (q.step())
      frames.push_back({q.integer(0), q.real(1), decode_frame_values(db, q.blob(2))});
    return frames;
  });
}

std::size_t ResultsStore::frame_count(const std::string& id) const {
  return impl_->call([&](StoreDb& db) { return count_rows(db, "frames", id); });
}

std::size_t ResultsStore::snapshot_count(const std::string& id) const {
  return impl_->call([&](StoreDb& db) { return count_rows(db, "snapshots", id); });
}

std::vector<Snapshot> ResultsStore::snapshots(const std::string& id) const {
  return impl_->call([&](StoreDb& db) {
    Query q(db, "SELECT " + db.snapshot_columns() + " FROM snapshots WHERE job_id = ? ORDER BY seq",
            "cannot read the snapshots of job '" + id + "'");
    q.bind(1, id);
    std::vector<Snapshot> snaps;
    while (q.step()) snaps.push_back(read_snapshot(db, q));
    return snaps;
  });
}

std::optional<Snapshot> ResultsStore::snapshot(const std::string& id, std::size_t k) const {
  return impl_->call([&](StoreDb& db) -> std::optional<Snapshot> {
    Query q(db,
            "SELECT " + db.snapshot_columns() +
                " FROM snapshots WHERE job_id = ? ORDER BY seq LIMIT 1 OFFSET ?",
            "cannot read a snapshot of job '" + id + "'");
    q.bind(1, id).bind(2, static_cast<long>(k));
    if (!q.step()) return std::nullopt;
    return read_snapshot(db, q);
  });
}

}  // namespace mdem::cli
