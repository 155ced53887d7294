#pragma once
// Starts a real mdemd process for the service tests: a temp data directory, a token file with
// users alice, bob and an admin root, port 0 (the daemon writes the bound port to a file), and
// stubs that carry a user's token; the job RPCs and the mdem binary as the service tests call them.
#include <fcntl.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "mdem/v1/service.grpc.pb.h"
#include "support.h"

namespace mdem::testing {

namespace fs = std::filesystem;

inline const char* kAliceToken = "alice-token-0123456789";
inline const char* kBobToken = "bob-token-0123456789ab";
inline const char* kRootToken = "root-token-0123456789ab";

// A test's own directory (removed after a passing run, see ScratchDirs).
inline fs::path fresh_dir(const std::string& name) {
  return ScratchDirs::make("mdemd-test-" + std::to_string(getpid()) + "-" + name);
}

// Writes a file only its owner may read (mdemd refuses a token file others may read).
inline void write_private(const fs::path& path, const std::string& text) {
  std::ofstream(path) << text;
  fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write);
}

class DaemonProcess {
 public:
  // dir: the test's directory (data/, tokens, log inside). extra: more mdemd flags.
  explicit DaemonProcess(fs::path dir, std::vector<std::string> extra = {})
      : dir_(std::move(dir)), extra_(std::move(extra)) {
    write_private(dir_ / "tokens", std::string("# test users\n") + kAliceToken + " alice\n" +
                                       kBobToken + " bob\n" + kRootToken + " root admin\n");
    start();
  }
  ~DaemonProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }

  // Starts (or restarts) the daemon on the same data directory; waits until it serves.
  void start() {
    const fs::path port_file = dir_ / "port";
    fs::remove(port_file);
    std::vector<std::string> args = {MDEMD_PATH,
                                     "--listen",
                                     "127.0.0.1:0",
                                     "--data-dir",
                                     (dir_ / "data").string(),
                                     "--token-file",
                                     (dir_ / "tokens").string(),
                                     "--port-file",
                                     port_file.string()};
    args.insert(args.end(), extra_.begin(), extra_.end());
    pid_ = spawn(args, dir_ / "mdemd.log");
    for (int i = 0; i < 400 && !fs::exists(port_file); ++i) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        throw std::runtime_error("mdemd exited at start:\n" + log());
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    std::ifstream(port_file) >> port_;
    if (port_ <= 0) throw std::runtime_error("mdemd did not write its port:\n" + log());
    channel_ = grpc::CreateChannel("127.0.0.1:" + std::to_string(port_),
                                   grpc::InsecureChannelCredentials());
  }
  void kill9() {
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, nullptr, 0);
    pid_ = -1;
  }
  // SIGTERM; returns the exit status (or -1 when it had to be killed after timeout_s).
  int terminate(double timeout_s = 30) {
    ::kill(pid_, SIGTERM);
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    int status = 0;
    while (std::chrono::steady_clock::now() < end) {
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    kill9();
    return -1;
  }

  int pid() const { return pid_; }
  int port() const { return port_; }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  fs::path data_dir() const { return dir_ / "data"; }
  std::string log() const { return slurp(dir_ / "mdemd.log"); }
  std::shared_ptr<grpc::Channel> channel() const { return channel_; }
  std::unique_ptr<v1::JobService::Stub> stub() const { return v1::JobService::NewStub(channel_); }
  // Resident memory of the daemon (kB), from /proc.
  long rss_kb() const {
    std::ifstream in("/proc/" + std::to_string(pid_) + "/status");
    std::string line;
    while (std::getline(in, line))
      if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
    return -1;
  }

  // Runs a program with stdout to `out` (appended, or truncated with `truncate`) and stderr to
  // `err` (the same file when empty); returns its pid.
  static int spawn(const std::vector<std::string>& args, const fs::path& out,
                   const fs::path& err = {}, bool truncate = false) {
    const int pid = ::fork();
    if (pid == 0) {
      const int fd =
          ::open(out.c_str(), O_WRONLY | O_CREAT | (truncate ? O_TRUNC : O_APPEND), 0644);
      ::dup2(fd, 1);
      ::dup2(err.empty() ? fd : ::open(err.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644), 2);
      std::vector<char*> argv;
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    return pid;
  }
  // spawn, then wait: the exit status (-1 when killed by a signal).
  static int run(const std::vector<std::string>& args, const fs::path& out,
                 const fs::path& err = "/dev/null") {
    int status = 0;
    ::waitpid(spawn(args, out, err, true), &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  // A connected channel with its own TCP connection (not shared with other channels).
  std::shared_ptr<grpc::Channel> new_channel() const {
    grpc::ChannelArguments args;
    args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
    args.SetMaxReceiveMessageSize(64 << 20);
    auto ch = grpc::CreateCustomChannel(address(), grpc::InsecureChannelCredentials(), args);
    if (!ch->WaitForConnected(std::chrono::system_clock::now() + std::chrono::seconds(10)))
      throw std::runtime_error("cannot connect to mdemd at " + address());
    return ch;
  }
  // User + system CPU seconds of the daemon so far (/proc/PID/stat, fields 14 and 15).
  double cpu_s() const {
    std::ifstream in("/proc/" + std::to_string(pid_) + "/stat");
    std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::istringstream rest(s.substr(s.rfind(')') + 2));
    std::string f;
    double ut = 0, st = 0;
    for (int k = 3; k <= 15 && rest >> f; ++k) {
      if (k == 14) ut = std::stod(f);
      if (k == 15) st = std::stod(f);
    }
    return (ut + st) / static_cast<double>(::sysconf(_SC_CLK_TCK));
  }

 private:
  fs::path dir_;
  std::vector<std::string> extra_;
  int pid_ = -1, port_ = 0;
  std::shared_ptr<grpc::Channel> channel_;
};

// A client context carrying a user's token and a deadline.
inline std::unique_ptr<grpc::ClientContext> ctx_for(const char* token, double deadline_s = 30) {
  auto c = std::make_unique<grpc::ClientContext>();
  if (token) c->AddMetadata("authorization", std::string("Bearer ") + token);
  if (deadline_s > 0)
    c->set_deadline(std::chrono::system_clock::now() +
                    std::chrono::milliseconds(static_cast<long>(deadline_s * 1000)));
  return c;
}

struct Submitted {
  grpc::Status status;
  v1::SubmitJobResponse resp;
};

inline Submitted submit(const DaemonProcess& d, const char* token, const std::string& request_id,
                        const v1::JobSpec& spec) {
  v1::SubmitJobRequest req;
  req.set_request_id(request_id);
  *req.mutable_spec() = spec;
  Submitted s;
  auto ctx = ctx_for(token);
  s.status = d.stub()->SubmitJob(ctx.get(), req, &s.resp);
  return s;
}

// submit, expecting it to succeed; the job id.
inline std::string submit_ok(const DaemonProcess& d, const char* token, const std::string& rid,
                             const v1::JobSpec& spec) {
  const Submitted s = submit(d, token, rid, spec);
  EXPECT_TRUE(s.status.ok()) << s.status.error_message();
  return s.resp.job().job_id();
}

inline v1::JobInfo get(const DaemonProcess& d, const char* token, const std::string& id,
                       grpc::Status* status = nullptr) {
  v1::GetJobRequest req;
  req.set_job_id(id);
  v1::JobInfo info;
  auto ctx = ctx_for(token);
  const grpc::Status s = d.stub()->GetJob(ctx.get(), req, &info);
  if (status) *status = s;
  return info;
}

// Reads a job's events from from_seq until the stream ends (or max_events were read), within
// deadline_s.
inline std::vector<v1::JobEvent> watch(const DaemonProcess& d, const char* token,
                                       const std::string& id, long from_seq, long max_events = -1,
                                       grpc::Status* status = nullptr, double deadline_s = 300) {
  v1::WatchJobRequest req;
  req.set_job_id(id);
  req.set_from_seq(from_seq);
  auto ctx = ctx_for(token, deadline_s);
  auto stub = d.stub();
  auto reader = stub->WatchJob(ctx.get(), req);
  std::vector<v1::JobEvent> out;
  v1::JobEvent e;
  while ((max_events < 0 || static_cast<long>(out.size()) < max_events) && reader->Read(&e))
    out.push_back(e);
  if (max_events >= 0 && static_cast<long>(out.size()) == max_events) ctx->TryCancel();
  const grpc::Status s = reader->Finish();
  if (status) *status = s;
  return out;
}

// The mdem binary with `args` (one shell word string), without the user's settings; stderr is
// appended to DIR/cli.err. Its exit code and stdout.
inline CliResult mdem_cli(const fs::path& dir, const std::string& args) {
  const std::string cmd = "env -u MDEM_SERVER -u MDEM_TOKEN -u MDEM_CONFIG -u MDEM_DB " +
                          std::string(MDEM_CLI_PATH) + " " + args + " 2>>" +
                          (dir / "cli.err").string();
  return run_shell(cmd);
}

// `mdem submit ARGS --watch --json` to the daemon d as alice (her token in DIR/alice.token).
inline CliResult mdem_submit_watch(const DaemonProcess& d, const fs::path& dir,
                                   const std::string& args) {
  std::ofstream(dir / "alice.token") << kAliceToken << "\n";
  return mdem_cli(dir, "submit " + args + " --server " + d.address() + " --token-file " +
                           (dir / "alice.token").string() + " --watch --json");
}

}  // namespace mdem::testing
