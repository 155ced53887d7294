// Times and wall-time limits as users read and write them (issue 16): one timestamp style (ISO
// 8601 UTC to the second) whatever was stored, durations as Slurm prints them, and --time-limit
// in Slurm's forms, refusing everything else with a message naming the flag, the value and the
// forms accepted.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <chrono>
#include <cmath>
#include <regex>

#include "../client/src/results_store.h"
#include "mdem/cli.h"
#include "mdem/time_text.h"
#include "support.h"

namespace {

using mdem::parse_time_limit;
using mdem::testing::contains;

TEST(TimeText, SlurmFormsAndUnitsGiveSeconds) {
  // Slurm's --time: MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM, D-HH:MM:SS.
  EXPECT_EQ(parse_time_limit("90", "--time-limit"), 90 * 60);
  EXPECT_EQ(parse_time_limit("15:30", "--time-limit"), 15 * 60 + 30);
  EXPECT_EQ(parse_time_limit("02:00:00", "--time-limit"), 7200);
  EXPECT_EQ(parse_time_limit("1-00:00:00", "--time-limit"), 86400);
  EXPECT_EQ(parse_time_limit("1-2", "--time-limit"), 86400 + 2 * 3600);
  EXPECT_EQ(parse_time_limit("1-2:30", "--time-limit"), 86400 + 2 * 3600 + 30 * 60);
  EXPECT_EQ(parse_time_limit("30-00:00:00", "--time-limit"), 30 * 86400);  // the maximum
  // A number with a unit.
  EXPECT_EQ(parse_time_limit("90s", "--time-limit"), 90);
  EXPECT_EQ(parse_time_limit("15m", "--time-limit"), 900);
  EXPECT_EQ(parse_time_limit("2h", "--time-limit"), 7200);
  EXPECT_EQ(parse_time_limit("1.5d", "--time-limit"), 1.5 * 86400);
  EXPECT_EQ(parse_time_limit("0.5s", "--time-limit"), 0.5);
}

TEST(TimeText, RefusesWithFlagValueAndForms) {
  for (const char* bad :
       {"",    "0",    "0s",   "00:00:00", "-5m",         "-1-00:00:00", "+2h",
        "2x",  "h",    "abc",  "1:2:3:4",  "1-",          "1:-2",        "2 h",
        "inf", "infh", "nanh", "1e999s",   "31-00:00:00", "721h",        "1e6h"}) {
    try {
      parse_time_limit(bad, "--time-limit");
      ADD_FAILURE() << "'" << bad << "' accepted";
    } catch (const std::invalid_argument& e) {
      const std::string m = e.what();
      EXPECT_TRUE(contains(m, "--time-limit: '" + std::string(bad) + "'")) << m;
      EXPECT_TRUE(contains(m, "HH:MM:SS") && contains(m, "30 days")) << m;
    }
  }
  // What is wrong, in words.
  auto why = [](const char* v) {
    try {
      parse_time_limit(v, "--time-limit");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_TRUE(contains(why("-5m"), "negative"));
  EXPECT_TRUE(contains(why("0"), "zero"));
  EXPECT_TRUE(contains(why("infh"), "not finite"));
  EXPECT_TRUE(contains(why("31-00:00:00"), "above the maximum"));
  // A huge value is not echoed in full.
  EXPECT_LT(why(std::string(5000, '9').c_str()).size(), 400u);
}

TEST(TimeText, OneTimestampStyleWhateverWasStored) {
  // The daemon stores milliseconds; everything shown is to the second.
  EXPECT_EQ(mdem::shown_time("2026-12-02T03:04:05.123Z"), "2026-12-02T03:04:05Z");
  EXPECT_EQ(mdem::shown_time("2026-12-02T03:04:05Z"), "2026-12-02T03:04:05Z");
  EXPECT_EQ(mdem::shown_time(""), "");
  EXPECT_EQ(mdem::shown_time("yesterday"), "yesterday");  // never made up
  EXPECT_EQ(mdem::shown_time("2026-12-02T03:04:05.Z"), "2026-12-02T03:04:05.Z");
  // Epoch seconds of a known instant (date -u -d 2026-12-02T03:04:05Z +%s = 1796180645).
  EXPECT_EQ(*mdem::epoch_seconds("2026-12-02T03:04:05Z"), 1796180645.0);
  EXPECT_NEAR(*mdem::epoch_seconds("2026-12-02T03:04:05.250Z"), 1796180645.25, 1e-6);
  EXPECT_FALSE(mdem::epoch_seconds("2026-12-02 03:04:05").has_value());
  const std::string now = mdem::utc_now_text();
  EXPECT_TRUE(std::regex_match(now, std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)"))) << now;
  const double now_s =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  EXPECT_NEAR(*mdem::epoch_seconds(now), now_s, 2.0);
}

TEST(TimeText, DurationsAsSlurmPrintsThem) {
  EXPECT_EQ(mdem::duration_text(0), "00:00:00");
  EXPECT_EQ(mdem::duration_text(59.9), "00:00:59");
  EXPECT_EQ(mdem::duration_text(3 * 3600 + 4 * 60 + 5), "03:04:05");
  EXPECT_EQ(mdem::duration_text(86400 + 3600), "1-01:00:00");
  EXPECT_EQ(mdem::duration_text(-1), "-");
  EXPECT_EQ(mdem::duration_text(std::nan("")), "-");
}

// `mdem submit --time-limit` refuses a bad value before anything is sent (exit 2, naming the
// flag, the value and the forms), with no daemon needed.
TEST(TimeText, SubmitRefusesABadTimeLimitFlag) {
  for (const char* bad : {"0", "-1h", "nan", "inf", "soon", "99999999999", "31d"}) {
    std::ostringstream out, err;
    const int code =
        mdem::cli::submit({"twist", "--time-limit", bad, "--server", "127.0.0.1:1"}, out, err);
    EXPECT_EQ(code, mdem::cli::kUsage) << bad << ": " << err.str();
    EXPECT_TRUE(contains(err.str(), "--time-limit: '" + std::string(bad) + "'")) << err.str();
    EXPECT_TRUE(contains(err.str(), "D-HH:MM:SS")) << err.str();
  }
  std::ostringstream out, err;
  EXPECT_EQ(mdem::cli::submit({"twist", "--time-limit"}, out, err), mdem::cli::kUsage);
  EXPECT_TRUE(contains(err.str(), "--time-limit")) << err.str();
}

// SQL on the file directly, bypassing ResultsStore.
void raw_sql(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK)
      << sqlite3_errmsg(db);
  sqlite3_close(db);
}

// A results database written before TIMEOUT existed (its jobs table's CHECK lists five states)
// and holding a daemon's times to the millisecond: opened by this mdem, it takes a TIMEOUT job
// and shows every time to the second.
TEST(TimeText, AnOlderResultsDatabaseTakesTimeoutAndShowsSeconds) {
  mdem::testing::TempDir tmp("mdem-times");
  const std::string path = tmp.file("r.db");
  { mdem::cli::ResultsStore created(path); }
  // Back to the older schema text (as an older mdem created it), and a row as it stored it.
  raw_sql(path,
          "PRAGMA writable_schema = ON; UPDATE sqlite_master SET sql = replace(sql, "
          "', ''TIMEOUT''))', '))') WHERE name = 'jobs'; PRAGMA schema_version = 100; "
          "PRAGMA writable_schema = OFF;");
  raw_sql(path,
          "INSERT INTO jobs (id, kind, spec_json, state, reason, summary_json, created_at, "
          "finished_at, server) VALUES ('j-old', 'twist', '{}', 'RUNNING', '', '', "
          "'2026-12-02T03:04:05.123Z', '', '127.0.0.1:1')");
  {
    // The older CHECK refuses TIMEOUT: what this mdem must widen.
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    EXPECT_NE(sqlite3_exec(db, "UPDATE jobs SET state = 'TIMEOUT'", nullptr, nullptr, nullptr),
              SQLITE_OK);
    sqlite3_close(db);
  }
  mdem::cli::ResultsStore store(path);
  store.set_state("j-old", "TIMEOUT", "wall-time limit 00:00:02 reached");
  auto job = store.find("j-old");
  ASSERT_TRUE(job.has_value());
  EXPECT_EQ(job->state, "TIMEOUT");
  EXPECT_EQ(job->created_at, "2026-12-02T03:04:05Z");
  // Queued again (`mdem resume`): not ended, so no end time.
  mdem::cli::RemoteUpdate u;
  u.state = "TIMEOUT";
  u.finished_at = "2026-12-02T03:05:00Z";
  u.last_seq = 3;
  store.apply_remote("j-old", u);
  EXPECT_EQ(store.find("j-old")->finished_at, "2026-12-02T03:05:00Z");
  store.set_state("j-old", "QUEUED", "resumed");
  EXPECT_EQ(store.find("j-old")->finished_at, "");
  // The file is sound after the schema edit.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, "PRAGMA integrity_check", -1, &st, nullptr), SQLITE_OK);
  ASSERT_EQ(sqlite3_step(st), SQLITE_ROW);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(sqlite3_column_text(st, 0))), "ok");
  sqlite3_finalize(st);
  sqlite3_close(db);
}

}  // namespace
