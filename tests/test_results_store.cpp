// The local results database: jobs, prefixes, bit-exact frames and snapshots, refusal of
// non-finite values, and clear errors for unwritable, corrupt, foreign or newer database files.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <random>
#include <regex>
#include <set>

#include "../client/src/results_store.h"
#include "support.h"

namespace {

namespace fs = std::filesystem;
using mdem::Quat;
using mdem::SeriesFrame;
using mdem::Snapshot;
using mdem::Vec3;
using mdem::cli::JobRecord;
using mdem::cli::ResultsStore;
using mdem::cli::StoreError;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// A fresh temp directory for one test.
struct TempDir : mdem::testing::TempDir {
  TempDir() : mdem::testing::TempDir("mdem-store-test") {}
};

JobRecord make_job(const std::string& id, const std::string& created = "") {
  JobRecord j;
  j.id = id;
  j.kind = "twist";
  j.spec_json = R"({"kind":"twist","tubes":7})";
  j.state = "RUNNING";
  j.created_at = created;
  return j;
}

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

// Values that a lossy encoding would change: denormals, -0, extremes, non-terminating binaries.
std::vector<double> awkward_values(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  return {std::numeric_limits<double>::denorm_min(), -0.0,      std::numeric_limits<double>::max(),
          std::numeric_limits<double>::lowest(),     1.0 / 3.0, u(rng)};
}

Snapshot make_snapshot(std::size_t n, long step, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 3);
  Snapshot s;
  s.step = step;
  s.time_ps = step * 0.026861;
  std::vector<double> force(n), torque(n);
  for (std::size_t i = 0; i < n; ++i) {
    s.x.emplace_back(g(rng), g(rng), g(rng));
    s.q.push_back(Quat(g(rng), g(rng), g(rng), g(rng)).normalized());
    s.radius.push_back(0.678 + 1e-3 * g(rng));
    s.kind.push_back(static_cast<std::int32_t>(i % 3));
    s.tube.push_back(i % 3 == 0 ? static_cast<std::int32_t>(i / 7) : -1);
    s.index.push_back(static_cast<std::int32_t>(i));
    force[i] = std::abs(g(rng));
    torque[i] = g(rng) * 1e-17;
  }
  s.scalars = {{"force_nN", force}, {"torque_nNnm", torque}};
  return s;
}

void expect_same(const Snapshot& a, const Snapshot& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.step, b.step);
  EXPECT_TRUE(same_bits(a.time_ps, b.time_ps));
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(same_bits(a.x[i][k], b.x[i][k])) << i;
    for (int k = 0; k < 4; ++k) EXPECT_TRUE(same_bits(a.q[i].coeffs()[k], b.q[i].coeffs()[k]));
    EXPECT_TRUE(same_bits(a.radius[i], b.radius[i]));
  }
  EXPECT_EQ(a.kind, b.kind);
  EXPECT_EQ(a.tube, b.tube);
  EXPECT_EQ(a.index, b.index);
  ASSERT_EQ(a.scalars.size(), b.scalars.size());
  for (std::size_t k = 0; k < a.scalars.size(); ++k) {
    EXPECT_EQ(a.scalars[k].first, b.scalars[k].first);
    for (std::size_t i = 0; i < a.size(); ++i)
      EXPECT_TRUE(same_bits(a.scalars[k].second[i], b.scalars[k].second[i]));
  }
}

// Runs SQL on the file directly, bypassing ResultsStore.
void raw_sql(const std::string& path, const char* sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
  sqlite3_close(db);
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const StoreError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no StoreError";
  return "";
}

}  // namespace

TEST(ResultsStore, CreatesFinishesAndListsNewestFirst) {
  TempDir tmp;
  const std::string path = tmp.file("a/b/results.db");  // parent directories are created
  ResultsStore store(path);
  EXPECT_EQ(store.path(), path);
  store.create_job(make_job("j-1", "2026-01-01T00:00:00Z"));
  store.create_job(make_job("j-2", "2026-01-01T00:00:05Z"));
  store.create_job(make_job("j-3"));  // created_at filled in: now
  store.finish_job("j-1", "SUCCEEDED", "", R"({"state":"SUCCEEDED","summary":{"n":1}})");
  store.finish_job("j-2", "FAILED", "numerical instability at step 12", "{}");

  const auto jobs = store.list();
  ASSERT_EQ(jobs.size(), 3u);
  EXPECT_EQ(jobs[0].id, "j-3");
  EXPECT_EQ(jobs[1].id, "j-2");
  EXPECT_EQ(jobs[2].id, "j-1");
  EXPECT_TRUE(
      std::regex_match(jobs[0].created_at, std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")));
  EXPECT_EQ(jobs[0].state, "RUNNING");
  EXPECT_EQ(jobs[0].finished_at, "");
  EXPECT_EQ(jobs[1].state, "FAILED");
  EXPECT_EQ(jobs[1].reason, "numerical instability at step 12");
  EXPECT_EQ(jobs[2].state, "SUCCEEDED");
  EXPECT_EQ(jobs[2].summary_json, R"({"state":"SUCCEEDED","summary":{"n":1}})");
  EXPECT_EQ(jobs[2].spec_json, R"({"kind":"twist","tubes":7})");
  EXPECT_FALSE(jobs[2].finished_at.empty());
}

TEST(ResultsStore, RefusesDuplicateIdsUnknownStatesAndUnknownJobs) {
  TempDir tmp;
  ResultsStore store(tmp.file("r.db"));
  store.create_job(make_job("j-1"));
  EXPECT_NE(error_of([&] { store.create_job(make_job("j-1")); }).find("j-1"), std::string::npos);
  JobRecord bad = make_job("j-2");
  bad.state = "DONE";
  EXPECT_NE(error_of([&] { store.create_job(bad); }).find("unknown state 'DONE'"),
            std::string::npos);
  EXPECT_NE(error_of([&] { store.finish_job("j-9", "FAILED", "x", ""); }).find("no job 'j-9'"),
            std::string::npos);
  EXPECT_NE(error_of([&] { store.append_frames("j-9", {}); }).find("no job 'j-9'"),
            std::string::npos);
  EXPECT_NE(error_of([&] { store.append_snapshot("j-9", Snapshot{}); }).find("no job 'j-9'"),
            std::string::npos);
  EXPECT_EQ(store.list().size(), 1u);
}

TEST(ResultsStore, FindsByIdOrUniquePrefixAndRefusesAmbiguousPrefixes) {
  TempDir tmp;
  ResultsStore store(tmp.file("r.db"));
  for (const char* id : {"j-20260101-000000-aaaa", "j-20260101-000000-abcd", "j-2027", "j-20"})
    store.create_job(make_job(id));
  EXPECT_EQ(store.find("j-20260101-000000-aaaa")->id, "j-20260101-000000-aaaa");
  EXPECT_EQ(store.find("j-20260101-000000-ab")->id, "j-20260101-000000-abcd");
  EXPECT_EQ(store.find("j-2027")->id, "j-2027");
  EXPECT_EQ(store.find("j-20")->id, "j-20");  // an exact id wins over the prefix matches
  EXPECT_FALSE(store.find("j-3").has_value());
  EXPECT_FALSE(store.find("").has_value());
  EXPECT_FALSE(store.find("%").has_value());  // no LIKE wildcards
  const std::string msg = error_of([&] { store.find("j-20260101-000000-a"); });
  EXPECT_NE(msg.find("ambiguous"), std::string::npos) << msg;
  EXPECT_NE(msg.find("j-20260101-000000-aaaa"), std::string::npos) << msg;
  EXPECT_NE(msg.find("j-20260101-000000-abcd"), std::string::npos) << msg;
}

TEST(ResultsStore, FramesRoundTripBitForBit) {
  TempDir tmp;
  ResultsStore store(tmp.file("r.db"));
  store.create_job(make_job("j-1"));
  const std::vector<std::string> columns = {"a_eV", "b_eV", "c", "d", "e", "f"};
  store.set_columns("j-1", columns);
  std::mt19937_64 rng(7);
  std::vector<SeriesFrame> frames;
  for (long k = 0; k < 5; ++k) frames.push_back({k * 100, k * 2.6861 / 3, awkward_values(rng)});
  frames[0].time_ps = -0.0;
  store.append_frames("j-1", {frames.begin(), frames.begin() + 2});
  store.append_frames("j-1", {frames.begin() + 2, frames.end()});
  store.append_frames("j-1", {});

  EXPECT_EQ(store.columns("j-1"), columns);
  EXPECT_EQ(store.frame_count("j-1"), 5u);
  const auto back = store.frames("j-1");
  ASSERT_EQ(back.size(), frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) {
    EXPECT_EQ(back[k].step, frames[k].step);
    EXPECT_TRUE(same_bits(back[k].time_ps, frames[k].time_ps)) << k;
    ASSERT_EQ(back[k].values.size(), columns.size());
    for (std::size_t c = 0; c < columns.size(); ++c)
      EXPECT_TRUE(same_bits(back[k].values[c], frames[k].values[c])) << k << " " << c;
  }
  EXPECT_TRUE(store.frames("j-other").empty());
  EXPECT_TRUE(store.columns("j-other").empty());
}

TEST(ResultsStore, ColumnsAreFixedOnceFramesExist) {
  TempDir tmp;
  ResultsStore store(tmp.file("r.db"));
  store.create_job(make_job("j-1"));
  store.set_columns("j-1", {"a", "b"});
  store.set_columns("j-1", {"x", "y"});  // no frames yet: may change
  const std::string wrong = error_of([&] { store.append_frames("j-1", {{0, 0.0, {1.0}}}); });
  EXPECT_NE(wrong.find("1 values for 2 columns"), std::string::npos) << wrong;
  store.append_frames("j-1", {{0, 0.0, {1.0, 2.0}}});
  store.set_columns("j-1", {"x", "y"});  // unchanged: fine
  EXPECT_NE(error_of([&] { store.set_columns("j-1", {"x"}); }).find("cannot change"),
            std::string::npos);
}

TEST(ResultsStore, SnapshotsRoundTripBitForBit) {
  TempDir tmp;
  ResultsStore store(tmp.file("r.db"));
  store.create_job(make_job("j-1"));
  const Snapshot s0 = make_snapshot(50, 0, 1), s1 = make_snapshot(50, 1000, 2);
  Snapshot empty;  // no elements and no scalars is a valid snapshot
  empty.step = 2000;
  store.append_snapshot("j-1", s0);
  store.append_snapshot("j-1", s1);
  store.append_snapshot("j-1", empty);
  EXPECT_EQ(store.snapshot_count("j-1"), 3u);
  const auto all = store.snapshots("j-1");
  ASSERT_EQ(all.size(), 3u);
  expect_same(all[0], s0);
  expect_same(all[1], s1);
  expect_same(all[2], empty);
  expect_same(*store.snapshot("j-1", 1), s1);
  EXPECT_FALSE(store.snapshot("j-1", 3).has_value());
  EXPECT_EQ(store.snapshot_count("j-other"), 0u);
}

TEST(ResultsStore, NonFiniteValuesAreRefusedNamingTheColumnAndNothingIsWritten) {
  TempDir tmp;
  ResultsStore store(tmp.file("r.db"));
  store.create_job(make_job("j-1"));
  store.set_columns("j-1", {"kinetic_eV", "potential_eV"});
  const std::vector<SeriesFrame> frames = {{0, 0.0, {1.0, 2.0}}, {10, 0.1, {1.0, kNaN}}};
  std::string msg = error_of([&] { store.append_frames("j-1", frames); });
  EXPECT_NE(msg.find("potential_eV"), std::string::npos) << msg;
  EXPECT_NE(msg.find("step 10"), std::string::npos) << msg;
  msg = error_of([&] { store.append_frames("j-1", {{0, kInf, {1.0, 2.0}}}); });
  EXPECT_NE(msg.find("time_ps"), std::string::npos) << msg;
  EXPECT_EQ(store.frame_count("j-1"), 0u);  // the good first frame was not written either

  Snapshot s = make_snapshot(10, 5, 3);
  s.x[3].y() = kInf;
  msg = error_of([&] { store.append_snapshot("j-1", s); });
  EXPECT_NE(msg.find("'x'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("element 3"), std::string::npos) << msg;
  s = make_snapshot(10, 5, 3);
  s.scalars[1].second[9] = -kNaN;
  msg = error_of([&] { store.append_snapshot("j-1", s); });
  EXPECT_NE(msg.find("torque_nNnm"), std::string::npos) << msg;
  s = make_snapshot(10, 5, 3);
  s.q[0].w() = kNaN;
  EXPECT_NE(error_of([&] { store.append_snapshot("j-1", s); }).find("'q'"), std::string::npos);
  s = make_snapshot(10, 5, 3);
  s.radius.pop_back();
  EXPECT_NE(error_of([&] { store.append_snapshot("j-1", s); }).find("'radius'"), std::string::npos);
  EXPECT_EQ(store.snapshot_count("j-1"), 0u);
}

TEST(ResultsStore, UnwritablePathIsAnErrorNamingThePath) {
  TempDir tmp;
  const std::string plain = tmp.file("plain");
  std::ofstream(plain) << "a regular file, not a directory\n";
  const std::string path = plain + "/sub/results.db";
  const std::string msg = error_of([&] { ResultsStore store(path); });
  EXPECT_NE(msg.find(path), std::string::npos) << msg;
  // A directory where the file should be.
  fs::create_directory(tmp.file("dir.db"));
  const std::string msg2 = error_of([&] { ResultsStore store(tmp.file("dir.db")); });
  EXPECT_NE(msg2.find(tmp.file("dir.db")), std::string::npos) << msg2;
}

TEST(ResultsStore, CorruptFileIsAnErrorNotACrash) {
  TempDir tmp;
  const std::string path = tmp.file("garbage.db");
  {
    std::ofstream os(path, std::ios::binary);
    std::mt19937 rng(1);
    for (int i = 0; i < 8192; ++i) os.put(static_cast<char>(rng() & 0xff));
  }
  const std::string msg = error_of([&] { ResultsStore store(path); });
  EXPECT_NE(msg.find(path), std::string::npos) << msg;
  EXPECT_NE(msg.find("not a database"), std::string::npos) << msg;
  EXPECT_EQ(fs::file_size(path), 8192u);  // left as it was
}

TEST(ResultsStore, ForeignAndNewerDatabasesAreRefused) {
  TempDir tmp;
  const std::string foreign = tmp.file("foreign.db");
  raw_sql(foreign, "CREATE TABLE photos (id INTEGER)");
  std::string msg = error_of([&] { ResultsStore store(foreign); });
  EXPECT_NE(msg.find("not an mdem results database"), std::string::npos) << msg;

  const std::string newer = tmp.file("newer.db");
  { ResultsStore store(newer); }
  raw_sql(newer, "UPDATE schema_version SET version = 99");
  msg = error_of([&] { ResultsStore store(newer); });
  EXPECT_NE(msg.find("newer"), std::string::npos) << msg;
  EXPECT_NE(msg.find(newer), std::string::npos) << msg;
}

// A job run in-process records its process; once that process is gone without finishing the
// job (here: a child that creates it and exits), every reader sees INTERRUPTED, while a job of a
// live process, a finished job and a daemon's job read as stored.
TEST(ResultsStore, ARunningJobWhoseProcessIsGoneReadsInterrupted) {
  TempDir tmp;
  const std::string path = tmp.file("r.db");
  ResultsStore store(path);
  store.create_job(make_job("j-alive"));  // this process: alive
  JobRecord remote = make_job("j-remote");
  remote.server = "127.0.0.1:1";
  store.upsert_remote_job(remote);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    int code = 0;
    try {
      ResultsStore s(path);
      s.create_job(make_job("j-dead"));
      s.create_job(make_job("j-done"));
      s.finish_job("j-done", "SUCCEEDED", "", "{}");
    } catch (...) {
      code = 1;
    }
    _exit(code);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);

  const auto dead = store.find("j-dead");
  ASSERT_TRUE(dead.has_value());
  EXPECT_EQ(dead->state, "INTERRUPTED");
  EXPECT_NE(dead->reason.find("pid " + std::to_string(child)), std::string::npos) << dead->reason;
  EXPECT_EQ(store.find("j-alive")->state, "RUNNING");
  EXPECT_EQ(store.find("j-done")->state, "SUCCEEDED");
  EXPECT_EQ(store.find("j-remote")->state, "RUNNING");
  for (const JobRecord& j : store.list())
    EXPECT_EQ(j.state, j.id == "j-dead"   ? "INTERRUPTED"
                       : j.id == "j-done" ? "SUCCEEDED"
                                          : "RUNNING")
        << j.id;
  // It is how the job reads, not what is stored (a read-only file reads the same): the row
  // still says RUNNING.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* q = nullptr;
  sqlite3_prepare_v2(db, "SELECT state FROM jobs WHERE id = 'j-dead'", -1, &q, nullptr);
  ASSERT_EQ(sqlite3_step(q), SQLITE_ROW);
  EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(q, 0)), "RUNNING");
  sqlite3_finalize(q);
  sqlite3_close(db);
}

TEST(ResultsStore, ReopeningSeesEarlierDataAndTwoConnectionsShareTheFile) {
  TempDir tmp;
  const std::string path = tmp.file("r.db");
  const Snapshot s = make_snapshot(20, 40, 9);
  {
    ResultsStore store(path);
    store.create_job(make_job("j-1"));
    store.set_columns("j-1", {"e_eV"});
    store.append_frames("j-1", {{1, 0.5, {-3.25}}});
    store.append_snapshot("j-1", s);
  }
  ResultsStore a(path), b(path);
  ASSERT_TRUE(a.find("j-1").has_value());
  EXPECT_EQ(a.frames("j-1").at(0).values, std::vector<double>{-3.25});
  expect_same(a.snapshots("j-1").at(0), s);
  b.finish_job("j-1", "CANCELLED", "cancelled by the user", "");
  b.append_frames("j-1", {{2, 1.0, {-3.5}}});
  EXPECT_EQ(a.find("j-1")->state, "CANCELLED");
  EXPECT_EQ(a.frame_count("j-1"), 2u);
}

TEST(ResultsStore, NewJobIdsAreTimestampedAndRandom) {
  const std::regex form(R"(j-\d{8}-\d{6}-[0-9a-f]{4})");
  std::set<std::string> ids;
  for (int i = 0; i < 10; ++i) {
    const std::string id = ResultsStore::new_job_id();
    EXPECT_TRUE(std::regex_match(id, form)) << id;
    ids.insert(id);
  }
  EXPECT_GT(ids.size(), 1u);
}

TEST(ResultsStore, DefaultPathFollowsTheEnvironment) {
  struct Saved {
    const char* name;
    std::optional<std::string> value;
  };
  std::vector<Saved> saved;
  for (const char* n : {"MDEM_DB", "XDG_DATA_HOME", "HOME"}) {
    const char* v = std::getenv(n);
    saved.push_back({n, v ? std::optional<std::string>(v) : std::nullopt});
  }
  setenv("HOME", "/home/u", 1);
  unsetenv("MDEM_DB");
  unsetenv("XDG_DATA_HOME");
  EXPECT_EQ(ResultsStore::default_path(), "/home/u/.local/share/mdem/results.db");
  setenv("XDG_DATA_HOME", "relative/ignored", 1);
  EXPECT_EQ(ResultsStore::default_path(), "/home/u/.local/share/mdem/results.db");
  setenv("XDG_DATA_HOME", "/data", 1);
  EXPECT_EQ(ResultsStore::default_path(), "/data/mdem/results.db");
  setenv("MDEM_DB", "/tmp/x.db", 1);
  EXPECT_EQ(ResultsStore::default_path(), "/tmp/x.db");
  for (const Saved& s : saved) {
    if (s.value)
      setenv(s.name, s.value->c_str(), 1);
    else
      unsetenv(s.name);
  }
}
