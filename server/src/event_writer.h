#pragma once
// Between a running job and the job database: each job pushes its events into its own bounded
// buffer and never waits for the disk; one writer thread commits the buffers in batches (one
// transaction per job per round) and wakes the watchers. When a job outruns the disk by more than
// its buffer, droppable events (energy frames, snapshots, progress) are not logged - a Coalesced
// event says how many - while state changes, columns, logs and the final report always are
// (service.md "Streaming"). When a commit fails (a full disk), the events are kept, in order, and
// retried every half second; the job runs on, and its log catches up once the disk takes writes.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "job_store.h"

namespace mdem::server {

// Watchers wait here for new events of any job (a generation counter bumped on every commit).
class EventHub {
 public:
  long generation() const;
  void notify();
  // Returns when the generation moves past `seen` or after `timeout`.
  void wait(long seen, std::chrono::milliseconds timeout) const;

 private:
  mutable std::mutex mu_;
  mutable std::condition_variable cv_;
  long generation_ = 0;
};

class EventWriter;

// One job's buffer. Thread-safe; the job's thread pushes, the writer drains.
class EventChannel {
 public:
  // Appends events that must be logged (state, columns, log, report).
  void push(v1::JobEvent e);
  // Appends a group (e.g. the chunks of one snapshot) that is logged whole or not at all:
  // dropped when the buffer holds more than its capacity.
  void push_droppable(std::vector<v1::JobEvent> group, long step, bool is_snapshot);
  // Blocks until everything pushed so far is committed. Throws SqliteError at once while the
  // writer cannot commit this job's events (they are kept and retried).
  void flush();
  // Blocks until everything pushed so far is committed, through failed commits (the writer
  // retries them). Returns false, with events still uncommitted, once give_up() is true (asked
  // every 0.2 s).
  bool flush_retrying(const std::function<bool()>& give_up);
  const std::string& job_id() const { return job_id_; }

 private:
  friend class EventWriter;
  EventChannel(EventWriter* writer, std::string job_id, std::size_t capacity)
      : writer_(writer), job_id_(std::move(job_id)), capacity_(capacity) {}
  void wake_writer();
  EventWriter* writer_;
  std::string job_id_;
  std::size_t capacity_;
  std::mutex mu_;
  std::condition_variable flushed_;
  std::deque<v1::JobEvent> pending_;
  std::size_t pending_bytes_ = 0;
  long pushed_ = 0, committed_ = 0;
  long dropped_frames_ = 0, dropped_snapshots_ = 0, dropped_up_to_ = 0;
  std::string error_;  // why the last commit failed; empty once one succeeds
  std::chrono::steady_clock::time_point retry_at_;
};

class EventWriter {
 public:
  EventWriter(JobStore& store, EventHub& hub, std::size_t capacity_bytes);
  ~EventWriter();
  EventWriter(const EventWriter&) = delete;
  EventWriter& operator=(const EventWriter&) = delete;

  std::shared_ptr<EventChannel> open(const std::string& job_id);
  void close(const std::string& job_id);

 private:
  void loop();
  void drain(EventChannel& ch);
  JobStore& store_;
  EventHub& hub_;
  std::size_t capacity_;
  std::mutex mu_;
  std::condition_variable wake_;
  std::map<std::string, std::shared_ptr<EventChannel>> channels_;
  bool stop_ = false;
  std::thread thread_;
  friend class EventChannel;
};

}  // namespace mdem::server
