#pragma once
// A connection to one SQLite database file with its prepared-statement cache, and the two ways
// to use it: a Query (bind, step, read; reset when done) and a Transaction (BEGIN IMMEDIATE,
// rolled back unless committed). Every failure throws SqliteError naming the database (by the
// label the owner gives, e.g. "job database '/var/lib/mdemd/jobs.db'") and SQLite's message.
#include <sqlite3.h>

#include <functional>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

namespace mdem {

struct SqliteError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class SqliteDb {
 public:
  // Checks that an opened file is the owner's (its tables, say), reading only; throws to refuse
  // it. Runs before anything is written or any pragma changes the file.
  using Recognizer = std::function<void(SqliteDb&)>;

  // Opens (creating) the file in WAL mode with foreign keys on, the given synchronous level
  // ("NORMAL" or "FULL") and a busy timeout. Creates missing parent directories. A file the
  // process may not write is opened read-only (readable; writes fail with SqliteError). A file
  // that is not an SQLite database, or that `recognize` refuses, is left exactly as it was.
  SqliteDb(std::string path, std::string label, const char* synchronous = "NORMAL",
           int busy_timeout_ms = 10000, const Recognizer& recognize = {});
  ~SqliteDb();
  SqliteDb(const SqliteDb&) = delete;
  SqliteDb& operator=(const SqliteDb&) = delete;

  const std::string& path() const { return path_; }
  // "<label> '<path>'", for messages.
  std::string where() const { return label_ + " '" + path_ + "'"; }
  [[noreturn]] void fail(const std::string& what) const;
  void exec(const char* sql, const std::string& what);
  sqlite3_stmt* prepare(const std::string& sql);
  sqlite3* handle() { return db_; }
  // Held by the owner around each call: one call at a time per connection.
  std::mutex& mutex() { return mu_; }

  bool has_table(const std::string& name);
  bool has_column(const std::string& table, const std::string& column);

 private:
  void switch_to_wal(int busy_timeout_ms);

  std::string path_, label_;
  sqlite3* db_ = nullptr;
  std::map<std::string, sqlite3_stmt*> statements_;  // prepared once, reset after each use
  std::mutex mu_;
};

// One use of a cached prepared statement.
class Query {
 public:
  Query(SqliteDb& db, const std::string& sql, std::string what);
  ~Query();
  Query(const Query&) = delete;
  Query& operator=(const Query&) = delete;

  Query& bind(int i, const std::string& text);
  Query& bind(int i, double v);
  Query& bind(int i, long v);
  Query& bind_blob(int i, const std::string& bytes);
  // True while there is a row to read.
  bool step();
  void run();  // steps to the end
  std::string text(int col) const;
  std::string blob(int col) const;
  double real(int col) const { return sqlite3_column_double(s_, col); }
  long integer(int col) const { return static_cast<long>(sqlite3_column_int64(s_, col)); }

 private:
  Query& check(int rc);
  SqliteDb& db_;
  sqlite3_stmt* s_;
  std::string what_;
};

// BEGIN IMMEDIATE (takes the write lock up front, waiting up to the busy timeout); rolls back
// unless committed.
class Transaction {
 public:
  explicit Transaction(SqliteDb& db);
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void commit();

 private:
  SqliteDb& db_;
  bool done_ = false;
};

}  // namespace mdem
