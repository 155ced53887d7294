// Connection settings from flags, environment and config file; the channel and the calls; and
// gRPC statuses as messages and exit codes.
#include "remote.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "mdem/cli.h"

namespace mdem::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* kConfigKeys = "server, token_file, tls, ca_file";
constexpr std::size_t kMaxFileBytes = 1 << 20;  // token, CA and config files

std::optional<std::string> non_empty(const Env& env, const char* name) {
  std::optional<std::string> v = env(name);
  if (v && v->empty()) return std::nullopt;
  return v;
}

std::string trim(const std::string& s) {
  const char* ws = " \t\r\n\v\f";
  const std::size_t a = s.find_first_not_of(ws);
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(ws) - a + 1);
}

// ~/x -> $HOME/x; a relative path is taken relative to `base` (the config file's directory).
std::string expand_path(const std::string& p, const fs::path& base, const Env& env) {
  if (p.rfind("~/", 0) == 0) {
    if (const auto home = non_empty(env, "HOME")) return (fs::path(*home) / p.substr(2)).string();
  }
  const fs::path path(p);
  if (path.is_absolute() || base.empty()) return p;
  return (base / path).string();
}

// A readable regular file's text (at most kMaxFileBytes); `what` names it in errors.
std::string read_small_file(const std::string& path, const std::string& what) {
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (ec || !fs::exists(status))
    throw SettingsError("cannot read " + what + " '" + path + "': no such file");
  if (!fs::is_regular_file(status))
    throw SettingsError("cannot read " + what + " '" + path + "': not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SettingsError("cannot read " + what + " '" + path + "': permission denied");
  std::string text(kMaxFileBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxFileBytes)
    throw SettingsError(what + " '" + path + "' is larger than 1 MiB");
  return text;
}

void check_token(const std::string& token, const std::string& origin) {
  for (const char c : token)
    if (c < 0x21 || c > 0x7e)
      throw SettingsError(origin +
                          ": the token has a space, a control or a non-ASCII character (not "
                          "allowed in an authorization header)");
}

void check_server(const std::string& s, const std::string& origin) {
  for (const char* scheme : {"unix:", "unix-abstract:", "dns:", "ipv4:", "ipv6:"})
    if (s.rfind(scheme, 0) == 0 && s.size() > std::string(scheme).size()) return;
  const std::string bad =
      origin + ": '" + s + "' is not HOST:PORT (e.g. localhost:50051 or 10.0.0.5:50051)";
  const std::size_t colon = s.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == s.size()) throw SettingsError(bad);
  const std::string host = s.substr(0, colon), port = s.substr(colon + 1);
  if (!std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; }) ||
      port.size() > 5 || std::stol(port) < 1 || std::stol(port) > 65535)
    throw SettingsError(bad + " (the port must be 1..65535)");
  if (std::any_of(host.begin(), host.end(),
                  [](char c) { return c <= 0x20 || c > 0x7e || c == '/'; }))
    throw SettingsError(bad);
}

// A config value that must be a string.
std::string config_string(const YAML::Node& v, const std::string& path, const std::string& key) {
  if (!v.IsScalar())
    throw SettingsError("config file '" + path + "': key '" + key + "' must be a string");
  return v.Scalar();
}

}  // namespace

Env process_env() {
  return [](const std::string& name) -> std::optional<std::string> {
    const char* v = std::getenv(name.c_str());
    if (!v) return std::nullopt;
    return std::string(v);
  };
}

void add_connection_flags(FlagSpec& spec) {
  spec.with_value.insert(spec.with_value.end(), {"--server", "--token-file", "--ca-file"});
  spec.switches.push_back("--tls");
}

const char* const kConnectionHelp =
    "Connection (each setting from the first of: flag, environment, config file):\n"
    "  --server HOST:PORT   the mdemd daemon ($MDEM_SERVER, config key server)\n"
    "  --token-file FILE    a file whose first non-empty line is your token, sent as\n"
    "                       'authorization: Bearer <token>' ($MDEM_TOKEN holds the token\n"
    "                       itself; config key token_file)\n"
    "  --tls                use TLS (config key tls: true|false; default: plain TCP)\n"
    "  --ca-file FILE       PEM root certificates to trust for TLS (implies --tls; default:\n"
    "                       the system's; config key ca_file)\n"
    "Config file: $MDEM_CONFIG, else $XDG_CONFIG_HOME/mdem/config.yaml, else\n"
    "~/.config/mdem/config.yaml; a YAML mapping of the keys above, e.g.\n"
    "    server: mdemd.lab.example:50051\n"
    "    token_file: ~/.config/mdem/token\n"
    "    tls: true\n"
    "Relative paths in it are relative to the file's directory. Unknown keys and values of the\n"
    "wrong type are errors (exit code 2).\n";

std::string config_file_path(const Env& env) {
  if (const auto p = non_empty(env, "MDEM_CONFIG")) return *p;
  if (const auto xdg = non_empty(env, "XDG_CONFIG_HOME"); xdg && xdg->front() == '/')
    return (fs::path(*xdg) / "mdem" / "config.yaml").string();
  if (const auto home = non_empty(env, "HOME"))
    return (fs::path(*home) / ".config" / "mdem" / "config.yaml").string();
  return "";
}

ConfigFile load_config(const Env& env) {
  ConfigFile cfg;
  const std::string path = config_file_path(env);
  if (path.empty()) return cfg;
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    if (non_empty(env, "MDEM_CONFIG"))
      throw SettingsError("config file '" + path + "' (from $MDEM_CONFIG): no such file");
    return cfg;
  }
  const std::string text = read_small_file(path, "the config file");
  cfg.path = path;
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw SettingsError("config file '" + path + "' line " + std::to_string(e.mark.line + 1) +
                        ", column " + std::to_string(e.mark.column + 1) +
                        ": malformed YAML: " + e.msg);
  }
  if (!root || root.IsNull()) return cfg;
  if (!root.IsMap())
    throw SettingsError("config file '" + path + "': expected a mapping of the keys " +
                        kConfigKeys);
  const fs::path dir = fs::path(path).parent_path();
  for (const auto& kv : root) {
    if (!kv.first.IsScalar())
      throw SettingsError("config file '" + path +
                          "': keys must be names (allowed: " + kConfigKeys + ")");
    const std::string key = kv.first.Scalar();
    const YAML::Node& v = kv.second;
    if (key != "server" && key != "token_file" && key != "tls" && key != "ca_file")
      throw SettingsError("config file '" + path + "': unknown key '" + key +
                          "' (allowed: " + kConfigKeys + ")");
    if (v.IsNull()) continue;  // `key:` with no value: unset
    if (key == "server") cfg.server = config_string(v, path, key);
    if (key == "token_file") cfg.token_file = expand_path(config_string(v, path, key), dir, env);
    if (key == "ca_file") cfg.ca_file = expand_path(config_string(v, path, key), dir, env);
    if (key == "tls") {
      bool b = false;
      if (!v.IsScalar() || !YAML::convert<bool>::decode(v, b))
        throw SettingsError("config file '" + path + "': key 'tls' must be true or false" +
                            (v.IsScalar() ? " (got '" + v.Scalar() + "')" : ""));
      cfg.tls = b;
    }
  }
  return cfg;
}

bool server_named(const std::map<std::string, std::string>& flags, const Env& env) {
  return flags.count("--server") > 0 || non_empty(env, "MDEM_SERVER").has_value();
}

std::string read_token_file(const std::string& path, const std::string& origin) {
  const std::string text = read_small_file(path, "the token file (from " + origin + ")");
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    const std::string token = trim(line);
    if (token.empty()) continue;
    check_token(token, "token file '" + path + "' (" + origin + ")");
    return token;
  }
  throw SettingsError("the token file '" + path + "' (" + origin + ") is empty");
}

ConnectionSettings resolve_connection(const std::map<std::string, std::string>& flags,
                                      const Env& env, const std::string& job_server,
                                      const std::string& job_token_file) {
  const ConfigFile cfg = load_config(env);
  const std::string in_config = cfg.path.empty() ? "" : " in config file '" + cfg.path + "'";
  ConnectionSettings c;
  c.config_path = cfg.path;

  if (flags.count("--server")) {
    c.server = flags.at("--server");
    c.server_origin = "--server";
  } else if (!job_server.empty()) {
    c.server = job_server;
    c.server_origin = "the job's record in the results database";
  } else if (const auto s = non_empty(env, "MDEM_SERVER")) {
    c.server = *s;
    c.server_origin = "$MDEM_SERVER";
  } else if (cfg.server) {
    c.server = *cfg.server;
    c.server_origin = "key 'server'" + in_config;
  } else {
    const std::string path = cfg.path.empty() ? config_file_path(env) : cfg.path;
    throw SettingsError(
        "no mdemd daemon named: give --server HOST:PORT, set $MDEM_SERVER, or put "
        "'server: HOST:PORT' in the config file" +
        (path.empty() ? std::string() : " '" + path + "'") +
        " (`mdem run` runs a job in this process without a daemon)");
  }
  check_server(c.server, c.server_origin);

  const auto from_file = [&](const std::string& path, std::string origin) {
    c.token_origin = std::move(origin);
    c.token = read_token_file(path, c.token_origin);
    std::error_code ec;
    const fs::path abs = fs::absolute(path, ec);
    c.token_file = ec ? path : abs.lexically_normal().string();
  };
  if (flags.count("--token-file")) {
    from_file(flags.at("--token-file"), "--token-file");
  } else if (!job_token_file.empty()) {
    from_file(job_token_file, "the token file recorded with the job at submit");
  } else if (const auto t = non_empty(env, "MDEM_TOKEN")) {
    c.token_origin = "$MDEM_TOKEN";
    c.token = trim(*t);
    check_token(c.token, c.token_origin);
  } else if (cfg.token_file) {
    from_file(*cfg.token_file, "key 'token_file'" + in_config);
  }

  c.tls = flags.count("--tls") > 0 || cfg.tls.value_or(false);
  if (flags.count("--ca-file"))
    c.ca_file = flags.at("--ca-file");
  else if (cfg.ca_file)
    c.ca_file = *cfg.ca_file;
  if (!c.ca_file.empty()) c.tls = true;
  return c;
}

void check_request_id(const std::string& id) {
  if (id.empty() || id.size() > 128)
    throw UsageError("--request-id: must have 1..128 characters (got " + std::to_string(id.size()) +
                     ")");
  for (const char c : id)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == ':' ||
          c == '-'))
      throw UsageError("--request-id: '" + id +
                       "' has a character outside [A-Za-z0-9._:-] (allowed: letters, digits, "
                       "'.', '_', ':' and '-')");
}

std::string new_request_id() {
  std::random_device rd;
  char hex[32];
  std::snprintf(hex, sizeof hex, "%08x%08x%08x", rd(), rd(), rd());
  return std::string("r-") + hex;
}

int exit_code_for(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::UNAVAILABLE:
    case grpc::StatusCode::DEADLINE_EXCEEDED:
    case grpc::StatusCode::UNIMPLEMENTED:
    case grpc::StatusCode::INTERNAL:
    case grpc::StatusCode::UNKNOWN:
    case grpc::StatusCode::DATA_LOSS:
      return kConnection;
    case grpc::StatusCode::INVALID_ARGUMENT:
      return kUsage;
    default:
      return kJobFailed;
  }
}

const char* status_code_name(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK:
      return "OK";
    case grpc::StatusCode::CANCELLED:
      return "CANCELLED";
    case grpc::StatusCode::UNKNOWN:
      return "UNKNOWN";
    case grpc::StatusCode::INVALID_ARGUMENT:
      return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND:
      return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS:
      return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED:
      return "PERMISSION_DENIED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION:
      return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED:
      return "ABORTED";
    case grpc::StatusCode::OUT_OF_RANGE:
      return "OUT_OF_RANGE";
    case grpc::StatusCode::UNIMPLEMENTED:
      return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL:
      return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE:
      return "UNAVAILABLE";
    case grpc::StatusCode::DATA_LOSS:
      return "DATA_LOSS";
    case grpc::StatusCode::UNAUTHENTICATED:
      return "UNAUTHENTICATED";
    default:
      return "status";
  }
}

std::string describe_status(const grpc::Status& status, const ConnectionSettings& c) {
  const std::string& s = c.server;
  const std::string msg = status.error_message();
  const std::string detail = msg.empty() ? "" : ": " + msg;
  switch (status.error_code()) {
    case grpc::StatusCode::UNAVAILABLE:
      return "cannot reach mdemd at " + s + " (is it running? check --server" +
             (c.server_origin == "--server" ? "" : "; the address is from " + c.server_origin) +
             (c.tls ? "; TLS is on: does the daemon use TLS?"
                    : "; if the daemon serves TLS, add --tls --ca-file FILE") +
             ")" + detail;
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      return "mdemd at " + s + " did not answer within " + std::to_string(kCallDeadlineMs / 1000) +
             " s (is it overloaded, or is " + s + " another service? check --server)" + detail;
    case grpc::StatusCode::UNAUTHENTICATED:
      // The daemon's own message for a missing token says what this one says: not repeated.
      if (c.token.empty())
        return "mdemd at " + s + " wants a token and none is configured: give --token-file FILE, " +
               "set $MDEM_TOKEN, or put 'token_file: FILE' in the config file";
      return "the server refused the token (from " + c.token_origin +
             "): check that it is the token mdemd's token file gives you" + detail;
    case grpc::StatusCode::PERMISSION_DENIED:
      return "not allowed by mdemd at " + s + detail +
             " (a user sees and cancels only their own jobs; other users' jobs need an admin "
             "token)";
    case grpc::StatusCode::NOT_FOUND:
      return (msg.empty() ? "not found" : msg) + " (on mdemd at " + s + "; `mdem ls --server " + s +
             "` lists your jobs)";
    case grpc::StatusCode::INVALID_ARGUMENT:
      return "mdemd at " + s + " refused the request" + detail;
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
      return "a per-user limit of mdemd at " + s + " refused it" + detail +
             " (wait for your jobs to finish, or cancel some with `mdem cancel`)";
    case grpc::StatusCode::UNIMPLEMENTED:
      return s + " does not offer this call (is it an mdemd of a matching version?)" + detail;
    default:
      return "mdemd at " + s + " answered " + status_code_name(status.error_code()) + detail;
  }
}

JobClient::JobClient(ConnectionSettings settings) : settings_(std::move(settings)) {
  std::shared_ptr<grpc::ChannelCredentials> creds;
  if (settings_.tls) {
    grpc::SslCredentialsOptions opts;
    if (!settings_.ca_file.empty())
      opts.pem_root_certs = read_small_file(settings_.ca_file, "the CA file");
    creds = grpc::SslCredentials(opts);
  } else {
    creds = grpc::InsecureChannelCredentials();
  }
  grpc::ChannelArguments args;
  args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, 30000);
  args.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 10000);
  args.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  args.SetInt(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);  // keep pinging a quiet watch
  // Reconnect within the watch's own backoff (0.2 s .. 5 s), not gRPC's default of up to 2 min.
  args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 200);
  args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 5000);
  // Despite its name, gRPC takes this as the least time a connection attempt may take before it
  // is abandoned (TCP connect plus the daemon's HTTP/2 SETTINGS). At 200 ms a daemon that is
  // busy or paused for a moment failed every call at once; at 20 s (gRPC's default) the call's
  // own deadline decides. A refused connection (no daemon listening) still fails at once.
  args.SetInt(GRPC_ARG_MIN_RECONNECT_BACKOFF_MS, kConnectAttemptTimeoutMs);
  args.SetMaxReceiveMessageSize(64 << 20);
  channel_ = grpc::CreateCustomChannel(settings_.server, creds, args);
  stub_ = v1::JobService::NewStub(channel_);
}

std::unique_ptr<grpc::ClientContext> JobClient::stream_context() const {
  auto ctx = std::make_unique<grpc::ClientContext>();
  if (!settings_.token.empty()) ctx->AddMetadata("authorization", "Bearer " + settings_.token);
  return ctx;
}

bool JobClient::wait_connected(std::chrono::system_clock::time_point deadline) {
  return channel_->WaitForConnected(deadline);
}

std::unique_ptr<grpc::ClientContext> JobClient::call_context() const {
  auto ctx = stream_context();
  ctx->set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(kCallDeadlineMs));
  return ctx;
}

void JobClient::fail(const grpc::Status& status) const {
  throw RemoteError(describe_status(status, settings_), status.error_code(),
                    exit_code_for(status.error_code()));
}

v1::SubmitJobResponse JobClient::submit(const v1::SubmitJobRequest& request) {
  v1::SubmitJobResponse response;
  const auto ctx = call_context();
  if (const grpc::Status s = stub_->SubmitJob(ctx.get(), request, &response); !s.ok()) fail(s);
  return response;
}

v1::JobInfo JobClient::get(const std::string& job_id) {
  v1::GetJobRequest request;
  request.set_job_id(job_id);
  v1::JobInfo info;
  const auto ctx = call_context();
  if (const grpc::Status s = stub_->GetJob(ctx.get(), request, &info); !s.ok()) fail(s);
  return info;
}

v1::ListJobsResponse JobClient::list(bool all_users, int limit, const std::string& study_id) {
  v1::ListJobsRequest request;
  request.set_all_users(all_users);
  request.set_limit(limit);
  request.set_study_id(study_id);
  v1::ListJobsResponse response;
  const auto ctx = call_context();
  if (const grpc::Status s = stub_->ListJobs(ctx.get(), request, &response); !s.ok()) fail(s);
  return response;
}

v1::JobInfo JobClient::cancel(const std::string& job_id) {
  v1::CancelJobRequest request;
  request.set_job_id(job_id);
  v1::JobInfo info;
  const auto ctx = call_context();
  if (const grpc::Status s = stub_->CancelJob(ctx.get(), request, &info); !s.ok()) fail(s);
  return info;
}

v1::JobInfo JobClient::resume(const std::string& job_id, double time_limit_s) {
  v1::ResumeJobRequest request;
  request.set_job_id(job_id);
  request.set_time_limit_s(time_limit_s);
  v1::JobInfo info;
  const auto ctx = call_context();
  if (const grpc::Status s = stub_->ResumeJob(ctx.get(), request, &info); !s.ok()) fail(s);
  return info;
}

}  // namespace mdem::cli
