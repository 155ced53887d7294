#pragma once
// Talking to the mdemd daemon: where it is and how to authenticate (flags > environment > config
// file), the gRPC channel (keepalive, quick reconnects) and calls (bearer token, deadlines), and
// gRPC statuses turned into messages that say what to do and into exit codes.
#include <grpcpp/grpcpp.h>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "flags.h"
#include "mdem/v1/service.grpc.pb.h"

namespace mdem::cli {

// A bad connection setting: a flag, an environment variable, the config file (the message names
// the file and the key) or the token file. Exit code kUsage.
struct SettingsError : UsageError {
  using UsageError::UsageError;
};

struct ConnectionSettings {
  std::string server;         // HOST:PORT (or a gRPC target such as unix:/path/to/socket)
  std::string server_origin;  // where it came from, for messages: "--server", "$MDEM_SERVER", ...
  std::string token;          // "" when none is configured (the daemon will refuse the call)
  std::string token_origin;   // "--token-file FILE", "$MDEM_TOKEN", "token_file in FILE"
  std::string token_file;     // the token's file as an absolute path ("" when the token is from
                              // $MDEM_TOKEN or there is none): recorded with a submitted job
  bool tls = false;
  std::string ca_file;      // PEM root certificates for TLS; "" = the system's
  std::string config_path;  // the config file that was read; "" when none
};

// The environment as a function, so tests can give their own.
using Env = std::function<std::optional<std::string>(const std::string& name)>;
Env process_env();

// The connection flags (--server, --token-file, --tls, --ca-file), added to a command's flags.
void add_connection_flags(FlagSpec& spec);
// Help of the connection flags, the environment and the config file, for every remote command.
extern const char* const kConnectionHelp;

// The config file's keys (each optional) and where it is.
struct ConfigFile {
  std::string path;  // "" when there is none
  std::optional<std::string> server, token_file, ca_file;
  std::optional<bool> tls;
};

// $MDEM_CONFIG, else $XDG_CONFIG_HOME/mdem/config.yaml (when absolute), else
// $HOME/.config/mdem/config.yaml; "" when neither variable is set.
std::string config_file_path(const Env& env);
// Reads the config file: a YAML mapping of server, token_file, tls, ca_file. A missing default
// file is an empty config; a missing $MDEM_CONFIG file, malformed YAML, an unknown key or a value
// of the wrong type is a SettingsError naming the file and the key. Relative token_file and
// ca_file paths are relative to the file's directory; ~/ is the home directory.
ConfigFile load_config(const Env& env);

// True when --server or $MDEM_SERVER names a daemon (`ls` and `show` ask it then).
bool server_named(const std::map<std::string, std::string>& flags, const Env& env);

// The settings, each from the first source that has it: the flags, then the environment
// ($MDEM_SERVER, $MDEM_TOKEN), then the config file. `job_server` and `job_token_file`, the
// daemon and token file recorded with a job in the local database (by `mdem submit`), come
// right after --server and --token-file. A --ca-file implies --tls. Throws SettingsError for a
// bad value or when no source names a server.
ConnectionSettings resolve_connection(const std::map<std::string, std::string>& flags,
                                      const Env& env, const std::string& job_server = "",
                                      const std::string& job_token_file = "");

// The token of a token file: its first non-empty line, trimmed of whitespace. `origin` names the
// setting in messages ("--token-file", "token_file in FILE"). Throws SettingsError.
std::string read_token_file(const std::string& path, const std::string& origin);

// Request ids (SubmitJob's idempotency key): 1..128 characters of [A-Za-z0-9._:-]; a
// UsageError naming --request-id otherwise. new_request_id(): a random one ("r-" + 24 hex).
void check_request_id(const std::string& id);
std::string new_request_id();

// A call that failed: what happened and what to do, and the exit code it deserves.
struct RemoteError : std::runtime_error {
  RemoteError(const std::string& message, grpc::StatusCode code, int exit_code)
      : std::runtime_error(message), code(code), exit_code(exit_code) {}
  grpc::StatusCode code;
  int exit_code;
};

// UNAVAILABLE, DEADLINE_EXCEEDED, UNIMPLEMENTED, INTERNAL, UNKNOWN, DATA_LOSS -> kConnection;
// INVALID_ARGUMENT -> kUsage; everything else (UNAUTHENTICATED, PERMISSION_DENIED, NOT_FOUND,
// RESOURCE_EXHAUSTED, ...) -> kJobFailed.
int exit_code_for(grpc::StatusCode code);
// The status as a message that says what to do ("cannot reach mdemd at HOST:PORT (is it running?
// check --server) ...", "the server refused the token ...").
std::string describe_status(const grpc::Status& status, const ConnectionSettings& c);
const char* status_code_name(grpc::StatusCode code);

inline constexpr int kCallDeadlineMs = 10000;  // every unary call
// How long one connection attempt may wait for the daemon's handshake: longer than a call's
// deadline, so that a daemon answering within the deadline is always reached.
inline constexpr int kConnectAttemptTimeoutMs = 20000;

// The JobService of one daemon. Unary calls carry the token and a 10 s deadline and throw
// RemoteError; a WatchJob stream carries the token and no deadline.
class JobClient {
 public:
  explicit JobClient(ConnectionSettings settings);
  const ConnectionSettings& settings() const { return settings_; }

  v1::SubmitJobResponse submit(const v1::SubmitJobRequest& request);
  v1::JobInfo get(const std::string& job_id);
  // study_id: only that study's jobs ("" = every job).
  v1::ListJobsResponse list(bool all_users, int limit, const std::string& study_id = "");
  v1::JobInfo cancel(const std::string& job_id);
  // Queues a TIMEOUT job again with time_limit_s more running time (0: the daemon's default).
  v1::JobInfo resume(const std::string& job_id, double time_limit_s);

  std::unique_ptr<grpc::ClientContext> stream_context() const;
  // Waits until the channel is connected (starting a connection attempt) or `deadline`; true
  // when connected.
  bool wait_connected(std::chrono::system_clock::time_point deadline);
  v1::JobService::Stub& stub() { return *stub_; }

 private:
  std::unique_ptr<grpc::ClientContext> call_context() const;
  [[noreturn]] void fail(const grpc::Status& status) const;
  ConnectionSettings settings_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::JobService::Stub> stub_;
};

}  // namespace mdem::cli
