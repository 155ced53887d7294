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

#include "parse_failure.h"

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
  for (const fs::path& d : {fs::path(dir), fs::path(dir) / "checkpoints"})
    if (const std::string why = probe_write(d.string()); !why.empty())
      throw StartupError("data directory '" + dir + "': not writable (check its owner and " +
                         "permissions, or disk space): " + why);
}

// A PEM file as gRPC wants it: readable, and holding a block whose BEGIN line contains `kind`
// ("CERTIFICATE", "PRIVATE KEY"). gRPC itself only says that it cannot listen.
std::string read_pem(const std::string& path, const char* what, const std::string& kind) {
  std::error_code ec;
  if (fs::is_directory(path, ec))
    throw StartupError(std::string(what) + " '" + path + "': is a directory, not a PEM file");
  const std::string pem = read_file(path, what);
  if (pem.empty()) throw StartupError(std::string(what) + " '" + path + "': empty file");
  bool found = false;
  for (std::size_t at = pem.find("-----BEGIN "); at != std::string::npos && !found;
       at = pem.find("-----BEGIN ", at + 1)) {
    const std::size_t end = pem.find("-----", at + 11);
    found = end != std::string::npos && pem.substr(at, end - at).find(kind) != std::string::npos;
  }
  if (!found)
    throw StartupError(std::string(what) + " '" + path + "': no '-----BEGIN ..." + kind +
                       "-----' block; expected a PEM " +
                       (kind == "CERTIFICATE" ? "certificate" : "private key"));
  return pem;
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

// Whether `listen` can be served without TLS: when a TLS server cannot start, this tells a
// certificate or key gRPC refused from an address that cannot be bound.
bool can_listen_without_tls(const std::string& listen) {
  grpc::ServerBuilder builder;
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  int port = 0;
  builder.AddListeningPort(listen, grpc::InsecureServerCredentials(), &port);
  std::unique_ptr<grpc::Server> probe = builder.BuildAndStart();
  if (!probe || port == 0) return false;
  probe->Shutdown(std::chrono::system_clock::now());
  return true;
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
  const std::string db_path = (fs::path(config_.data_dir) / "jobs.db").string();
  store_ = std::make_unique<JobStore>(db_path);
  try {
    storage_ = std::make_unique<StorageHealth>(config_.data_dir, db_path);
  } catch (const std::runtime_error& e) {
    throw StartupError(e.what());
  }
  for (const std::string& id : store_->reconcile())
    spdlog::info("event=job_requeued job={} note=\"running when the daemon last stopped\"", id);
  writer_ = std::make_unique<EventWriter>(
      *store_, hub_, static_cast<std::size_t>(config_.event_buffer_mb * (1 << 20)));
  scheduler_ = std::make_unique<Scheduler>(config_, *store_, *writer_);
  service_ =
      std::make_unique<JobServiceImpl>(config_, tokens_, *store_, *scheduler_, hub_, *storage_);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  std::shared_ptr<grpc::ServerCredentials> creds;
  if (!config_.tls_cert.empty()) {
    grpc::SslServerCredentialsOptions ssl;
    ssl.pem_key_cert_pairs.push_back(
        {read_pem(config_.tls_key, "TLS key", "PRIVATE KEY"),
         read_pem(config_.tls_cert, "TLS certificate", "CERTIFICATE")});
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
  // Requests are bounded: 4 MiB (gRPC's default, stated) and protobuf's nesting limit of 100.
  builder.SetMaxReceiveMessageSize(kMaxRequestBytes);
  std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> intercept;
  intercept.push_back(std::make_unique<ParseFailureInterceptorFactory>());
  builder.experimental().SetInterceptorCreators(std::move(intercept));
  server_ = builder.BuildAndStart();
  if (!server_ || port_ == 0) {
    server_.reset();
    if (!config_.tls_cert.empty() && can_listen_without_tls(config_.listen))
      throw StartupError("TLS refused the certificate '" + config_.tls_cert + "' or the key '" +
                         config_.tls_key + "' (are both valid PEM, and is the key the " +
                         "certificate's?); '" + config_.listen + "' itself can be served");
    throw StartupError("cannot listen on '" + config_.listen +
                       "' (address in use, or not HOST:PORT?)");
  }
  server_->GetHealthCheckService()->SetServingStatus(true);
  scheduler_->start();
  if (!config_.port_file.empty()) write_port_file(config_.port_file, port_);
  // Last: nothing after it can throw, so the monitor never outlives the server it reports to.
  storage_->start(std::chrono::seconds(1), [this](bool serving) {
    server_->GetHealthCheckService()->SetServingStatus(serving);
  });
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
  if (storage_) storage_->stop();  // health stays NOT_SERVING from here on
  if (server_) server_->GetHealthCheckService()->SetServingStatus(false);
  if (scheduler_) scheduler_->drain();
  if (server_) server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
  spdlog::info("event=stopped");
}

}  // namespace mdem::server
