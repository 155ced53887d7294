// The client under faults (issue 11): a daemon that is paused, busy or down must not make `mdem`
// give up before its deadline (nor hang past it); `mdem watch` started before the daemon waits
// for it up to --reconnect-timeout; `mdem run` stopped by SIGTERM or SIGHUP ends CANCELLED with
// its results kept, as with Ctrl-C, and one killed outright reads as INTERRUPTED, not RUNNING
// for ever; a foreign SQLite file given as the results database is refused byte for byte
// unchanged. Real processes throughout: the mdem binary, and a real mdemd (tests/daemon.h).
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "../client/src/remote.h"
#include "../client/src/results_store.h"
#include "daemon.h"
#include "mdem/cli.h"

namespace {

namespace fs = std::filesystem;
using mdem::cli::ResultsStore;
using mdem::cli::StoreError;
using mdem::testing::DaemonProcess;
using mdem::testing::fresh_dir;
using mdem::testing::slurp;
using Clock = std::chrono::steady_clock;
using mdem::testing::clear_mdem_env;
using mdem::testing::since;
using mdem::testing::operator+;

// A small twist job that runs for minutes unless stopped (it is always stopped or watched).
const std::vector<std::string> kLongTwist = {"twist",   "--layers",  "2", "--length",
                                             "13.56",   "--torque",  "2", "--hold",
                                             "1000000", "--threads", "1"};
// A small twist job that ends in a few seconds.
const std::vector<std::string> kShortTwist = {"twist", "--layers",  "2", "--length",
                                              "13.56", "--torque",  "2", "--hold",
                                              "10",    "--threads", "1"};

std::vector<std::string> mdem(std::vector<std::string> args) {
  args.insert(args.begin(), MDEM_CLI_PATH);
  return args;
}

// Waits for `pid` up to timeout_s: its exit code, -1 when a signal ended it, -2 when it was
// still running (it is then killed).
int wait_exit(int pid, double timeout_s) {
  const auto t0 = Clock::now();
  int status = 0;
  while (since(t0) < timeout_s) {
    if (::waitpid(pid, &status, WNOHANG) == pid)
      return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return -2;
}

// True while `pid` has not exited (without reaping it: wait_exit still gets its status).
bool still_running(int pid) {
  siginfo_t info{};
  return ::waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) == 0 &&
         info.si_pid == 0;
}

std::string token_file(const fs::path& dir) {
  const fs::path p = dir / "alice.token";
  std::ofstream(p) << mdem::testing::kAliceToken << "\n";
  return p.string();
}

// A TCP port of 127.0.0.1 that nothing listens on.
int closed_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

// A socket that listens on 127.0.0.1 and never answers (the kernel completes TCP connections,
// no HTTP/2 handshake follows): a daemon frozen for good. Closed when destroyed.
class SilentListener {
 public:
  SilentListener() : fd_(::socket(AF_INET, SOCK_STREAM, 0)) {
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    ::listen(fd_, 16);
    socklen_t len = sizeof a;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
  }
  ~SilentListener() { ::close(fd_); }
  int port() const { return port_; }

 private:
  int fd_, port_ = 0;
};

// ---- 1. clients never give up before their deadline -------------------------------------------

// The daemon paused (SIGSTOP) for 2 s while `mdem ls` connects: the call waits and succeeds.
// (Before, every call failed after ~0.3 s: "connection attempt timed out before receiving
// SETTINGS frame".)
TEST(ClientFaults, ACallOutlastsADaemonPausedForTwoSeconds) {
  clear_mdem_env();
  const fs::path dir = fresh_dir("faults-pause");
  DaemonProcess d(dir);
  const std::string token = token_file(dir);
  ASSERT_EQ(::kill(d.pid(), SIGSTOP), 0);
  const auto t0 = Clock::now();
  const int pid =
      DaemonProcess::spawn(mdem({"ls", "--server", d.address(), "--token-file", token, "--json"}),
                           dir / "ls.out", dir / "ls.err", true);
  std::this_thread::sleep_for(std::chrono::seconds(2));
  const bool waited = still_running(pid);
  ::kill(d.pid(), SIGCONT);
  const int code = wait_exit(pid, 30);
  EXPECT_TRUE(waited) << "mdem ls gave up while the daemon was paused: " << slurp(dir / "ls.err");
  EXPECT_EQ(code, mdem::cli::kOk) << slurp(dir / "ls.err");
  EXPECT_GE(since(t0), 2.0);
  EXPECT_EQ(slurp(dir / "ls.out").rfind("[", 0), 0u) << slurp(dir / "ls.out");  // the JSON list
}

// No daemon: a refused connection fails at once, a daemon that never answers fails at the 10 s
// deadline; both exit 3 with a message that says which daemon and what happened.
TEST(ClientFaults, AnAbsentOrFrozenDaemonFailsWithExit3WithinTheDeadline) {
  clear_mdem_env();
  const fs::path dir = fresh_dir("faults-absent");
  {
    const std::string server = "127.0.0.1:" + std::to_string(closed_port());
    const auto t0 = Clock::now();
    const int code =
        DaemonProcess::run(mdem({"ls", "--server", server}), dir / "out", dir / "refused.err");
    EXPECT_EQ(code, mdem::cli::kConnection) << slurp(dir / "refused.err");
    EXPECT_LT(since(t0), 5.0);
    EXPECT_TRUE(
        mdem::testing::contains(slurp(dir / "refused.err"), "cannot reach mdemd at " + server))
        << slurp(dir / "refused.err");
  }
  {
    SilentListener frozen;
    const std::string server = "127.0.0.1:" + std::to_string(frozen.port());
    const auto t0 = Clock::now();
    const int pid = DaemonProcess::spawn(mdem({"ls", "--server", server}), dir / "out",
                                         dir / "frozen.err", true);
    const int code = wait_exit(pid, 30);
    const double s = since(t0);
    EXPECT_EQ(code, mdem::cli::kConnection) << slurp(dir / "frozen.err");
    EXPECT_GT(s, mdem::cli::kCallDeadlineMs / 1000.0 - 1);  // it waited for the deadline...
    EXPECT_LT(s, mdem::cli::kCallDeadlineMs / 1000.0 + 5);  // ...and no longer
    EXPECT_TRUE(mdem::testing::contains(slurp(dir / "frozen.err"),
                                        "mdemd at " + server + " did not answer within 10 s"))
        << slurp(dir / "frozen.err");
  }
}

// ---- 2. `mdem watch` started before the daemon -------------------------------------------------

// Submits kShortTwist to d (recorded in db); its job id.
std::string submit_short_job(const DaemonProcess& d, const fs::path& dir, const std::string& db,
                             const std::string& token) {
  const int code = DaemonProcess::run(
      mdem({"submit"}) + kShortTwist +
          std::vector<std::string>{"--server", d.address(), "--token-file", token, "--db", db},
      dir / "submit.out", dir / "submit.err");
  EXPECT_EQ(code, 0) << slurp(dir / "submit.err");
  std::string id;
  std::ifstream(dir / "submit.out") >> id;
  return id;
}

void expect_stored_and_succeeded(const std::string& db, const std::string& id) {
  ResultsStore store(db);
  const auto rec = store.find(id);
  ASSERT_TRUE(rec.has_value());
  EXPECT_EQ(rec->state, "SUCCEEDED");
  EXPECT_FALSE(rec->summary_json.empty());
  EXPECT_GT(store.frame_count(id), 0u);
}

// A daemon with a short job submitted to it and recorded in a local database.
struct SubmittedJob {
  explicit SubmittedJob(const std::string& name)
      : dir(fresh_dir(name)),
        d(dir),
        token(token_file(dir)),
        db((dir / "results.db").string()),
        id(submit_short_job(d, dir, db, token)) {}
  // `mdem watch ID --reconnect-timeout 20` in the background (the daemon from the job's
  // record); its pid.
  int start_watch() const {
    return DaemonProcess::spawn(
        mdem({"watch", id, "--reconnect-timeout", "20", "--token-file", token, "--db", db}),
        dir / "watch.out", dir / "watch.err", true);
  }
  fs::path dir;
  DaemonProcess d;
  std::string token, db, id;
};

TEST(ClientFaults, WatchStartedWhileTheDaemonIsPausedFollowsItOnceItResumes) {
  clear_mdem_env();
  SubmittedJob job("faults-watch-paused");
  ASSERT_FALSE(job.id.empty());
  ASSERT_EQ(::kill(job.d.pid(), SIGSTOP), 0);
  const int pid = job.start_watch();
  std::this_thread::sleep_for(std::chrono::seconds(2));
  const bool waited = still_running(pid);
  ::kill(job.d.pid(), SIGCONT);
  const int code = wait_exit(pid, 120);
  EXPECT_TRUE(waited) << slurp(job.dir / "watch.err");
  ASSERT_EQ(code, mdem::cli::kOk) << slurp(job.dir / "watch.err");
  expect_stored_and_succeeded(job.db, job.id);
}

// The daemon killed; `mdem watch` started; a new daemon on the same port and data directory:
// the watch, which never had an event, keeps retrying and then completes the job's results.
TEST(ClientFaults, WatchStartedWhileTheDaemonIsDownWaitsForItsRestart) {
  clear_mdem_env();
  SubmittedJob job("faults-watch-down");
  ASSERT_FALSE(job.id.empty());
  const fs::path& dir = job.dir;
  const int port = job.d.port();
  job.d.kill9();
  const int pid = job.start_watch();
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const bool waited = still_running(pid);
  const int daemon = DaemonProcess::spawn(
      {MDEMD_PATH, "--listen", "127.0.0.1:" + std::to_string(port), "--data-dir",
       job.d.data_dir().string(), "--token-file", (dir / "tokens").string()},
      dir / "mdemd-restarted.log");
  const int code = wait_exit(pid, 120);
  ::kill(daemon, SIGKILL);
  ::waitpid(daemon, nullptr, 0);
  const std::string err = slurp(dir / "watch.err");
  EXPECT_TRUE(waited) << err;
  ASSERT_EQ(code, mdem::cli::kOk) << err << slurp(dir / "mdemd-restarted.log");
  EXPECT_TRUE(mdem::testing::contains(
      err, "cannot reach mdemd at 127.0.0.1:" + std::to_string(port) + " yet"))
      << err;
  expect_stored_and_succeeded(job.db, job.id);
}

// ---- 3. `mdem run` stopped by a signal ----------------------------------------------------

// Starts `mdem run kLongTwist --db db` and waits until its job is recorded with some frames:
// the pid and the job id (empty when that did not happen within 60 s).
std::pair<int, std::string> start_local_run(const fs::path& dir, const std::string& db) {
  const int pid =
      DaemonProcess::spawn(mdem({"run"}) + kLongTwist + std::vector<std::string>{"--db", db},
                           dir / "run.out", dir / "run.err", true);
  const auto t0 = Clock::now();
  while (since(t0) < 60 && still_running(pid)) {
    if (fs::exists(db)) {
      try {
        ResultsStore store(db);
        const auto jobs = store.list();
        if (!jobs.empty() && store.frame_count(jobs.front().id) > 0) {
          EXPECT_EQ(jobs.front().state, "RUNNING");  // alive: never taken for interrupted
          return {pid, jobs.front().id};
        }
      } catch (const StoreError&) {  // being created
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ADD_FAILURE() << "mdem run did not store frames: " << slurp(dir / "run.err");
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
  return {-1, ""};
}

TEST(ClientFaults, SigtermAndSighupStopALocalRunAsCtrlCDoes) {
  clear_mdem_env();
  for (const auto& [sig, name] :
       {std::pair{SIGINT, "SIGINT"}, std::pair{SIGTERM, "SIGTERM"}, std::pair{SIGHUP, "SIGHUP"}}) {
    SCOPED_TRACE(name);
    const fs::path dir = fresh_dir(std::string("faults-run-") + name);
    const std::string db = (dir / "results.db").string();
    const auto [pid, id] = start_local_run(dir, db);
    if (pid < 0) continue;
    ::kill(pid, sig);
    const int code = wait_exit(pid, 30);
    EXPECT_EQ(code, mdem::cli::kJobFailed) << slurp(dir / "run.err");  // as for Ctrl-C
    ResultsStore store(db);
    const auto rec = store.find(id);
    ASSERT_TRUE(rec.has_value());
    EXPECT_EQ(rec->state, "CANCELLED");
    EXPECT_TRUE(mdem::testing::contains(rec->reason, name)) << rec->reason;
    EXPECT_FALSE(rec->summary_json.empty());
    EXPECT_FALSE(rec->finished_at.empty());
    EXPECT_GT(store.frame_count(id), 0u);
  }
}

TEST(ClientFaults, ALocalRunKilledOutrightIsListedInterruptedNotRunning) {
  clear_mdem_env();
  const fs::path dir = fresh_dir("faults-run-kill9");
  const std::string db = (dir / "results.db").string();
  const auto [pid, id] = start_local_run(dir, db);
  ASSERT_GT(pid, 0);
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);

  ASSERT_EQ(DaemonProcess::run(mdem({"ls", "--db", db}), dir / "ls.out"), 0);
  const std::string ls = slurp(dir / "ls.out");
  EXPECT_TRUE(mdem::testing::contains(ls, "INTERRUPTED")) << ls;
  EXPECT_FALSE(mdem::testing::contains(ls, "RUNNING")) << ls;
  ASSERT_EQ(DaemonProcess::run(mdem({"show", id, "--db", db}), dir / "show.out"), 0);
  const std::string show = slurp(dir / "show.out");
  EXPECT_TRUE(mdem::testing::contains(show, "INTERRUPTED")) << show;
  EXPECT_TRUE(mdem::testing::contains(show, "pid " + std::to_string(pid))) << show;

  ResultsStore store(db);
  EXPECT_EQ(store.find(id)->state, "INTERRUPTED");
  EXPECT_EQ(store.list().front().state, "INTERRUPTED");
  EXPECT_GT(store.frame_count(id), 0u);  // what it stored is kept
}

// ---- 4. a file that is not ours is refused untouched -------------------------------------------

std::string file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::string journal_mode(const fs::path& p) {
  sqlite3* db = nullptr;
  sqlite3_open_v2(p.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
  sqlite3_stmt* s = nullptr;
  sqlite3_prepare_v2(db, "PRAGMA journal_mode", -1, &s, nullptr);
  std::string mode = sqlite3_step(s) == SQLITE_ROW
                         ? reinterpret_cast<const char*>(sqlite3_column_text(s, 0))
                         : "?";
  sqlite3_finalize(s);
  sqlite3_close(db);
  return mode;
}

TEST(ClientFaults, AForeignSqliteFileIsRefusedByteForByteUnchanged) {
  clear_mdem_env();
  const fs::path dir = fresh_dir("faults-foreign");
  const fs::path foreign = dir / "notes.sqlite";
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(foreign.c_str(), &db), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(db,
                           "CREATE TABLE notes (id INTEGER PRIMARY KEY, text TEXT);"
                           "INSERT INTO notes (text) VALUES ('keep me'), ('and me');",
                           nullptr, nullptr, nullptr),
              SQLITE_OK);
    sqlite3_close(db);
  }
  ASSERT_EQ(journal_mode(foreign), "delete");
  const std::string before = file_bytes(foreign);

  for (const std::string cmd : {"ls", "show"}) {
    std::vector<std::string> args = {cmd};
    if (cmd == "show") args.push_back("j-1");
    const int code =
        DaemonProcess::run(mdem(args + std::vector<std::string>{"--db", foreign.string()}),
                           dir / "out", dir / (cmd + ".err"));
    const std::string err = slurp(dir / (cmd + ".err"));
    EXPECT_NE(code, 0) << cmd;
    EXPECT_TRUE(mdem::testing::contains(err, "not an mdem results database")) << err;
    EXPECT_TRUE(mdem::testing::contains(err, foreign.string())) << err;
  }
  EXPECT_THROW(ResultsStore{foreign.string()}, StoreError);
  EXPECT_TRUE(file_bytes(foreign) == before) << "the foreign file was changed";
  EXPECT_EQ(journal_mode(foreign), "delete");
  EXPECT_FALSE(fs::exists(foreign.string() + "-wal"));
  EXPECT_FALSE(fs::exists(foreign.string() + "-journal"));

  // A file that is not an SQLite database at all is refused unchanged too.
  const fs::path text = dir / "notes.txt";
  std::ofstream(text) << std::string(4096, 'x');
  EXPECT_THROW(ResultsStore{text.string()}, StoreError);
  EXPECT_TRUE(file_bytes(text) == std::string(4096, 'x')) << "the text file was changed";
}

}  // namespace
