// SqliteDb, the connection every database of the project opens (results, job queue): connections
// that open a new database at the same moment all get it in WAL mode (two `mdem run --db F`
// started together, or a reader polling a file a job is creating; CI once failed a job with
// "cannot switch to WAL: database is locked" that way), and a lock held for longer than the busy
// timeout still fails, naming the database and the lock, after about that timeout.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <atomic>
#include <barrier>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "mdem/sqlite_db.h"
#include "support.h"

namespace {

using mdem::SqliteDb;
using mdem::SqliteError;
using mdem::testing::TempDir;

std::string journal_mode(const std::string& path) {
  sqlite3* db = nullptr;
  sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
  sqlite3_stmt* s = nullptr;
  std::string mode = "?";
  if (sqlite3_prepare_v2(db, "PRAGMA journal_mode", -1, &s, nullptr) == SQLITE_OK &&
      sqlite3_step(s) == SQLITE_ROW)
    mode = reinterpret_cast<const char*>(sqlite3_column_text(s, 0));
  sqlite3_finalize(s);
  sqlite3_close_v2(db);
  return mode;
}

TEST(SqliteDb, ConnectionsOpeningANewDatabaseAtOnceAllGetItInWalMode) {
  const TempDir dir("mdem-sqlite-race");
  constexpr int kThreads = 4, kRounds = 60;
  std::atomic<int> failures = 0;
  std::string first_error;
  std::mutex error_mu;
  for (int round = 0; round < kRounds; ++round) {
    const std::string path = dir.file("race-" + std::to_string(round) + ".db");
    std::barrier start(kThreads);
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
      threads.emplace_back([&] {
        start.arrive_and_wait();
        try {
          SqliteDb db(path, "test database", "NORMAL", 10000);
        } catch (const SqliteError& e) {
          ++failures;
          const std::lock_guard lock(error_mu);
          if (first_error.empty()) first_error = e.what();
        }
      });
    for (auto& t : threads) t.join();
    EXPECT_EQ(journal_mode(path), "wal") << path;
  }
  EXPECT_EQ(failures.load(), 0) << "of " << kThreads * kRounds << " opens; first: " << first_error;
}

TEST(SqliteDb, ALockHeldPastTheBusyTimeoutFailsNamingTheDatabaseAfterAboutTheTimeout) {
  const TempDir dir("mdem-sqlite-held");
  const std::string path = dir.file("held.db");
  // A rollback-journal database another connection reads in an open transaction: its shared lock
  // keeps the file from being switched to WAL until it commits.
  sqlite3* other = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &other), SQLITE_OK);
  ASSERT_EQ(
      sqlite3_exec(other, "CREATE TABLE t(x); INSERT INTO t VALUES (1); BEGIN; SELECT * FROM t;",
                   nullptr, nullptr, nullptr),
      SQLITE_OK);
  const auto t0 = std::chrono::steady_clock::now();
  std::string message;
  try {
    SqliteDb db(path, "test database", "NORMAL", 300);
  } catch (const SqliteError& e) {
    message = e.what();
  }
  const double waited =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_NE(message.find("test database '" + path + "': cannot switch to WAL"), std::string::npos)
      << message;
  EXPECT_NE(message.find("locked"), std::string::npos) << message;
  EXPECT_GE(waited, 0.25);
  EXPECT_LT(waited, 5.0);
  EXPECT_EQ(journal_mode(path), "delete");
  // Once the reader is done, the same open succeeds and switches the file.
  sqlite3_exec(other, "COMMIT", nullptr, nullptr, nullptr);
  sqlite3_close_v2(other);
  EXPECT_NO_THROW(SqliteDb(path, "test database", "NORMAL", 300));
  EXPECT_EQ(journal_mode(path), "wal");
}

}  // namespace
