#pragma once
// Where the daemon's jobs execute. The scheduler decides which job runs next, tracks it and
// stops it (its logic); an executor only runs the work it is handed, up to capacity() at once.
// The thread pool below is today's executor; one that hands jobs to a cluster scheduler (a
// Slurm allocation running the same JobRunner) implements the same interface without touching
// the scheduler.
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace mdem::server {

class Executor {
 public:
  virtual ~Executor() = default;
  // Jobs it runs at once; the scheduler hands it no more.
  virtual int capacity() const = 0;
  // Runs `task` (one job, to its end) somewhere; returns at once.
  virtual void submit(std::function<void()> task) = 0;
  // Stops taking work. all_done: every submitted task has ended (wait for the threads);
  // otherwise tasks still running are abandoned to the process's exit.
  virtual void shutdown(bool all_done) = 0;
};

// N threads of this process, each running one task at a time.
class ThreadPoolExecutor final : public Executor {
 public:
  explicit ThreadPoolExecutor(int threads);
  ~ThreadPoolExecutor() override;
  ThreadPoolExecutor(const ThreadPoolExecutor&) = delete;
  ThreadPoolExecutor& operator=(const ThreadPoolExecutor&) = delete;

  int capacity() const override { return static_cast<int>(threads_.size()); }
  void submit(std::function<void()> task) override;
  void shutdown(bool all_done) override;

 private:
  void loop();
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::function<void()>> tasks_;
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace mdem::server
