#pragma once
// The scheduler (service.md "Sharing a queue"): a dispatcher hands the next job the store's fair
// order gives to an Executor (today N worker threads, executor.h) whenever it has room; each job
// runs through the shared JobRunner with the job's fixed thread count, its events going through
// an EventChannel, its state checkpointed at a wall-clock cadence. Cancel and drain reach a
// running job between chunks of steps (well under a second).
#include <atomic>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "config.h"
#include "event_writer.h"
#include "executor.h"
#include "job_store.h"
#include "mdem/job/job.h"

namespace mdem::server {

class Scheduler {
 public:
  // executor: where jobs run; nullptr = a pool of config.workers threads.
  Scheduler(const DaemonConfig& config, JobStore& store, EventWriter& writer,
            std::unique_ptr<Executor> executor = nullptr);
  ~Scheduler();
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  void start();
  // A job was queued: a free worker takes it.
  void wake();
  // Stops a queued or running job. Returns false when the job is neither.
  bool cancel(const std::string& job_id, const std::string& reason);
  // Stops taking jobs; running jobs checkpoint and go back to the queue; waits for the workers
  // up to the drain timeout (a job still running then is requeued by reconcile at next start).
  void drain();

  std::string checkpoint_path(const std::string& job_id) const;

  // What a running job has used so far: its running time (every run added up) and the peak of
  // its data (System::memory_bytes), as of its last poll.
  struct Usage {
    double elapsed_s = 0;
    long peak_bytes = 0;
    long daemon_rss_peak_bytes = 0;  // the daemon's, getrusage's ru_maxrss
  };
  // The usage of a job running now; nullopt for any other.
  std::optional<Usage> usage(const std::string& job_id);

 private:
  enum Stop : int { kRun = 0, kCancel = 1, kDrain = 2, kTimeout = 3 };
  struct Control {
    std::atomic<int> stop{kRun};
    std::string reason;  // set before stop, read after
    std::mutex usage_mu;
    Usage usage;  // under usage_mu: written at the job's polls, read by GetJob/ListJobs
  };
  // Hands queued jobs to the executor while it has room, until stopping.
  void dispatch();
  void run(const JobRow& row, Control& ctl);
  // For a job built only by the worker: initializes it (which checks the time step) and throws
  // std::invalid_argument when it needs more steps than max_steps.
  void check_steps(Job& job) const;

  DaemonConfig config_;
  JobStore& store_;
  EventWriter& writer_;
  std::mutex mu_;
  std::condition_variable cv_;
  bool stopping_ = false;
  std::map<std::string, std::shared_ptr<Control>> running_;
  std::unique_ptr<Executor> executor_;
  std::thread dispatcher_;
  int active_workers_ = 0;  // jobs handed to the executor and not yet ended
};

}  // namespace mdem::server
