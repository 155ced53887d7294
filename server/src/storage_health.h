#pragma once
// Whether the daemon can still keep what it accepts (service.md "Durability"): the data directory
// must still be the one it started on, hold the job database it has open, and take writes. A
// submit is acknowledged only after this check passes, and a monitor thread repeats it every
// second so that health (grpc.health.v1) turns NOT_SERVING when it fails - and SERVING again when
// a transient fault (read-only remount, full disk) clears.
#include <sys/types.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace mdem::server {

// Tries to create, write and remove a small file in `dir`; empty when that worked, otherwise
// what failed (with the system's reason, e.g. "No space left on device").
std::string probe_write(const std::string& dir);

class StorageHealth {
 public:
  // Records the identity (device, inode) of the data directory and of the database file through
  // handles held for the daemon's life, so neither can be deleted and replaced unnoticed. The
  // database must exist. Throws std::runtime_error when either cannot be opened.
  StorageHealth(std::string data_dir, std::string db_path);
  ~StorageHealth();
  StorageHealth(const StorageHealth&) = delete;
  StorageHealth& operator=(const StorageHealth&) = delete;

  // Checks now: empty when the data directory can keep new jobs, otherwise the reason. A change
  // between healthy and not is logged and reported to the listener.
  std::string check();
  // Every `period`, check(); on_change(serving) is called on each change (and never after stop).
  void start(std::chrono::milliseconds period, std::function<void(bool serving)> on_change);
  void stop();

 private:
  std::string diagnose() const;
  std::string data_dir_, db_path_;
  int dir_fd_ = -1, db_fd_ = -1;
  std::mutex probe_mu_;  // one probe at a time (they share a file name)
  std::mutex state_mu_;
  bool healthy_ = true;
  std::function<void(bool)> on_change_;
  std::mutex stop_mu_;
  std::condition_variable stop_cv_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace mdem::server
