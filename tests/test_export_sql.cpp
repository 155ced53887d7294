// The results database read with plain SQL (docs/results-db.md): the view frames_long names every
// value of a job's series with its unit. Checked through SQLite's C API (not ResultsStore) against
// the packed frames.vals BLOBs, decoded here byte by byte, and against what was written; a file
// as an mdem without the long form wrote it gains the table and view when opened, losing nothing.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <stdlib.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "../client/src/results_store.h"
#include "support.h"

namespace {

namespace fs = std::filesystem;
using mdem::SeriesFrame;
using mdem::cli::JobRecord;
using mdem::cli::ResultsStore;

const std::vector<std::string> kColumns = {"kinetic_eV", "bond_stretch_eV", "strain",
                                           "applied_torque_nNnm", "time_ps"};

struct TempDir : mdem::testing::TempDir {
  TempDir() : mdem::testing::TempDir("mdem-sql-test") {}
};

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

// A job with `count` frames of random values (one of them -0.0, one whole-valued).
std::vector<SeriesFrame> fill(ResultsStore& store, const std::string& id, int count) {
  JobRecord job;
  job.id = id;
  job.kind = "twist";
  job.spec_json = "{}";
  job.state = "RUNNING";
  store.create_job(job);
  store.set_columns(id, kColumns);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0, 1);
  std::vector<SeriesFrame> frames;
  for (int k = 0; k < count; ++k) {
    const double t = k * 0.02686;
    frames.push_back({k * 100L, t, {g(rng), -g(rng) * 1e3, k * 1e-3, g(rng) * 1e-17, t}});
  }
  frames[0].values[0] = -0.0;
  frames[1].values[1] = -4200.0;
  store.append_frames(id, frames);
  store.finish_job(id, "SUCCEEDED", "", "{}");
  return frames;
}

class Sql {
 public:
  explicit Sql(const std::string& path) {
    EXPECT_EQ(sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE, nullptr), SQLITE_OK);
  }
  ~Sql() { sqlite3_close(db_); }
  // Rows of a query, each column as text, a BLOB as its bytes and a REAL as its bits.
  struct Row {
    std::vector<std::string> text;
    std::vector<double> real;
  };
  std::vector<Row> rows(const std::string& sql) {
    sqlite3_stmt* q = nullptr;
    std::vector<Row> out;
    EXPECT_EQ(sqlite3_prepare_v2(db_, sql.c_str(), -1, &q, nullptr), SQLITE_OK)
        << sqlite3_errmsg(db_) << "\n"
        << sql;
    if (!q) return out;
    int rc;
    while ((rc = sqlite3_step(q)) == SQLITE_ROW) {
      Row r;
      for (int c = 0; c < sqlite3_column_count(q); ++c) {
        const void* b = sqlite3_column_blob(q, c);
        const int n = sqlite3_column_bytes(q, c);
        r.real.push_back(sqlite3_column_double(q, c));
        r.text.emplace_back(b ? static_cast<const char*>(b) : "", static_cast<std::size_t>(n));
      }
      out.push_back(std::move(r));
    }
    EXPECT_EQ(rc, SQLITE_DONE) << sqlite3_errmsg(db_);
    sqlite3_finalize(q);
    return out;
  }
  void exec(const char* sql) {
    ASSERT_EQ(sqlite3_exec(db_, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db_);
  }

 private:
  sqlite3* db_ = nullptr;
};

// frames.vals decoded here: little-endian float64, one per column.
std::map<long, std::vector<double>> blob_values(Sql& sql, const std::string& id) {
  std::map<long, std::vector<double>> by_step;
  for (const auto& r : sql.rows("SELECT step, vals FROM frames WHERE job_id = '" + id + "'")) {
    const std::string& b = r.text[1];
    std::vector<double> v(b.size() / 8);
    for (std::size_t k = 0; k < v.size(); ++k) {
      std::uint64_t u = 0;
      for (int i = 0; i < 8; ++i)
        u |= static_cast<std::uint64_t>(static_cast<unsigned char>(b[8 * k + i])) << (8 * i);
      v[k] = std::bit_cast<double>(u);
    }
    by_step[std::stol(r.text[0])] = v;
  }
  return by_step;
}

// Every value of frames_long equals the BLOB's and what was written, with the right unit.
void expect_long_form_matches(Sql& sql, const std::string& id,
                              const std::vector<SeriesFrame>& written) {
  const auto blobs = blob_values(sql, id);
  ASSERT_EQ(blobs.size(), written.size());
  const std::map<std::string, std::string> unit = {{"kinetic_eV", "eV"},
                                                   {"bond_stretch_eV", "eV"},
                                                   {"strain", ""},
                                                   {"applied_torque_nNnm", "nN·nm"},
                                                   {"time_ps", "ps"}};
  for (std::size_t c = 0; c < kColumns.size(); ++c) {
    const auto rows =
        sql.rows("SELECT step, time_ps, value, unit FROM frames_long WHERE job_id = '" + id +
                 "' AND name = '" + kColumns[c] + "' ORDER BY step");
    ASSERT_EQ(rows.size(), written.size()) << kColumns[c];
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const long step = std::stol(rows[k].text[0]);
      EXPECT_EQ(step, written[k].step);
      EXPECT_TRUE(same_bits(rows[k].real[1], written[k].time_ps));
      EXPECT_TRUE(same_bits(rows[k].real[2], blobs.at(step)[c]))
          << kColumns[c] << " at step " << step << ": " << rows[k].real[2] << " vs "
          << blobs.at(step)[c];
      EXPECT_TRUE(same_bits(rows[k].real[2], written[k].values[c])) << kColumns[c];
      EXPECT_EQ(rows[k].text[3], unit.at(kColumns[c])) << kColumns[c];
    }
  }
}

}  // namespace

TEST(ResultsSql, EnergiesOfAStoredRunAreQueryableByName) {
  TempDir tmp;
  const std::string path = tmp.file("results.db");
  std::vector<SeriesFrame> written;
  {
    ResultsStore store(path);
    written = fill(store, "j-a", 40);
    fill(store, "j-b", 3);  // another job's rows stay out of j-a's
  }
  Sql sql(path);
  expect_long_form_matches(sql, "j-a", written);
  // The total of two energy terms at one step, as a user would ask for it.
  const auto sum = sql.rows(
      "SELECT SUM(value) FROM frames_long WHERE job_id = 'j-a' AND step = 500 AND unit = 'eV'");
  ASSERT_EQ(sum.size(), 1u);
  EXPECT_DOUBLE_EQ(sum[0].real[0], written[5].values[0] + written[5].values[1]);
  EXPECT_EQ(sql.rows("SELECT 1 FROM frames_long WHERE job_id = 'j-b'").size(), 3 * kColumns.size());
}

TEST(ResultsSql, AFileWithoutTheLongFormGainsItWhenOpened) {
  TempDir tmp;
  const std::string path = tmp.file("old.db");
  std::vector<SeriesFrame> written;
  {
    ResultsStore store(path);
    written = fill(store, "j-old", 25);
  }
  {
    // What an mdem of before the long form wrote: the same schema without frame_values and
    // frames_long (the frames' BLOBs alone).
    Sql sql(path);
    sql.exec("DROP VIEW frames_long; DROP TABLE frame_values;");
    EXPECT_TRUE(sql.rows("SELECT name FROM sqlite_master WHERE name = 'frame_values'").empty());
  }
  {
    ResultsStore store(path);  // opening migrates
    const auto frames = store.frames("j-old");
    ASSERT_EQ(frames.size(), written.size());
    for (std::size_t k = 0; k < frames.size(); ++k)
      for (std::size_t c = 0; c < kColumns.size(); ++c)
        EXPECT_TRUE(same_bits(frames[k].values[c], written[k].values[c]));
    // New frames after the migration land in both forms.
    store.append_frames("j-old", {{9999, 1.5, {1, 2, 3, 4, 1.5}}});
    written.push_back({9999, 1.5, {1, 2, 3, 4, 1.5}});
  }
  Sql sql(path);
  expect_long_form_matches(sql, "j-old", written);
  // Opening again adds nothing twice.
  { ResultsStore again(path); }
  EXPECT_EQ(sql.rows("SELECT 1 FROM frame_values").size(), written.size() * kColumns.size());
}

// Snapshots keep their velocities and bonds; a file whose snapshots table predates them (no v,
// bonds columns) opens, gains the columns and reads its old snapshots without them.
TEST(ResultsSql, SnapshotsKeepVelocitiesAndBondsAndOldSnapshotsStillRead) {
  TempDir tmp;
  const std::string path = tmp.file("snap.db");
  mdem::Snapshot s;
  s.step = 7;
  s.time_ps = 0.25;
  for (int i = 0; i < 3; ++i) {
    s.x.emplace_back(i, 2.0 * i, -1.0 * i);
    s.q.push_back(mdem::Quat::Identity());
    s.v.emplace_back(0.1 * i, -0.0, 3e-17 * i);
    s.radius.push_back(1.0 + i);
    s.kind.push_back(2);
    s.tube.push_back(-1);
    s.index.push_back(-1);
  }
  s.bonds = {{0, 1, mdem::BondState::Intact},
             {1, 2, mdem::BondState::Yielded},
             {0, 2, mdem::BondState::Broken}};
  {
    ResultsStore store(path);
    fill(store, "j-s", 2);
    store.append_snapshot("j-s", s);
    const auto back = store.snapshot("j-s", 0);
    ASSERT_TRUE(back.has_value());
    ASSERT_EQ(back->v.size(), 3u);
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) EXPECT_TRUE(same_bits(back->v[i][k], s.v[i][k]));
    ASSERT_EQ(back->bonds.size(), 3u);
    for (int b = 0; b < 3; ++b) {
      EXPECT_EQ(back->bonds[b].i, s.bonds[b].i);
      EXPECT_EQ(back->bonds[b].j, s.bonds[b].j);
      EXPECT_EQ(back->bonds[b].state, s.bonds[b].state);
    }
    // A bond naming no element is refused, and nothing is written.
    mdem::Snapshot bad = s;
    bad.bonds.push_back({0, 3, mdem::BondState::Intact});
    EXPECT_THROW(store.append_snapshot("j-s", bad), mdem::cli::StoreError);
    EXPECT_EQ(store.snapshot_count("j-s"), 1u);
  }
  {
    Sql sql(path);
    sql.exec("ALTER TABLE snapshots DROP COLUMN v; ALTER TABLE snapshots DROP COLUMN bonds;");
  }
  {
    ResultsStore store(path);  // upgraded: the old snapshot reads without velocities or bonds
    EXPECT_TRUE(store.snapshot("j-s", 0)->v.empty());
    store.append_snapshot("j-s", s);
    EXPECT_EQ(store.snapshot("j-s", 1)->bonds.size(), 3u);
    EXPECT_EQ(store.snapshot("j-s", 1)->v.size(), 3u);
  }
}
