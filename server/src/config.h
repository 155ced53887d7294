#pragma once
// mdemd's settings: defaults, then a YAML config file (--config FILE), then flags. Every value is
// checked with a message that names the key or flag and what is allowed.
#include <stdexcept>
#include <string>
#include <vector>

namespace mdem::server {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct DaemonConfig {
  std::string listen = "127.0.0.1:50051";  // host:port; port 0 picks a free one
  std::string data_dir;                    // required: jobs.db and checkpoints/
  std::string token_file;                  // required
  std::string port_file;                   // optional: the bound port is written here
  std::string tls_cert, tls_key;           // both or neither: TLS on
  int workers = 1;                         // N jobs at once
  int threads_per_job = 1;                 // M OpenMP threads each
  double checkpoint_every_s = 60;          // wall seconds between checkpoints of a running job
  long max_queued_per_user = 20;           // queued + running jobs per user
  long max_elements = 2'000'000;           // per job
  long max_steps = 100'000'000;            // per job
  double event_buffer_mb = 64;             // per job, frames/snapshots waiting for the disk
  double drain_timeout_s = 30;             // SIGTERM: wait this long for jobs to checkpoint
  // Wall-time limits of jobs' running time, as Slurm's partition DefaultTime and MaxTime: the
  // limit of a job submitted without one (0 = max_time_limit_s, or none when that is 0 too), and
  // the largest a job may ask for (0 = up to mdem's own 30 days).
  double default_time_limit_s = 0;
  double max_time_limit_s = 0;
  int keepalive_time_s = 30;       // server-side HTTP/2 keepalive pings
  std::string log_level = "info";  // trace, debug, info, warn, error
};

// Parses argv (without the program name). Throws ConfigError; `--help` is handled by the caller.
DaemonConfig parse_daemon_config(const std::vector<std::string>& args);
const char* daemon_usage();

}  // namespace mdem::server
