#include "storage_health.h"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "fault_injection.h"

namespace mdem::server {
namespace {

std::string errno_text() { return std::strerror(errno); }

bool same_file(const struct stat& a, const struct stat& b) {
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

}  // namespace

std::string probe_write(const std::string& dir) {
  if (auto injected = injected_write_failure())
    return "cannot write in '" + dir + "': " + *injected;
  const std::string path = (std::filesystem::path(dir) / ".mdemd-write-probe").string();
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) return "cannot create a file in '" + dir + "': " + errno_text();
  std::string error;
  if (::write(fd, "ok", 2) != 2) error = "cannot write in '" + dir + "': " + errno_text();
  ::close(fd);
  ::unlink(path.c_str());
  return error;
}

StorageHealth::StorageHealth(std::string data_dir, std::string db_path)
    : data_dir_(std::move(data_dir)), db_path_(std::move(db_path)) {
  dir_fd_ = ::open(data_dir_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd_ < 0)
    throw std::runtime_error("data directory '" + data_dir_ + "': cannot open: " + errno_text());
  // Kept open for the daemon's life (after the database is closed: closing another descriptor
  // of the file would drop SQLite's locks on it), so its inode cannot be reused unnoticed.
  db_fd_ = ::open(db_path_.c_str(), O_RDONLY | O_CLOEXEC);
  if (db_fd_ < 0) {
    ::close(dir_fd_);
    throw std::runtime_error("job database '" + db_path_ + "': cannot open: " + errno_text());
  }
}

StorageHealth::~StorageHealth() {
  stop();
  ::close(db_fd_);
  ::close(dir_fd_);
}

std::string StorageHealth::diagnose() const {
  struct stat held {
  }, now{};
  const std::string dir = "data directory '" + data_dir_ + "'";
  if (::stat(data_dir_.c_str(), &now) != 0) return dir + " is gone: " + errno_text();
  if (!S_ISDIR(now.st_mode)) return dir + " was replaced by something that is not a directory";
  if (::fstat(dir_fd_, &held) != 0 || !same_file(held, now))
    return dir + " was replaced: it is not the directory mdemd started on";
  const std::string db = "job database '" + db_path_ + "'";
  if (::stat(db_path_.c_str(), &now) != 0) return db + " is gone: " + errno_text();
  if (::fstat(db_fd_, &held) != 0 || !same_file(held, now))
    return db + " was replaced by another file";
  if (held.st_nlink == 0) return db + " was deleted while mdemd had it open";
  for (const std::string& d :
       {data_dir_, (std::filesystem::path(data_dir_) / "checkpoints").string()})
    if (std::string why = probe_write(d); !why.empty())
      return dir + " does not take writes: " + why;
  return {};
}

std::string StorageHealth::check() {
  std::string why;
  {
    std::lock_guard probe(probe_mu_);
    why = diagnose();
  }
  std::function<void(bool)> notify;
  {
    std::lock_guard lock(state_mu_);
    if (healthy_ != why.empty()) {
      healthy_ = why.empty();
      if (healthy_)
        spdlog::info("event=storage_ok note=\"the data directory takes new jobs again\"");
      else
        spdlog::error("event=storage_fault reason=\"{}\" note=\"submits are refused\"", why);
      notify = on_change_;
    }
  }
  if (notify) notify(why.empty());
  return why;
}

void StorageHealth::start(std::chrono::milliseconds period,
                          std::function<void(bool serving)> on_change) {
  {
    std::lock_guard lock(state_mu_);
    on_change_ = std::move(on_change);
  }
  thread_ = std::thread([this, period] {
    std::unique_lock lock(stop_mu_);
    while (!stop_cv_.wait_for(lock, period, [&] { return stopping_; })) {
      lock.unlock();
      check();
      lock.lock();
    }
  });
}

void StorageHealth::stop() {
  {
    std::lock_guard lock(stop_mu_);
    stopping_ = true;
  }
  stop_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  std::lock_guard lock(state_mu_);
  on_change_ = nullptr;
}

}  // namespace mdem::server
