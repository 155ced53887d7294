#include "daemon.h"

#include <fcntl.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <spdlog/spdlog.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace mdem::server {
namespace {

namespace fs = std::filesystem;

std::string read_file(const std::string& path, const char* what) {
  std::ifstream in(path);
  if (!in) throw StartupError(std::string(what) + " '" + path + "': cannot open");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The data directory must exist (or be creatable) and take writes: checked up front, so a
// misconfigured daemon refuses to start instead of failing jobs later.
void check_data_dir(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "checkpoints", ec);
  if (ec)
    throw StartupError("data directory '" + dir +
                       "': cannot create it or its checkpoints/: " + ec.message());
  const fs::path probe = fs::path(dir) / "checkpoints" / ".write-test";
  {
    std::ofstream out(probe);
    out << "ok";
    if (!out.flush())
      throw StartupError("data directory '" + dir +
                         "': not writable (check its owner and permissions, or disk space)");
  }
  fs::remove(probe, ec);
}

// One daemon per data directory: an exclusive lock on DIR/lock, held for the process's life
// (released by the kernel on any exit, kill -9 included).
int lock_data_dir(const std::string& dir) {
  const std::string path = (fs::path(dir) / "lock").string();
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw StartupError("data directory '" + dir + "': cannot create its lock file");
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd);
    throw StartupError("data directory '" + dir + "' is in use by another mdemd (it holds " + path +
                       ")");
  }
  return fd;
}

void write_port_file(const std::string& path, int port) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    out << port << "\n";
    if (!out.flush()) throw StartupError("port file '" + path + "': cannot write");
  }
  fs::rename(tmp, path);
}

}  // namespace

Daemon::Daemon(const DaemonConfig& config)
    : config_(config), tokens_(TokenTable::load(config.token_file)) {
  check_data_dir(config_.data_dir);
  lock_fd_ = lock_data_dir(config_.data_dir);
  store_ = std::make_unique<JobStore>((fs::path(config_.data_dir) / "jobs.db").string());
  for (const std::string& id : store_->reconcile())
    spdlog::info("event=job_requeued job={} note=\"running when the daemon last stopped\"", id);
  writer_ = std::make_unique<EventWriter>(
      *store_, hub_, static_cast<std::size_t>(config_.event_buffer_mb * (1 << 20)));
  scheduler_ = std::make_unique<Scheduler>(config_, *store_, *writer_);
  service_ = std::make_unique<JobServiceImpl>(config_, tokens_, *store_, *scheduler_, hub_);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  std::shared_ptr<grpc::ServerCredentials> creds;
  if (!config_.tls_cert.empty()) {
    grpc::SslServerCredentialsOptions ssl;
    ssl.pem_key_cert_pairs.push_back(
        {read_file(config_.tls_key, "TLS key"), read_file(config_.tls_cert, "TLS certificate")});
    creds = grpc::SslServerCredentials(ssl);
  } else {
    creds = grpc::InsecureServerCredentials();
  }
  grpc::ServerBuilder builder;
  // One daemon per address: gRPC would otherwise let a second process bind the same port.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder.AddListeningPort(config_.listen, creds, &port_);
  builder.RegisterService(service_.get());
  // Keepalive: ping idle connections so a vanished watcher is noticed, and accept clients'
  // pings down to every 10 s.
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, config_.keepalive_time_s * 1000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 10000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 10000);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
  server_ = builder.BuildAndStart();
  if (!server_ || port_ == 0)
    throw StartupError("cannot listen on '" + config_.listen +
                       "' (address in use, or not HOST:PORT?)");
  server_->GetHealthCheckService()->SetServingStatus(true);
  scheduler_->start();
  if (!config_.port_file.empty()) write_port_file(config_.port_file, port_);
  spdlog::info(
      "event=serving listen={} port={} tls={} workers={} threads_per_job={} "
      "checkpoint_every_s={} data_dir={}",
      config_.listen, port_, !config_.tls_cert.empty(), config_.workers, config_.threads_per_job,
      config_.checkpoint_every_s, config_.data_dir);
}

Daemon::~Daemon() { shutdown(); }

void Daemon::shutdown() {
  if (stopped_) return;
  stopped_ = true;
  spdlog::info("event=draining");
  if (server_) server_->GetHealthCheckService()->SetServingStatus(false);
  if (scheduler_) scheduler_->drain();
  if (server_) server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
  spdlog::info("event=stopped");
}

}  // namespace mdem::server
