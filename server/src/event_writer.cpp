#include "event_writer.h"

#include <spdlog/spdlog.h>

#include "fault_injection.h"

namespace mdem::server {
namespace {
constexpr auto kRetryEvery = std::chrono::milliseconds(500);
}  // namespace

long EventHub::generation() const {
  std::lock_guard lock(mu_);
  return generation_;
}

void EventHub::notify() {
  {
    std::lock_guard lock(mu_);
    ++generation_;
  }
  cv_.notify_all();
}

void EventHub::wait(long seen, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(mu_);
  cv_.wait_for(lock, timeout, [&] { return generation_ != seen; });
}

void EventChannel::push(v1::JobEvent e) {
  {
    std::lock_guard lock(mu_);
    pending_bytes_ += e.ByteSizeLong();
    pending_.push_back(std::move(e));
    ++pushed_;
  }
  wake_writer();
}

void EventChannel::push_droppable(std::vector<v1::JobEvent> group, long step, bool is_snapshot) {
  {
    std::lock_guard lock(mu_);
    if (pending_bytes_ > capacity_) {
      (is_snapshot ? dropped_snapshots_ : dropped_frames_) += 1;
      dropped_up_to_ = step;
      return;
    }
    if (dropped_frames_ + dropped_snapshots_ > 0) {
      v1::JobEvent c;
      c.mutable_coalesced()->set_frames(dropped_frames_);
      c.mutable_coalesced()->set_snapshots(dropped_snapshots_);
      c.mutable_coalesced()->set_up_to_step(dropped_up_to_);
      dropped_frames_ = dropped_snapshots_ = 0;
      pending_bytes_ += c.ByteSizeLong();
      pending_.push_back(std::move(c));
      ++pushed_;
    }
    for (v1::JobEvent& e : group) {
      pending_bytes_ += e.ByteSizeLong();
      pending_.push_back(std::move(e));
      ++pushed_;
    }
  }
  wake_writer();
}

void EventChannel::flush() {
  std::unique_lock lock(mu_);
  const long target = pushed_;
  flushed_.wait(lock, [&] { return committed_ >= target || !error_.empty(); });
  if (!error_.empty()) throw SqliteError(error_);
}

bool EventChannel::flush_retrying(const std::function<bool()>& give_up) {
  std::unique_lock lock(mu_);
  const long target = pushed_;
  while (committed_ < target) {
    if (give_up()) return false;
    flushed_.wait_for(lock, std::chrono::milliseconds(200));
  }
  return true;
}

void EventChannel::wake_writer() {
  std::lock_guard lock(writer_->mu_);
  writer_->wake_.notify_one();
}

EventWriter::EventWriter(JobStore& store, EventHub& hub, std::size_t capacity_bytes)
    : store_(store), hub_(hub), capacity_(capacity_bytes), thread_([this] { loop(); }) {}

EventWriter::~EventWriter() {
  {
    std::lock_guard lock(mu_);
    stop_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

std::shared_ptr<EventChannel> EventWriter::open(const std::string& job_id) {
  std::lock_guard lock(mu_);
  auto ch = std::shared_ptr<EventChannel>(new EventChannel(this, job_id, capacity_));
  channels_[job_id] = ch;
  return ch;
}

void EventWriter::close(const std::string& job_id) {
  std::lock_guard lock(mu_);
  channels_.erase(job_id);
}

void EventWriter::drain(EventChannel& ch) {
  std::vector<v1::JobEvent> batch;
  {
    std::lock_guard lock(ch.mu_);
    if (ch.pending_.empty()) return;
    if (!ch.error_.empty() && std::chrono::steady_clock::now() < ch.retry_at_) return;
    batch.assign(std::make_move_iterator(ch.pending_.begin()),
                 std::make_move_iterator(ch.pending_.end()));
    ch.pending_.clear();
    ch.pending_bytes_ = 0;
  }
  const long n = static_cast<long>(batch.size());
  std::string error;
  try {
    if (auto injected = injected_write_failure())
      throw SqliteError("job database: cannot log an event: " + *injected);
    store_.append(ch.job_id(), batch);
  } catch (const std::exception& e) {
    error = e.what();
  }
  {
    std::lock_guard lock(ch.mu_);
    if (error.empty()) {
      ch.committed_ += n;
      if (!ch.error_.empty())
        spdlog::info("event=log_recovered job={} note=\"the events held back are logged\"",
                     ch.job_id());
      ch.error_.clear();
    } else {
      // Kept ahead of what was pushed since, and retried: the log has no gap, the job no wait.
      std::size_t bytes = 0;
      for (const v1::JobEvent& e : batch) bytes += e.ByteSizeLong();
      ch.pending_.insert(ch.pending_.begin(), std::make_move_iterator(batch.begin()),
                         std::make_move_iterator(batch.end()));
      ch.pending_bytes_ += bytes;
      if (ch.error_.empty())
        spdlog::error(
            "event=log_failed job={} error=\"{}\" note=\"the job runs on; its events are held "
            "(frames beyond the buffer coalesced) and retried every 0.5 s\"",
            ch.job_id(), error);
      ch.error_ = error;
      ch.retry_at_ = std::chrono::steady_clock::now() + kRetryEvery;
    }
  }
  ch.flushed_.notify_all();
}

void EventWriter::loop() {
  std::unique_lock lock(mu_);
  while (true) {
    // Wake on a push, or every 50 ms: batching frames into fewer transactions.
    wake_.wait_for(lock, std::chrono::milliseconds(50));
    std::vector<std::shared_ptr<EventChannel>> chans;
    for (auto& [id, ch] : channels_) chans.push_back(ch);
    const bool stopping = stop_;
    lock.unlock();
    for (auto& ch : chans) drain(*ch);
    hub_.notify();
    lock.lock();
    if (stopping) break;
  }
}

}  // namespace mdem::server
