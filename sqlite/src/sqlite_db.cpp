#include "mdem/sqlite_db.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <thread>

namespace mdem {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

SqliteDb::SqliteDb(std::string path, std::string label, const char* synchronous,
                   int busy_timeout_ms, const Recognizer& recognize)
    : path_(std::move(path)), label_(std::move(label)) {
  if (path_.empty()) throw SqliteError(label_ + ": empty path");
  const fs::path parent = fs::path(path_).parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec)
      throw SqliteError(where() + ": cannot create the directory '" + parent.string() +
                        "': " + ec.message());
  }
  // A file the user may not write is opened read-only (SQLite's READWRITE means "if possible"):
  // it can still be read, and every write fails with SQLite's "readonly database".
  const int rc =
      sqlite3_open_v2(path_.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr);
  try {
    if (rc != SQLITE_OK) fail("cannot open");
    sqlite3_extended_result_codes(db_, 1);
    sqlite3_busy_timeout(db_, busy_timeout_ms);
    // The first statement only reads the file header and schema: a file that is not a database
    // fails here, and the owner may refuse a database that is not its own, both untouched. Only
    // then is the journal switched to WAL (which rewrites the header).
    exec("SELECT COUNT(*) FROM sqlite_master", "cannot read (is it an SQLite database?)");
    if (recognize) recognize(*this);
    switch_to_wal(busy_timeout_ms);
    exec((std::string("PRAGMA synchronous=") + synchronous).c_str(), "cannot configure");
    exec("PRAGMA foreign_keys=ON", "cannot configure");
  } catch (...) {
    // The destructor does not run when the constructor throws.
    for (auto& [sql, s] : statements_) sqlite3_finalize(s);
    statements_.clear();
    sqlite3_close_v2(db_);
    throw;
  }
}

SqliteDb::~SqliteDb() {
  for (auto& [sql, s] : statements_) sqlite3_finalize(s);
  if (db_) sqlite3_close_v2(db_);
}

// Two connections opening a new (rollback-journal) database at once can both hold the read lock
// and both ask for the exclusive lock the switch needs: SQLite fails one of them at once with
// SQLITE_BUSY rather than wait (waiting would deadlock), so the busy timeout never runs. The loser
// holds no lock once its statement has failed; it tries again, for up to the busy timeout, by
// when the winner has switched the file (switching a WAL file again takes no exclusive lock).
void SqliteDb::switch_to_wal(int busy_timeout_ms) {
  using Clock = std::chrono::steady_clock;
  const auto deadline = Clock::now() + std::chrono::milliseconds(busy_timeout_ms);
  for (auto pause = std::chrono::milliseconds(1);; pause = std::min(2 * pause, 50ms)) {
    const int rc = sqlite3_exec(db_, "PRAGMA journal_mode=WAL", nullptr, nullptr, nullptr);
    if (rc == SQLITE_OK) return;
    if ((rc & 0xff) != SQLITE_BUSY || Clock::now() + pause > deadline) fail("cannot switch to WAL");
    std::this_thread::sleep_for(pause);
  }
}

void SqliteDb::fail(const std::string& what) const {
  throw SqliteError(where() + ": " + what + ": " + (db_ ? sqlite3_errmsg(db_) : "out of memory"));
}

void SqliteDb::exec(const char* sql, const std::string& what) {
  if (sqlite3_exec(db_, sql, nullptr, nullptr, nullptr) != SQLITE_OK) fail(what);
}

sqlite3_stmt* SqliteDb::prepare(const std::string& sql) {
  auto it = statements_.find(sql);
  if (it != statements_.end()) return it->second;
  sqlite3_stmt* s = nullptr;
  if (sqlite3_prepare_v3(db_, sql.c_str(), -1, SQLITE_PREPARE_PERSISTENT, &s, nullptr) != SQLITE_OK)
    fail("cannot prepare '" + sql + "'");
  statements_.emplace(sql, s);
  return s;
}

bool SqliteDb::has_table(const std::string& name) {
  Query q(*this, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = ?", "cannot read");
  q.bind(1, name);
  return q.step();
}

bool SqliteDb::has_column(const std::string& table, const std::string& column) {
  Query q(*this, "SELECT 1 FROM pragma_table_info(?) WHERE name = ?", "cannot read");
  q.bind(1, table).bind(2, column);
  return q.step();
}

Query::Query(SqliteDb& db, const std::string& sql, std::string what)
    : db_(db), s_(db.prepare(sql)), what_(std::move(what)) {}

Query::~Query() {
  sqlite3_reset(s_);
  sqlite3_clear_bindings(s_);
}

Query& Query::bind(int i, const std::string& text) {
  return check(
      sqlite3_bind_text(s_, i, text.data(), static_cast<int>(text.size()), SQLITE_TRANSIENT));
}
Query& Query::bind(int i, double v) { return check(sqlite3_bind_double(s_, i, v)); }
Query& Query::bind(int i, long v) { return check(sqlite3_bind_int64(s_, i, v)); }
Query& Query::bind_blob(int i, const std::string& bytes) {
  return check(sqlite3_bind_blob64(s_, i, bytes.data(), bytes.size(), SQLITE_TRANSIENT));
}

bool Query::step() {
  const int rc = sqlite3_step(s_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  db_.fail(what_);
}

void Query::run() {
  while (step()) {
  }
  sqlite3_reset(s_);
}

std::string Query::text(int col) const {
  const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(s_, col));
  return p ? std::string(p, sqlite3_column_bytes(s_, col)) : std::string();
}

std::string Query::blob(int col) const {
  const auto* p = static_cast<const char*>(sqlite3_column_blob(s_, col));
  return p ? std::string(p, sqlite3_column_bytes(s_, col)) : std::string();
}

Query& Query::check(int rc) {
  if (rc != SQLITE_OK) db_.fail(what_);
  return *this;
}

Transaction::Transaction(SqliteDb& db) : db_(db) {
  db_.exec("BEGIN IMMEDIATE", "cannot begin a write");
}

Transaction::~Transaction() {
  if (!done_) sqlite3_exec(db_.handle(), "ROLLBACK", nullptr, nullptr, nullptr);
}

void Transaction::commit() {
  db_.exec("COMMIT", "cannot commit");
  done_ = true;
}

}  // namespace mdem
