#include "config.h"

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <functional>
#include <map>
#include <set>

#include "mdem/time_text.h"

namespace mdem::server {
namespace {

using Setter = std::function<void(DaemonConfig&, const std::string& value, const std::string& who)>;

double number(const std::string& v, const std::string& who, double lo, double hi) {
  double d = 0;
  const auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), d);
  if (ec != std::errc() || p != v.data() + v.size() || !std::isfinite(d) || d < lo || d > hi)
    throw ConfigError(who + ": '" + v + "' is not a number in [" + std::to_string(lo) + ", " +
                      std::to_string(hi) + "]");
  return d;
}

long integer(const std::string& v, const std::string& who, long lo, long hi) {
  long n = 0;
  const auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
  if (ec != std::errc() || p != v.data() + v.size() || n < lo || n > hi)
    throw ConfigError(who + ": '" + v + "' is not a whole number in [" + std::to_string(lo) + ", " +
                      std::to_string(hi) + "]");
  return n;
}

// A wall-time limit as Slurm's --time takes it ("2h", "1-00:00:00"), or "none" (0).
double time_limit(const std::string& v, const std::string& who) {
  if (v == "none") return 0;
  try {
    return parse_time_limit(v, who);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(std::string(e.what()) + ", or none");
  }
}

std::string text(const std::string& v, const std::string& who) {
  if (v.empty()) throw ConfigError(who + ": empty value");
  return v;
}

// key (config file) -> setter; the flag is "--" + key with '_' as '-'.
const std::map<std::string, Setter>& setters() {
  static const std::map<std::string, Setter> m = {
      {"listen", [](auto& c, auto& v, auto& w) { c.listen = text(v, w); }},
      {"data_dir", [](auto& c, auto& v, auto& w) { c.data_dir = text(v, w); }},
      {"token_file", [](auto& c, auto& v, auto& w) { c.token_file = text(v, w); }},
      {"port_file", [](auto& c, auto& v, auto& w) { c.port_file = text(v, w); }},
      {"tls_cert", [](auto& c, auto& v, auto& w) { c.tls_cert = text(v, w); }},
      {"tls_key", [](auto& c, auto& v, auto& w) { c.tls_key = text(v, w); }},
      {"workers", [](auto& c, auto& v, auto& w) { c.workers = integer(v, w, 1, 256); }},
      {"threads_per_job",
       [](auto& c, auto& v, auto& w) { c.threads_per_job = integer(v, w, 1, 256); }},
      {"checkpoint_every_s",
       [](auto& c, auto& v, auto& w) { c.checkpoint_every_s = number(v, w, 0.01, 86400); }},
      {"max_queued_per_user",
       [](auto& c, auto& v, auto& w) { c.max_queued_per_user = integer(v, w, 1, 1'000'000); }},
      {"max_elements",
       [](auto& c, auto& v, auto& w) { c.max_elements = integer(v, w, 1, 1'000'000'000); }},
      {"max_steps",
       [](auto& c, auto& v, auto& w) { c.max_steps = integer(v, w, 1, 1'000'000'000'000); }},
      {"event_buffer_mb",
       [](auto& c, auto& v, auto& w) { c.event_buffer_mb = number(v, w, 1, 65536); }},
      {"drain_timeout_s",
       [](auto& c, auto& v, auto& w) { c.drain_timeout_s = number(v, w, 0, 3600); }},
      {"default_time_limit",
       [](auto& c, auto& v, auto& w) { c.default_time_limit_s = time_limit(v, w); }},
      {"max_time_limit", [](auto& c, auto& v, auto& w) { c.max_time_limit_s = time_limit(v, w); }},
      {"keepalive_time_s",
       [](auto& c, auto& v, auto& w) { c.keepalive_time_s = integer(v, w, 1, 86400); }},
      {"log_level",
       [](auto& c, auto& v, auto& w) {
         static const std::set<std::string> ok = {"trace", "debug", "info", "warn", "error"};
         if (!ok.count(v))
           throw ConfigError(w + ": '" + v + "' is not one of trace, debug, info, warn, error");
         c.log_level = v;
       }},
  };
  return m;
}

// Seconds keys end in "_s" in the file; their flags leave it off (--checkpoint-every).
std::string flag_of(std::string key) {
  if (key.size() > 2 && key.ends_with("_s")) key.resize(key.size() - 2);
  for (char& ch : key)
    if (ch == '_') ch = '-';
  return "--" + key;
}

void load_file(DaemonConfig& c, const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError("config file '" + path + "': cannot open (missing or unreadable)");
  } catch (const YAML::Exception& e) {
    throw ConfigError("config file '" + path + "': not valid YAML: " + e.what());
  }
  if (root.IsNull()) return;
  if (!root.IsMap()) throw ConfigError("config file '" + path + "': expected a mapping of keys");
  std::map<std::string, int> seen;  // key -> its line
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    const int line = kv.first.Mark().line + 1;
    if (auto [it, fresh] = seen.emplace(key, line); !fresh)
      throw ConfigError("config file '" + path + "': key '" + key + "' given twice (lines " +
                        std::to_string(it->second) + " and " + std::to_string(line) +
                        "); give each key once");
    auto it = setters().find(key);
    if (it == setters().end()) {
      std::string allowed;
      for (const auto& [k, s] : setters()) allowed += (allowed.empty() ? "" : ", ") + k;
      throw ConfigError("config file '" + path + "': unknown key '" + key +
                        "' (allowed: " + allowed + ")");
    }
    if (!kv.second.IsScalar())
      throw ConfigError("config file '" + path + "': " + key + " must be a single value");
    it->second(c, kv.second.as<std::string>(), "config file '" + path + "': " + key);
  }
}

}  // namespace

DaemonConfig parse_daemon_config(const std::vector<std::string>& args) {
  std::map<std::string, std::string> flags;  // flag -> value, in the order they must apply
  std::string config_file;
  for (std::size_t i = 0; i < args.size(); ++i) {
    std::string a = args[i], value;
    const auto eq = a.find('=');
    if (eq != std::string::npos) {
      value = a.substr(eq + 1);
      a = a.substr(0, eq);
    } else if (i + 1 < args.size()) {
      value = args[++i];
    } else {
      throw ConfigError(a + ": missing value");
    }
    if (a.rfind("--", 0) != 0) throw ConfigError("'" + a + "': expected a flag (see --help)");
    if (flags.count(a) || (a == "--config" && !config_file.empty()))
      throw ConfigError(a + ": given twice");
    if (a == "--config")
      config_file = text(value, a);
    else
      flags[a] = value;
  }
  DaemonConfig c;
  if (!config_file.empty()) load_file(c, config_file);
  for (const auto& [flag, value] : flags) {
    bool known = false;
    for (const auto& [key, set] : setters())
      if (flag_of(key) == flag) {
        set(c, value, flag);
        known = true;
      }
    if (!known) throw ConfigError(flag + ": unknown flag (see mdemd --help)");
  }
  if (c.data_dir.empty()) throw ConfigError("--data-dir (data_dir) is required");
  if (c.token_file.empty()) throw ConfigError("--token-file (token_file) is required");
  if (c.tls_cert.empty() != c.tls_key.empty())
    throw ConfigError("--tls-cert and --tls-key go together (both for TLS, neither without)");
  if (c.max_time_limit_s > 0 && c.default_time_limit_s > c.max_time_limit_s)
    throw ConfigError("--default-time-limit (" + duration_text(c.default_time_limit_s) +
                      ") is above --max-time-limit (" + duration_text(c.max_time_limit_s) +
                      "); a job without a limit of its own would be refused");
  if (c.listen.find(':') == std::string::npos)
    throw ConfigError("--listen: '" + c.listen + "' is not HOST:PORT");
  return c;
}

const char* daemon_usage() {
  return "Usage: mdemd --data-dir DIR --token-file FILE [flags]   (or --config FILE)\n"
         "\n"
         "The mdem job daemon: a durable queue of simulation jobs (SQLite, DIR/jobs.db), run N at\n"
         "a time with M threads each, checkpointed to DIR/checkpoints, streamed to `mdem watch`.\n"
         "Settings come from defaults, then --config FILE (YAML, keys as below with '_'), then\n"
         "flags.\n"
         "\n"
         "  --config FILE            YAML file with any of the keys below\n"
         "  --listen HOST:PORT       address to serve (default 127.0.0.1:50051; port 0 = any)\n"
         "  --data-dir DIR           job database and checkpoints (required)\n"
         "  --token-file FILE        lines '<token> <user> [admin]' (required; mode 600: a file\n"
         "                           group or others may read is refused)\n"
         "  --port-file FILE         write the bound port here once serving\n"
         "  --tls-cert FILE --tls-key FILE   serve TLS with this PEM certificate and key\n"
         "  --workers N              jobs run at once, 1..256 (default 1)\n"
         "  --threads-per-job M      threads per job, 1..256 (default 1)\n"
         "  --checkpoint-every S     seconds between checkpoints of a running job (default 60)\n"
         "  --max-queued-per-user N  queued + running jobs per user (default 20)\n"
         "  --max-elements N         elements per job (default 2000000)\n"
         "  --max-steps N            steps per job (default 100000000)\n"
         "  --event-buffer-mb X      per-job buffer of frames/snapshots not yet on disk; beyond\n"
         "                           it they are coalesced and watchers are told (default 64)\n"
         "  --drain-timeout S        on SIGTERM, time for running jobs to checkpoint (default 30)\n"
         "  --default-time-limit T   wall-time limit of a job submitted without one, as Slurm's\n"
         "                           --time: 90s, 15m, 2h, 1.5d, MM, MM:SS, HH:MM:SS, "
         "D-HH[:MM[:SS]]\n"
         "                           (default none: --max-time-limit, or no limit)\n"
         "  --max-time-limit T       the longest limit a job may ask for, same forms (default\n"
         "                           none: 30 days); a job reaching its limit ends in TIMEOUT\n"
         "                           with its checkpoint kept (`mdem resume` continues it)\n"
         "  --keepalive-time S       HTTP/2 keepalive ping interval (default 30)\n"
         "  --log-level L            trace, debug, info, warn, error (default info)\n"
         "  --log-json true|false    one JSON object per log line (default false)\n"
         "  --version                print the version\n"
         "  -h, --help               show this help\n"
         "\n"
         "Signals: SIGTERM or SIGINT drains: running jobs checkpoint and go back to the queue,\n"
         "then the daemon exits 0. Exit codes: 0 clean stop, 2 bad settings, 1 runtime failure.\n";
}

}  // namespace mdem::server
