// `mdem` as the client of the mdemd daemon, without the daemon: connection settings (flags >
// environment > config file, and clear errors for bad files), an unreachable server, request ids,
// the results database's upgrade of an older file, and a fake in-process JobService that streams
// canned events (a snapshot in three chunks, a Coalesced notice, a final report) and drops the
// stream once mid-snapshot, so `mdem watch` must resume at the right event with nothing missing
// and nothing twice. The CLI runs as a subprocess, as a user runs it.
#include <fcntl.h>
#include <google/protobuf/util/message_differencer.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "../client/src/remote.h"
#include "../client/src/results_store.h"
#include "mdem/cli.h"
#include "mdem/snapshot_proto.h"
#include "mdem/v1/service.grpc.pb.h"
#include "support.h"

namespace {

namespace fs = std::filesystem;
namespace v1 = mdem::v1;
using json = nlohmann::json;
using mdem::cli::ConnectionSettings;
using mdem::cli::JobRecord;
using mdem::cli::ResultsStore;
using mdem::cli::SettingsError;
using mdem::cli::StoreError;

// ---- helpers ----------------------------------------------------------------------------------

struct TempDir : mdem::testing::TempDir {
  TempDir() : mdem::testing::TempDir("mdem-remote-test") {}
};

std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct Result {
  int code = -1;
  std::string out, err;
  double seconds = 0;
};

// The environment of a subprocess: none of the user's mdem settings, HOME in `dir` (so no real
// config file is read), plus `env`.
std::string env_prefix(const TempDir& dir, const std::map<std::string, std::string>& env) {
  std::string cmd =
      "env -u MDEM_SERVER -u MDEM_TOKEN -u MDEM_CONFIG -u MDEM_DB -u XDG_CONFIG_HOME "
      "-u XDG_DATA_HOME HOME=" +
      quote(dir.path().string());
  for (const auto& [k, v] : env) cmd += " " + k + "=" + quote(v);
  return cmd;
}

// Runs `mdem args` (already shell-quoted where needed) and collects exit code, stdout, stderr.
Result mdem_cli(const TempDir& dir, const std::string& args,
                const std::map<std::string, std::string>& env = {}) {
  const std::string err_file = dir.file("stderr.txt");
  const std::string cmd = "cd " + quote(dir.path().string()) + " && " + env_prefix(dir, env) + " " +
                          quote(MDEM_CLI_PATH) + " " + args + " 2>" + quote(err_file) +
                          " </dev/null";
  const auto t0 = std::chrono::steady_clock::now();
  FILE* pipe = popen(cmd.c_str(), "r");
  Result r;
  if (!pipe) return r;
  std::array<char, 4096> buf;
  while (std::size_t n = fread(buf.data(), 1, buf.size(), pipe)) r.out.append(buf.data(), n);
  const int status = pclose(pipe);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = slurp(err_file);
  return r;
}

// The environment as a map, for resolve_connection.
mdem::cli::Env env_of(std::map<std::string, std::string> vars) {
  return [vars](const std::string& name) -> std::optional<std::string> {
    const auto it = vars.find(name);
    if (it == vars.end()) return std::nullopt;
    return it->second;
  };
}

std::string settings_error(const std::map<std::string, std::string>& flags,
                           const mdem::cli::Env& env) {
  try {
    mdem::cli::resolve_connection(flags, env);
  } catch (const SettingsError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no SettingsError";
  return "";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// ---- connection settings ----------------------------------------------------------------------

TEST(RemoteSettings, FlagsBeatEnvironmentBeatConfigFile) {
  TempDir d;
  d.write("token-flag", "\n  tok-flag  \nsecond-line\n");
  fs::create_directories(d.path() / "cfg");
  d.write("cfg/token", "tok-config\n");
  const std::string cfg =
      d.write("cfg/config.yaml", "server: config-host:1111\ntoken_file: token\ntls: true\n");
  const auto env_all = env_of({{"MDEM_CONFIG", cfg},
                               {"MDEM_SERVER", "env-host:2222"},
                               {"MDEM_TOKEN", "tok-env"},
                               {"HOME", d.path().string()}});

  // Only the config file: its server, its token file (relative to the file), its tls.
  ConnectionSettings c = mdem::cli::resolve_connection({}, env_of({{"MDEM_CONFIG", cfg}}));
  EXPECT_EQ(c.server, "config-host:1111");
  EXPECT_EQ(c.token, "tok-config");
  EXPECT_TRUE(c.tls);
  EXPECT_EQ(c.config_path, cfg);
  EXPECT_TRUE(contains(c.server_origin, cfg)) << c.server_origin;

  // The environment beats the file.
  c = mdem::cli::resolve_connection({}, env_all);
  EXPECT_EQ(c.server, "env-host:2222");
  EXPECT_EQ(c.server_origin, "$MDEM_SERVER");
  EXPECT_EQ(c.token, "tok-env");
  EXPECT_TRUE(c.tls);  // still from the file: the environment does not set it

  // Flags beat both; the token file's first non-empty line, trimmed.
  c = mdem::cli::resolve_connection(
      {{"--server", "flag-host:3333"}, {"--token-file", d.file("token-flag")}}, env_all);
  EXPECT_EQ(c.server, "flag-host:3333");
  EXPECT_EQ(c.token, "tok-flag");

  // A job's recorded server comes right after --server.
  c = mdem::cli::resolve_connection({}, env_all, "job-host:4444");
  EXPECT_EQ(c.server, "job-host:4444");
  c = mdem::cli::resolve_connection({{"--server", "flag-host:3333"}}, env_all, "job-host:4444");
  EXPECT_EQ(c.server, "flag-host:3333");

  // --ca-file implies TLS.
  c = mdem::cli::resolve_connection({{"--server", "h:1"}, {"--ca-file", "/x.pem"}},
                                    env_of({{"HOME", d.path().string()}}));
  EXPECT_TRUE(c.tls);
  EXPECT_EQ(c.ca_file, "/x.pem");
}

TEST(RemoteSettings, ConfigFileIsFoundThroughXdgThenHome) {
  TempDir d;
  fs::create_directories(d.path() / "xdg" / "mdem");
  fs::create_directories(d.path() / "home" / ".config" / "mdem");
  d.write("xdg/mdem/config.yaml", "server: xdg-host:1\n");
  d.write("home/.config/mdem/config.yaml", "server: home-host:2\n");
  const std::string home = (d.path() / "home").string(), xdg = (d.path() / "xdg").string();
  EXPECT_EQ(
      mdem::cli::resolve_connection({}, env_of({{"HOME", home}, {"XDG_CONFIG_HOME", xdg}})).server,
      "xdg-host:1");
  EXPECT_EQ(mdem::cli::resolve_connection({}, env_of({{"HOME", home}})).server, "home-host:2");
  // No config file at all: no server, and the message says how to name one.
  const std::string e = settings_error({}, env_of({{"HOME", d.path().string()}}));
  EXPECT_TRUE(contains(e, "--server")) << e;
  EXPECT_TRUE(contains(e, "MDEM_SERVER")) << e;
}

TEST(RemoteSettings, BadConfigFilesAndTokenFilesAreClearErrors) {
  TempDir d;
  struct Case {
    std::string text;
    std::vector<std::string> expect;
  };
  const std::vector<Case> cases = {
      {"server: [unclosed\n", {"malformed YAML", "line"}},
      {"server: h:1\ncolour: blue\n", {"unknown key 'colour'", "allowed"}},
      {"server: h:1\ntls: maybe\n", {"'tls'", "true or false", "maybe"}},
      {"server: [a, b]\n", {"'server'", "string"}},
      {"- server\n", {"mapping"}},
      {"server: not-an-address\n", {"not HOST:PORT", "server"}},
      {"server: h:1\ntoken_file: missing-token\n", {"missing-token", "no such file"}},
  };
  for (const Case& c : cases) {
    const std::string cfg = d.write("config.yaml", c.text);
    const std::string e = settings_error({}, env_of({{"MDEM_CONFIG", cfg}}));
    EXPECT_TRUE(contains(e, cfg) || contains(e, "missing-token")) << c.text << " -> " << e;
    for (const std::string& part : c.expect)
      EXPECT_TRUE(contains(e, part)) << c.text << " -> " << e << " (wanted " << part << ")";
  }
  // Token files: missing, empty, and a token with a space inside.
  const auto env = env_of({{"HOME", d.path().string()}});
  EXPECT_TRUE(contains(settings_error({{"--server", "h:1"}, {"--token-file", d.file("nope")}}, env),
                       "no such file"));
  d.write("empty", "\n   \n");
  EXPECT_TRUE(contains(
      settings_error({{"--server", "h:1"}, {"--token-file", d.file("empty")}}, env), "is empty"));
  d.write("spaced", "to ken\n");
  EXPECT_TRUE(contains(
      settings_error({{"--server", "h:1"}, {"--token-file", d.file("spaced")}}, env), "space"));
  // An explicit $MDEM_CONFIG that does not exist.
  EXPECT_TRUE(contains(settings_error({}, env_of({{"MDEM_CONFIG", d.file("absent.yaml")}})),
                       "MDEM_CONFIG"));
}

TEST(RemoteSettings, TheCliExitsWithUsageErrorsForBadSettings) {
  TempDir d;
  const std::string bad = d.write("bad.yaml", "server: h:1\nport: 3\n");
  Result r = mdem_cli(d, "cancel j-1", {{"MDEM_CONFIG", bad}});
  EXPECT_EQ(r.code, mdem::cli::kUsage) << r.err;
  EXPECT_TRUE(contains(r.err, bad)) << r.err;
  EXPECT_TRUE(contains(r.err, "unknown key 'port'")) << r.err;

  const std::string malformed = d.write("malformed.yaml", "server: h:1\ntls: {true\n");
  r = mdem_cli(d, "submit twist --layers 2", {{"MDEM_CONFIG", malformed}});
  EXPECT_EQ(r.code, mdem::cli::kUsage) << r.err;
  EXPECT_TRUE(contains(r.err, "malformed YAML")) << r.err;

  const std::string typed = d.write("typed.yaml", "server: h:1\ntls: [1]\n");
  r = mdem_cli(d, "watch j-1", {{"MDEM_CONFIG", typed}});
  EXPECT_EQ(r.code, mdem::cli::kUsage) << r.err;
  EXPECT_TRUE(contains(r.err, "'tls'")) << r.err;

  r = mdem_cli(d, "cancel j-1 --server 127.0.0.1:9 --token-file " + quote(d.file("no-token")));
  EXPECT_EQ(r.code, mdem::cli::kUsage) << r.err;
  EXPECT_TRUE(contains(r.err, "no-token")) << r.err;

  r = mdem_cli(d, "watch j-1");  // nothing names a daemon
  EXPECT_EQ(r.code, mdem::cli::kUsage) << r.err;
  EXPECT_TRUE(contains(r.err, "--server")) << r.err;

  r = mdem_cli(d, "ls --all");  // a daemon-only flag without a daemon
  EXPECT_EQ(r.code, mdem::cli::kUsage) << r.err;
}

TEST(RemoteCli, UnreachableServerIsExitCode3NamingTheAddress) {
  TempDir d;
  const std::string db = quote(d.file("r.db"));
  for (const std::string& cmd :
       {"submit twist --layers 2 --length 8 --server 127.0.0.1:1 --db " + db,
        std::string("ls --server 127.0.0.1:1"), std::string("show j-1 --server 127.0.0.1:1"),
        "cancel j-1 --server 127.0.0.1:1 --db " + db,
        "watch j-1 --server 127.0.0.1:1 --db " + db}) {
    const Result r = mdem_cli(d, cmd);
    EXPECT_EQ(r.code, mdem::cli::kConnection) << cmd << "\n" << r.err;
    EXPECT_TRUE(contains(r.err, "cannot reach mdemd at 127.0.0.1:1")) << cmd << "\n" << r.err;
    EXPECT_LT(r.seconds, 5.0) << cmd;
  }
  // The submit says which request id to retry with.
  const Result r =
      mdem_cli(d, "submit twist --layers 2 --server 127.0.0.1:1 --request-id again-1 --db " + db);
  EXPECT_TRUE(contains(r.err, "--request-id again-1")) << r.err;
}

TEST(RemoteCli, BadRequestIdsAreRefusedBeforeConnecting) {
  TempDir d;
  for (const std::string& id : {std::string("has space"), std::string("semi;colon"),
                                std::string("ünïcode"), std::string(129, 'a')}) {
    const Result r = mdem_cli(d, "submit twist --layers 2 --server 127.0.0.1:1 --request-id " +
                                     quote(id) + " --db " + quote(d.file("r.db")));
    EXPECT_EQ(r.code, mdem::cli::kUsage) << id << "\n" << r.err;
    EXPECT_TRUE(contains(r.err, "--request-id")) << r.err;
    EXPECT_FALSE(contains(r.err, "cannot reach")) << r.err;
  }
  EXPECT_NO_THROW(mdem::cli::check_request_id("A-z_0.9:x"));
  EXPECT_TRUE(std::regex_match(mdem::cli::new_request_id(), std::regex("r-[0-9a-f]{24}")));
  EXPECT_NE(mdem::cli::new_request_id(), mdem::cli::new_request_id());
}

TEST(RemoteCli, HelpCoversTheNewCommandsAndTheConnection) {
  TempDir d;
  Result r = mdem_cli(d, "--help");
  EXPECT_EQ(r.code, 0);
  for (const char* part : {"submit", "watch", "cancel", "config.yaml", "MDEM_SERVER", "3 "})
    EXPECT_TRUE(contains(r.out, part)) << part;
  for (const char* cmd : {"submit", "watch", "cancel", "ls", "show"}) {
    r = mdem_cli(d, std::string(cmd) + " --help");
    EXPECT_EQ(r.code, 0) << cmd;
    EXPECT_TRUE(contains(r.out, std::string("Usage: mdem ") + cmd)) << r.out;
    EXPECT_TRUE(contains(r.out, "--server HOST:PORT")) << cmd;
    EXPECT_TRUE(contains(r.out, "--token-file")) << cmd;
  }
  r = mdem_cli(d, "submit --help");
  EXPECT_TRUE(contains(r.out, "--torque")) << r.out;  // the same spec flags as `mdem run twist`
}

// ---- the results database ---------------------------------------------------------------------

void raw_sql(const std::string& path, const char* sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, sql, nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
  sqlite3_close(db);
}

std::set<std::string> job_columns(const std::string& path) {
  sqlite3* db = nullptr;
  sqlite3_open(path.c_str(), &db);
  sqlite3_stmt* s = nullptr;
  sqlite3_prepare_v2(db, "SELECT name FROM pragma_table_info('jobs')", -1, &s, nullptr);
  std::set<std::string> names;
  while (sqlite3_step(s) == SQLITE_ROW)
    names.insert(reinterpret_cast<const char*>(sqlite3_column_text(s, 0)));
  sqlite3_finalize(s);
  sqlite3_close(db);
  return names;
}

// The schema as the first release wrote it (version 1, no server / last_seq columns).
constexpr const char* kOldSchema = R"sql(
CREATE TABLE schema_version (version INTEGER NOT NULL);
INSERT INTO schema_version (version) VALUES (1);
CREATE TABLE jobs (
  id TEXT PRIMARY KEY NOT NULL,
  kind TEXT NOT NULL,
  spec_json TEXT NOT NULL,
  state TEXT NOT NULL CHECK (state IN ('QUEUED', 'RUNNING', 'SUCCEEDED', 'FAILED', 'CANCELLED')),
  reason TEXT NOT NULL DEFAULT '',
  summary_json TEXT NOT NULL DEFAULT '',
  created_at TEXT NOT NULL,
  finished_at TEXT NOT NULL DEFAULT '',
  columns_json TEXT NOT NULL DEFAULT '[]'
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
  UNIQUE (job_id, seq)
);
INSERT INTO jobs (id, kind, spec_json, state, summary_json, created_at, finished_at, columns_json)
  VALUES ('j-old', 'twist', '{}', 'SUCCEEDED', '{"state":"SUCCEEDED"}', '2025-01-01T00:00:00Z',
          '2025-01-01T00:01:00Z', '["a_eV"]');
INSERT INTO frames VALUES ('j-old', 0, 0, 0.0, x'000000000000F03F');
)sql";

TEST(RemoteStore, AnOlderDatabaseGetsTheNewColumnsAndKeepsItsJobs) {
  TempDir d;
  const std::string path = d.file("old.db");
  raw_sql(path, kOldSchema);
  ASSERT_FALSE(job_columns(path).count("server"));
  {
    ResultsStore store(path);
    const auto cols = job_columns(path);
    EXPECT_TRUE(cols.count("server"));
    EXPECT_TRUE(cols.count("last_seq"));
    const auto old = store.find("j-old");
    ASSERT_TRUE(old.has_value());
    EXPECT_EQ(old->state, "SUCCEEDED");
    EXPECT_EQ(old->server, "");
    EXPECT_EQ(old->last_seq, 0);
    ASSERT_EQ(store.frames("j-old").size(), 1u);
    EXPECT_EQ(store.frames("j-old")[0].values, std::vector<double>{1.0});

    JobRecord rec;
    rec.id = "j-remote";
    rec.kind = "twist";
    rec.spec_json = "{}";
    rec.state = "QUEUED";
    rec.server = "h:1";
    store.upsert_remote_job(rec);
    store.set_last_seq("j-remote", 7);
  }
  // Reopening (the columns exist now) changes nothing and keeps what was written.
  ResultsStore again(path);
  const auto remote = again.find("j-remote");
  ASSERT_TRUE(remote.has_value());
  EXPECT_EQ(remote->server, "h:1");
  EXPECT_EQ(again.last_seq("j-remote"), 7);
  EXPECT_EQ(again.list().size(), 2u);
}

TEST(RemoteStore, RemoteUpdatesAreAllOrNothingAndNeverGoBack) {
  TempDir d;
  ResultsStore store(d.file("u.db"));
  JobRecord rec;
  rec.id = "j-1";
  rec.kind = "twist";
  rec.spec_json = "{}";
  rec.state = "QUEUED";
  rec.server = "h:1";
  store.upsert_remote_job(rec);

  mdem::cli::RemoteUpdate u;
  u.columns = std::vector<std::string>{"a_eV"};
  u.frames = {{0, 0.0, {1.0}}, {10, 1.0, {2.0}}};
  u.state = "RUNNING";
  u.last_seq = 4;
  store.apply_remote("j-1", u);
  EXPECT_EQ(store.last_seq("j-1"), 4);
  EXPECT_EQ(store.find("j-1")->state, "RUNNING");

  // A frame with a non-finite value: the whole batch is refused, last_seq stays.
  mdem::cli::RemoteUpdate bad;
  bad.frames = {{20, 2.0, {3.0}}, {30, 3.0, {std::nan("")}}};
  bad.state = "SUCCEEDED";
  bad.last_seq = 9;
  EXPECT_THROW(store.apply_remote("j-1", bad), StoreError);
  EXPECT_EQ(store.last_seq("j-1"), 4);
  EXPECT_EQ(store.frame_count("j-1"), 2u);
  EXPECT_EQ(store.find("j-1")->state, "RUNNING");

  // Going back is refused (events would be applied twice).
  mdem::cli::RemoteUpdate back;
  back.last_seq = 3;
  EXPECT_THROW(store.apply_remote("j-1", back), StoreError);

  // set_state does not finish; upsert keeps state and last_seq of a known job.
  store.set_state("j-1", "CANCELLED", "by the test");
  EXPECT_EQ(store.find("j-1")->finished_at, "");
  rec.spec_json = R"({"name":"x"})";
  store.upsert_remote_job(rec);
  EXPECT_EQ(store.find("j-1")->state, "CANCELLED");
  EXPECT_EQ(store.find("j-1")->spec_json, R"({"name":"x"})");
  EXPECT_EQ(store.last_seq("j-1"), 4);
}

// ---- a fake daemon ----------------------------------------------------------------------------

constexpr const char* kJobId = "j-fake-1";
constexpr const char* kToken = "tok-1";

mdem::Snapshot make_snapshot() {
  mdem::Snapshot s;
  s.step = 10;
  s.time_ps = 0.25;
  for (int i = 0; i < 40; ++i) {
    s.x.emplace_back(0.1 * i, -0.2 * i + 1.0 / 3.0, 1e-300 * i);
    s.q.push_back(mdem::Quat(1, 0.01 * i, -0.02 * i, 0.5).normalized());
    s.radius.push_back(0.678 + 1e-9 * i);
    s.kind.push_back(i % 2);
    s.tube.push_back(i / 8);
    s.index.push_back(i);
  }
  std::vector<double> force(40);
  for (int i = 0; i < 40; ++i) force[i] = std::sqrt(2.0) * i;
  s.scalars = {{"force_nN", force}};
  return s;
}

const json& report() {
  static const json r = {
      {"job_id", kJobId},
      {"kind", "twist"},
      {"state", "SUCCEEDED"},
      {"summary",
       {{"morphology", "twisted"},
        {"twist_angle_deg", 12.5},
        {"shift_angle_deg", 3.25},
        {"topological_charge", 0},
        {"max_topological_charge", 0},
        {"rope_radius_nm", 2.5},
        {"initial_rope_radius_nm", 2.5},
        {"length_nm", 8.136},
        {"applied_torque_nNnm", 1.0},
        {"grip_reaction_nNnm", 0.99},
        {"simulated_ps", 1.5}}},
      {"accuracy", {{"energy_balance_error", 0.001}, {"dt_ps", 0.02}, {"dt_over_critical", 0.6}}},
      {"performance", {{"wall_s", 2.0}, {"steps", 60}, {"element_steps_per_s", 1000.0}}}};
  return r;
}

// The canned log of the job: state, columns, progress, 4 frames, a snapshot in 3 chunks between
// them, a Coalesced notice, a log line, the final state and the report.
std::vector<v1::JobEvent> canned_events() {
  std::vector<v1::JobEvent> evs;
  auto add = [&]() -> v1::JobEvent& {
    evs.emplace_back();
    evs.back().set_seq(static_cast<long>(evs.size()));
    evs.back().set_time("2026-01-02T03:04:" + std::to_string(10 + evs.size()) + "Z");
    return evs.back();
  };
  auto frame = [&](long step) {
    v1::EnergyFrame* f = add().mutable_frame();
    f->set_step(step);
    f->set_time_ps(step * 0.025);
    f->add_values(1.0 + step);
    f->add_values(-0.5 * step);
    f->add_values(1.0 / 3.0 + step);
  };
  add().mutable_state()->set_state(v1::RUNNING);  // 1
  {
    v1::SeriesColumns* c = add().mutable_columns();  // 2
    for (const char* name : {"kinetic_eV", "potential_eV", "twist_angle_deg"}) c->add_names(name);
  }
  {
    v1::Progress* p = add().mutable_progress();  // 3
    p->set_step(0);
    p->set_total_steps(60);
    p->set_phase("ramp");
  }
  frame(0);   // 4
  frame(10);  // 5
  std::string bytes;
  mdem::snapshot_to_proto(make_snapshot()).SerializeToString(&bytes);
  const std::size_t third = bytes.size() / 3;
  for (int k = 0; k < 3; ++k) {  // 6, 7, 8
    v1::SnapshotChunk* c = add().mutable_snapshot();
    c->set_step(10);
    c->set_time_ps(0.25);
    c->set_index(k);
    c->set_count(3);
    c->set_data(bytes.substr(k * third, k == 2 ? std::string::npos : third));
  }
  frame(20);  // 9
  {
    v1::Coalesced* c = add().mutable_coalesced();  // 10
    c->set_frames(3);
    c->set_snapshots(1);
    c->set_up_to_step(50);
  }
  {
    v1::LogLine* l = add().mutable_log();  // 11
    l->set_level("warning");
    l->set_text("fake daemon says hello");
  }
  {
    v1::Progress* p = add().mutable_progress();  // 12
    p->set_step(60);
    p->set_total_steps(60);
    p->set_time_ps(1.5);
    p->set_phase("hold");
  }
  frame(60);                                          // 13
  add().mutable_state()->set_state(v1::SUCCEEDED);    // 14
  add().mutable_report()->set_json(report().dump());  // 15
  return evs;
}

class FakeJobService final : public v1::JobService::Service {
 public:
  std::mutex mu;
  std::vector<long> watch_from;            // from_seq of every WatchJob call
  std::vector<std::string> authorization;  // of every call
  std::vector<v1::SubmitJobRequest> submits;
  int cancels = 0;
  std::vector<v1::JobEvent> events = canned_events();
  long drop_after = 7;  // the first `drops` streams end with UNAVAILABLE after this event
  int drops = 1;
  long block_after = 0;  // > 0: after this event the stream waits until the client cancels
  std::atomic<bool> blocking{false};

  v1::JobInfo info(v1::JobState state) const {
    v1::JobInfo i;
    i.set_job_id(kJobId);
    i.set_user("alice");
    i.set_kind("twist");
    i.set_name("fake");
    i.set_state(state);
    i.set_created_at("2026-01-02T03:04:05Z");
    i.set_total_steps(60);
    i.mutable_spec()->mutable_twist()->set_layers(2);
    return i;
  }

  grpc::Status SubmitJob(grpc::ServerContext* ctx, const v1::SubmitJobRequest* req,
                         v1::SubmitJobResponse* resp) override {
    if (auto s = check(ctx); !s.ok()) return s;
    std::lock_guard lock(mu);
    if (req->spec().name() == "too-big")
      return {grpc::StatusCode::INVALID_ARGUMENT,
              "twist.layers: 9 is above this server's limit of 8 layers"};
    if (req->spec().name() == "limit")
      return {grpc::StatusCode::RESOURCE_EXHAUSTED, "max_queued_jobs: 2 queued jobs per user"};
    bool seen = false;
    for (const auto& s : submits) seen = seen || s.request_id() == req->request_id();
    submits.push_back(*req);
    *resp->mutable_job() = info(v1::QUEUED);
    *resp->mutable_job()->mutable_spec() = req->spec();
    resp->set_created(!seen);
    return grpc::Status::OK;
  }
  grpc::Status GetJob(grpc::ServerContext* ctx, const v1::GetJobRequest* req,
                      v1::JobInfo* resp) override {
    if (auto s = check(ctx); !s.ok()) return s;
    if (req->job_id() != kJobId)
      return {grpc::StatusCode::NOT_FOUND, "no job '" + req->job_id() + "'"};
    *resp = info(v1::SUCCEEDED);
    resp->set_report_json(report().dump());
    return grpc::Status::OK;
  }
  grpc::Status ListJobs(grpc::ServerContext* ctx, const v1::ListJobsRequest* req,
                        v1::ListJobsResponse* resp) override {
    if (auto s = check(ctx); !s.ok()) return s;
    if (req->all_users()) return {grpc::StatusCode::PERMISSION_DENIED, "alice is not an admin"};
    *resp->add_jobs() = info(v1::RUNNING);
    return grpc::Status::OK;
  }
  grpc::Status CancelJob(grpc::ServerContext* ctx, const v1::CancelJobRequest* req,
                         v1::JobInfo* resp) override {
    if (auto s = check(ctx); !s.ok()) return s;
    if (req->job_id() != kJobId)
      return {grpc::StatusCode::NOT_FOUND, "no job '" + req->job_id() + "'"};
    std::lock_guard lock(mu);
    ++cancels;
    *resp = info(v1::CANCELLED);
    resp->set_reason("cancelled by alice");
    return grpc::Status::OK;
  }
  grpc::Status WatchJob(grpc::ServerContext* ctx, const v1::WatchJobRequest* req,
                        grpc::ServerWriter<v1::JobEvent>* writer) override {
    if (auto s = check(ctx); !s.ok()) return s;
    if (req->job_id() != kJobId)
      return {grpc::StatusCode::NOT_FOUND, "no job '" + req->job_id() + "'"};
    bool drop;
    {
      std::lock_guard lock(mu);
      watch_from.push_back(req->from_seq());
      drop = drops > 0;
      if (drop) --drops;
    }
    for (const v1::JobEvent& ev : events) {
      if (ev.seq() < req->from_seq()) continue;
      if (drop && ev.seq() > drop_after)
        return {grpc::StatusCode::UNAVAILABLE, "fake daemon restarting"};
      if (block_after > 0 && ev.seq() > block_after) {
        blocking = true;
        while (!ctx->IsCancelled()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
        return grpc::Status::CANCELLED;
      }
      writer->Write(ev);
    }
    return grpc::Status::OK;
  }

 private:
  grpc::Status check(grpc::ServerContext* ctx) {
    const auto& md = ctx->client_metadata();
    const auto it = md.find("authorization");
    const std::string auth =
        it == md.end() ? "" : std::string(it->second.data(), it->second.size());
    {
      std::lock_guard lock(mu);
      authorization.push_back(auth);
    }
    if (auth != std::string("Bearer ") + kToken)
      return {grpc::StatusCode::UNAUTHENTICATED, "unknown token"};
    return grpc::Status::OK;
  }
};

class FakeDaemon : public ::testing::Test {
 protected:
  void SetUp() override {
    grpc::ServerBuilder builder;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port_);
    builder.RegisterService(&service_);
    server_ = builder.BuildAndStart();
    ASSERT_TRUE(server_);
    ASSERT_GT(port_, 0);
    token_file_ = dir_.write("token", std::string(kToken) + "\n");
    db_ = dir_.file("results.db");
  }
  void TearDown() override {
    server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
  }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  // The connection and database flags every command here gets.
  std::string conn() const {
    return "--server " + address() + " --token-file " + quote(token_file_);
  }
  std::string db() const { return " --db " + quote(db_); }
  std::vector<long> watch_from() {
    std::lock_guard lock(service_.mu);
    return service_.watch_from;
  }

  TempDir dir_;
  FakeJobService service_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
  std::string token_file_, db_;
};

// Checks the local copy of the canned job: every frame once, the one snapshot as sent, the state,
// the report and the last event.
void expect_complete_job(const std::string& db) {
  ResultsStore store(db);
  const auto rec = store.find(kJobId);
  ASSERT_TRUE(rec.has_value());
  EXPECT_EQ(rec->state, "SUCCEEDED");
  EXPECT_EQ(rec->kind, "twist");
  EXPECT_EQ(rec->summary_json, report().dump());
  EXPECT_EQ(rec->finished_at, "2026-01-02T03:04:24Z");  // the time of the SUCCEEDED event
  EXPECT_EQ(store.last_seq(kJobId), 15);
  EXPECT_EQ(store.columns(kJobId),
            (std::vector<std::string>{"kinetic_eV", "potential_eV", "twist_angle_deg"}));
  const auto frames = store.frames(kJobId);
  std::vector<long> steps;
  for (const auto& f : frames) steps.push_back(f.step);
  EXPECT_EQ(steps, (std::vector<long>{0, 10, 20, 60}));
  for (const auto& f : frames)
    EXPECT_EQ(f.values, (std::vector<double>{1.0 + f.step, -0.5 * f.step, 1.0 / 3.0 + f.step}));
  ASSERT_EQ(store.snapshot_count(kJobId), 1u);
  const v1::SnapshotData stored = mdem::snapshot_to_proto(*store.snapshot(kJobId, 0));
  const v1::SnapshotData sent = mdem::snapshot_to_proto(make_snapshot());
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(stored, sent))
      << stored.DebugString().substr(0, 400);
}

TEST_F(FakeDaemon, SubmitRecordsTheJobUnderTheDaemonsIdAndSendsTheToken) {
  const Result r = mdem_cli(dir_, "submit twist --layers 2 --length 8 --torque 1 --name smoke " +
                                      conn() + db() + " --request-id req-1 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["job_id"], kJobId);
  EXPECT_EQ(j["request_id"], "req-1");
  EXPECT_EQ(j["created"], true);
  EXPECT_EQ(j["state"], "QUEUED");
  EXPECT_EQ(j["server"], address());
  {
    std::lock_guard lock(service_.mu);
    ASSERT_EQ(service_.submits.size(), 1u);
    const v1::SubmitJobRequest& req = service_.submits[0];
    EXPECT_EQ(req.request_id(), "req-1");
    EXPECT_EQ(req.spec().twist().layers(), 2);
    EXPECT_DOUBLE_EQ(req.spec().twist().torque_nn_nm(), 1.0);
    EXPECT_TRUE(req.spec().twist().has_hold_ps());  // finalized: defaults filled in
    EXPECT_EQ(service_.authorization.back(), std::string("Bearer ") + kToken);
  }
  ResultsStore store(db_);
  const auto rec = store.find(kJobId);
  ASSERT_TRUE(rec.has_value());
  EXPECT_EQ(rec->state, "QUEUED");
  EXPECT_EQ(rec->server, address());
  EXPECT_EQ(rec->kind, "twist");
  EXPECT_EQ(json::parse(rec->spec_json)["name"], "smoke");

  // Without --request-id: a random one, printed, and the same one sent; the job id on stdout.
  const Result again = mdem_cli(dir_, "submit twist --layers 2 " + conn() + db());
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(again.out, std::string(kJobId) + "\n");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(again.err, m, std::regex("request id (r-[0-9a-f]{24})")))
      << again.err;
  std::lock_guard lock(service_.mu);
  EXPECT_EQ(service_.submits.back().request_id(), m[1].str());
}

TEST_F(FakeDaemon, SpecErrorsAreRefusedLocallyAndServerRefusalsMapToExitCodes) {
  // A bad value never reaches the daemon: the same message as `mdem run twist`.
  Result r = mdem_cli(dir_, "submit twist --layers 11 " + conn() + db());
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(r.err, "twist.layers (--layers)")) << r.err;
  {
    std::lock_guard lock(service_.mu);
    EXPECT_TRUE(service_.submits.empty());
  }
  // INVALID_ARGUMENT: the server's message, exit 2.
  r = mdem_cli(dir_, "submit twist --layers 2 --name too-big " + conn() + db());
  EXPECT_EQ(r.code, mdem::cli::kUsage) << r.err;
  EXPECT_TRUE(contains(r.err, "above this server's limit of 8 layers")) << r.err;
  // RESOURCE_EXHAUSTED: the limit named, exit 1.
  r = mdem_cli(dir_, "submit twist --layers 2 --name limit " + conn() + db());
  EXPECT_EQ(r.code, mdem::cli::kJobFailed) << r.err;
  EXPECT_TRUE(contains(r.err, "max_queued_jobs")) << r.err;
  // UNAUTHENTICATED: a wrong token, and none at all.
  const std::string wrong = dir_.write("wrong-token", "nope\n");
  r = mdem_cli(dir_, "submit twist --layers 2 --server " + address() + " --token-file " +
                         quote(wrong) + db());
  EXPECT_EQ(r.code, mdem::cli::kJobFailed) << r.err;
  EXPECT_TRUE(contains(r.err, "refused the token")) << r.err;
  r = mdem_cli(dir_, "ls --server " + address());
  EXPECT_EQ(r.code, mdem::cli::kJobFailed) << r.err;
  EXPECT_TRUE(contains(r.err, "--token-file")) << r.err;
  // PERMISSION_DENIED, NOT_FOUND.
  r = mdem_cli(dir_, "ls --all " + conn());
  EXPECT_EQ(r.code, mdem::cli::kJobFailed) << r.err;
  EXPECT_TRUE(contains(r.err, "not an admin")) << r.err;
  r = mdem_cli(dir_, "show j-nope " + conn());
  EXPECT_EQ(r.code, mdem::cli::kJobFailed) << r.err;
  EXPECT_TRUE(contains(r.err, "no job 'j-nope'")) << r.err;
}

TEST_F(FakeDaemon, WatchResumesAfterADroppedStreamWithNoGapAndNoDuplicate) {
  // Submitted first (the record exists, with its server): the watch needs no --server then.
  ASSERT_EQ(mdem_cli(dir_, "submit twist --layers 2 " + conn() + db()).code, 0);
  const Result r =
      mdem_cli(dir_, "watch " + std::string(kJobId) + " --token-file " + quote(token_file_) + db());
  ASSERT_EQ(r.code, 0) << r.err;
  // The first stream ended with UNAVAILABLE after chunk 2 of 3 of the snapshot (event 7): the
  // watch resumed at the snapshot's first chunk (event 6), everything before it being stored.
  EXPECT_EQ(watch_from(), (std::vector<long>{1, 6}));
  expect_complete_job(db_);
  EXPECT_TRUE(contains(r.err, "daemon skipped 3 frames, 1 snapshots up to step 50")) << r.err;
  EXPECT_TRUE(contains(r.err, "fake daemon says hello")) << r.err;
  EXPECT_TRUE(contains(r.err, "reconnect")) << r.err;
  EXPECT_TRUE(contains(r.out, "SUCCEEDED")) << r.out;
  EXPECT_TRUE(contains(r.out, "morphology twisted")) << r.out;

  // Watching again: everything is here, so it prints the result without a connection (even to
  // a server that does not exist).
  const Result again =
      mdem_cli(dir_, "watch " + std::string(kJobId) + " --json --server 127.0.0.1:1" + db());
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(watch_from().size(), 2u);
  const json j = json::parse(again.out);
  EXPECT_EQ(j["state"], "SUCCEEDED");
  EXPECT_EQ(j["summary"]["morphology"], "twisted");
  EXPECT_EQ(j["db"], db_);

  // `mdem export` works on it as on a job of `mdem run`.
  const Result csv = mdem_cli(dir_, "export " + std::string(kJobId) + " --format csv --out " +
                                        quote(dir_.file("w.csv")) + db());
  ASSERT_EQ(csv.code, 0) << csv.err;
  std::istringstream lines(slurp(dir_.file("w.csv")));
  std::vector<std::string> rows;
  for (std::string line; std::getline(lines, line);) rows.push_back(line);
  ASSERT_EQ(rows.size(), 5u) << slurp(dir_.file("w.csv"));
  EXPECT_EQ(rows[0], "step,time_ps,kinetic_eV,potential_eV,twist_angle_deg");
  EXPECT_EQ(rows[4].substr(0, 3), "60,");
  const Result xyz = mdem_cli(dir_, "export " + std::string(kJobId) + " --format xyz --out " +
                                        quote(dir_.file("w.xyz")) + db());
  ASSERT_EQ(xyz.code, 0) << xyz.err;
  EXPECT_EQ(slurp(dir_.file("w.xyz")).substr(0, 3), "40\n");
  // `mdem plot` too, where gnuplot is installed.
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    const Result svg = mdem_cli(
        dir_, "plot " + std::string(kJobId) + " --out " + quote(dir_.file("w.svg")) + db());
    ASSERT_EQ(svg.code, 0) << svg.err;
    EXPECT_TRUE(contains(slurp(dir_.file("w.svg")), "<svg")) << svg.out;
  }
  // And the local `ls` lists it.
  const Result ls = mdem_cli(dir_, "ls" + db());
  EXPECT_TRUE(contains(ls.out, kJobId)) << ls.out;
}

TEST_F(FakeDaemon, WatchOfAJobNotRecordedLocallyFetchesItWhole) {
  // No submit here: the watch asks the daemon for the job (GetJob), then streams from event 1;
  // a stream that drops after a frame (event 5) resumes at 6.
  service_.drop_after = 5;
  const Result r = mdem_cli(dir_, "watch " + std::string(kJobId) + " " + conn() + db() + " --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(watch_from(), (std::vector<long>{1, 6}));
  expect_complete_job(db_);
  EXPECT_EQ(json::parse(r.out)["state"], "SUCCEEDED");
}

TEST_F(FakeDaemon, WatchGivesUpAfterTheReconnectTimeoutKeepingWhatArrived) {
  service_.drop_after = 2;
  service_.drops = 1000;  // every stream drops; after event 2, before delivering anything more
  const Result r = mdem_cli(
      dir_, "watch " + std::string(kJobId) + " " + conn() + db() + " --reconnect-timeout 1");
  EXPECT_EQ(r.code, mdem::cli::kConnection) << r.err;
  EXPECT_TRUE(contains(r.err, "gave up")) << r.err;
  EXPECT_TRUE(contains(r.err, "mdem watch " + std::string(kJobId))) << r.err;
  EXPECT_LT(r.seconds, 8.0);
  const auto from = watch_from();
  ASSERT_GE(from.size(), 3u);
  EXPECT_EQ(from[0], 1);
  for (std::size_t k = 1; k < from.size(); ++k) EXPECT_EQ(from[k], 3) << k;
  ResultsStore store(db_);
  EXPECT_EQ(store.last_seq(kJobId), 2);
  EXPECT_EQ(store.find(kJobId)->state, "RUNNING");
  EXPECT_EQ(store.columns(kJobId).size(), 3u);
}

// Starts `mdem watch` in the background until the fake's stream goes quiet (block_after), then
// sends it `sig`; returns the wait status.
int watch_then_signal(const std::string& args, const std::string& err_file, FakeJobService& service,
                      int sig) {
  const std::string cmd = args + " 2>" + quote(err_file) + " >/dev/null </dev/null";
  const pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  for (int k = 0; k < 500 && !service.blocking; ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_TRUE(service.blocking.load());
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // let the client store it
  kill(pid, sig);
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

TEST_F(FakeDaemon, AWatcherKilledMidSnapshotResumesAtItsFirstChunk) {
  service_.drops = 0;
  service_.block_after = 7;  // quiet after chunk 2 of 3
  const std::string cmd =
      env_prefix(dir_, {}) + " " + quote(MDEM_CLI_PATH) + " watch " + kJobId + " " + conn() + db();
  const int status = watch_then_signal(cmd, dir_.file("killed.txt"), service_, SIGKILL);
  ASSERT_TRUE(WIFSIGNALED(status));
  {
    ResultsStore store(db_);
    EXPECT_EQ(store.last_seq(kJobId), 5);  // the frames before the snapshot, not its chunks
    EXPECT_EQ(store.frame_count(kJobId), 2u);
    EXPECT_EQ(store.snapshot_count(kJobId), 0u);
  }
  service_.block_after = 0;
  const Result r = mdem_cli(dir_, "watch " + std::string(kJobId) + " " + conn() + db());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(watch_from(), (std::vector<long>{1, 6}));
  expect_complete_job(db_);
}

TEST_F(FakeDaemon, CtrlCStopsWatchingAndNeverCancelsTheJob) {
  service_.drops = 0;
  service_.block_after = 9;  // the stream goes quiet after the snapshot and a frame
  const std::string err_file = dir_.file("watch-err.txt");
  const std::string cmd =
      env_prefix(dir_, {}) + " " + quote(MDEM_CLI_PATH) + " watch " + kJobId + " " + conn() + db();
  const int status = watch_then_signal(cmd, err_file, service_, SIGINT);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), mdem::cli::kInterrupted) << slurp(err_file);
  const std::string err = slurp(err_file);
  EXPECT_TRUE(contains(err, "stopped watching")) << err;
  EXPECT_TRUE(contains(err, "mdem cancel")) << err;
  {
    std::lock_guard lock(service_.mu);
    EXPECT_EQ(service_.cancels, 0);
  }
  ResultsStore store(db_);
  EXPECT_EQ(store.last_seq(kJobId), 9);
  EXPECT_EQ(store.snapshot_count(kJobId), 1u);
  EXPECT_EQ(store.frame_count(kJobId), 3u);
}

TEST_F(FakeDaemon, CancelLsAndShowAskTheDaemon) {
  ASSERT_EQ(mdem_cli(dir_, "submit twist --layers 2 " + conn() + db()).code, 0);
  Result r = mdem_cli(dir_, "cancel " + std::string(kJobId) + " --token-file " +
                                quote(token_file_) + db());  // the server from the record
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "cancelled " + std::string(kJobId))) << r.out;
  EXPECT_EQ(ResultsStore(db_).find(kJobId)->state, "CANCELLED");

  r = mdem_cli(dir_, "ls " + conn());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, kJobId)) << r.out;
  EXPECT_TRUE(contains(r.out, "RUNNING")) << r.out;
  r = mdem_cli(dir_, "ls --json " + conn());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out)[0]["user"], "alice");

  // $MDEM_SERVER alone sends ls and show to the daemon too; --local keeps them local.
  const std::map<std::string, std::string> env = {{"MDEM_SERVER", address()},
                                                  {"MDEM_TOKEN", kToken}};
  r = mdem_cli(dir_, "show " + std::string(kJobId) + " --json", env);
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["state"], "SUCCEEDED");
  EXPECT_EQ(j["report"]["summary"]["morphology"], "twisted");
  r = mdem_cli(dir_, "show " + std::string(kJobId) + " --local" + db(), env);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "CANCELLED")) << r.out;

  // The config file's server serves submit, watch and cancel.
  const std::string cfg =
      dir_.write("config.yaml", "server: " + address() + "\ntoken_file: token\ntls: false\n");
  r = mdem_cli(dir_, "cancel " + std::string(kJobId), {{"MDEM_CONFIG", cfg}});
  ASSERT_EQ(r.code, 0) << r.err;
  std::lock_guard lock(service_.mu);
  EXPECT_EQ(service_.cancels, 2);
}

}  // namespace

namespace {

int count_of(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST_F(FakeDaemon, WatchCancelAndShowUseTheServerAndTokenFileOfTheSubmit) {
  ASSERT_EQ(mdem_cli(dir_, "submit twist --layers 2 " + conn() + db()).code, 0);
  EXPECT_EQ(ResultsStore(db_).find(kJobId)->token_file, fs::canonical(token_file_).string());

  // The local ls marks the daemon's job whose state may be newer there.
  Result r = mdem_cli(dir_, "ls" + db());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.out, "QUEUED*")) << r.out;
  EXPECT_TRUE(contains(r.out, "the daemon may know more")) << r.out;
  r = mdem_cli(dir_, "ls --json" + db());
  EXPECT_EQ(json::parse(r.out)[0]["job_id"], kJobId) << r.out;
  EXPECT_EQ(json::parse(r.out)[0]["state_may_be_outdated"], true) << r.out;

  // No --server, no --token-file, no $MDEM_TOKEN: both come from the submit's record.
  r = mdem_cli(dir_, "watch " + std::string(kJobId).substr(0, 6) + db());
  ASSERT_EQ(r.code, 0) << r.err;
  expect_complete_job(db_);
  {
    std::lock_guard lock(service_.mu);
    EXPECT_EQ(service_.authorization.back(), std::string("Bearer ") + kToken);
  }
  r = mdem_cli(dir_, "ls" + db());
  EXPECT_TRUE(contains(r.out, "SUCCEEDED")) << r.out;
  EXPECT_FALSE(contains(r.out, "SUCCEEDED*")) << r.out;
  EXPECT_FALSE(contains(r.out, "the daemon may know more")) << r.out;

  r = mdem_cli(dir_, "cancel " + std::string(kJobId) + db());
  ASSERT_EQ(r.code, 0) << r.err;

  // show --server: a prefix of a job recorded here, with its token file ($MDEM_DB: --db is
  // refused with --server) ...
  r = mdem_cli(dir_, "show j-fake --json --server " + address(), {{"MDEM_DB", db_}});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out)["job_id"], kJobId);
  // ... and a prefix of a job only the daemon knows (an empty database here).
  r = mdem_cli(dir_, "show j-fa --json " + conn(), {{"MDEM_DB", dir_.file("other.db")}});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out)["job_id"], kJobId);
  r = mdem_cli(dir_, "show j-nope " + conn(), {{"MDEM_DB", dir_.file("other.db")}});
  EXPECT_EQ(r.code, mdem::cli::kJobFailed);
  EXPECT_TRUE(contains(r.err, "no job 'j-nope'")) << r.err;

  // No token anywhere: the advice once, not the daemon's words for the same thing after it.
  r = mdem_cli(dir_, "ls --server " + address());
  EXPECT_EQ(r.code, mdem::cli::kJobFailed);
  EXPECT_EQ(count_of(r.err, "--token-file"), 1) << r.err;
  EXPECT_FALSE(contains(r.err, "unknown token")) << r.err;
}

}  // namespace
