#pragma once
// mdemd assembled: data directory checks, the job database (reconciled at start), the event
// writer, the worker pool and the gRPC server (JobService, grpc.health.v1, reflection, keepalive,
// optional TLS). main() only parses flags, sets up logging and waits for a signal.
#include <grpcpp/grpcpp.h>

#include <memory>
#include <stdexcept>

#include "config.h"
#include "event_writer.h"
#include "job_service.h"
#include "job_store.h"
#include "scheduler.h"
#include "storage_health.h"
#include "tokens.h"

namespace mdem::server {

// The daemon cannot start: the message says what to fix.
// The largest request mdemd reads (gRPC refuses more with RESOURCE_EXHAUSTED).
constexpr int kMaxRequestBytes = 4 << 20;

struct StartupError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Daemon {
 public:
  // Checks the data directory and the token file, opens and reconciles the database, starts the
  // workers and the server. Throws StartupError (or TokenFileError, SqliteError).
  explicit Daemon(const DaemonConfig& config);
  ~Daemon();
  int port() const { return port_; }
  // Drains the workers (running jobs checkpoint and requeue), then stops the server.
  void shutdown();

 private:
  DaemonConfig config_;
  TokenTable tokens_;
  std::unique_ptr<StorageHealth> storage_;  // before store_: closed after the database
  std::unique_ptr<JobStore> store_;
  EventHub hub_;
  std::unique_ptr<EventWriter> writer_;
  std::unique_ptr<Scheduler> scheduler_;
  std::unique_ptr<JobServiceImpl> service_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
  int lock_fd_ = -1;
  bool stopped_ = false;
};

}  // namespace mdem::server
