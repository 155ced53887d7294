#include "scheduler.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <optional>

#include "fault_injection.h"
#include "mdem/checkpoint_file.h"
#include "mdem/job_runner.h"
#include "mdem/process_memory.h"
#include "mdem/snapshot_proto.h"
#include "mdem/spec_job.h"
#include "mdem/time_text.h"

namespace mdem::server {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::size_t kChunkBytes = 1 << 20;  // snapshot pieces, well under gRPC's 4 MiB limit

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

v1::JobEvent state_event(v1::JobState s, const std::string& reason) {
  v1::JobEvent e;
  e.mutable_state()->set_state(s);
  e.mutable_state()->set_reason(reason);
  return e;
}

// Why a job stopped at its wall-time limit, and how to continue it.
std::string timeout_reason(const JobRow& row, double elapsed_s, long step) {
  return "wall-time limit " + duration_text(row.time_limit_s) + " reached after " +
         duration_text(elapsed_s) + " of running time (queue time not counted); stopped at step " +
         std::to_string(step) + " with its checkpoint kept: `mdem resume " + row.id +
         " --time-limit T` continues it from there with T more running time";
}

v1::JobEvent report_event(const std::string& json) {
  v1::JobEvent e;
  e.mutable_report()->set_json(json);
  return e;
}

std::vector<v1::JobEvent> snapshot_events(const Snapshot& s, int stage) {
  std::string bytes;
  snapshot_to_proto(s).SerializeToString(&bytes);
  const std::size_t count =
      std::max<std::size_t>(1, (bytes.size() + kChunkBytes - 1) / kChunkBytes);
  std::vector<v1::JobEvent> out;
  for (std::size_t k = 0; k < count; ++k) {
    v1::JobEvent e;
    v1::SnapshotChunk* c = e.mutable_snapshot();
    c->set_step(s.step);
    c->set_time_ps(s.time_ps);
    c->set_index(static_cast<int>(k));
    c->set_count(static_cast<int>(count));
    c->set_stage(stage);
    c->set_data(bytes.substr(k * kChunkBytes, kChunkBytes));
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace

Scheduler::Scheduler(const DaemonConfig& config, JobStore& store, EventWriter& writer,
                     std::unique_ptr<Executor> executor)
    : config_(config), store_(store), writer_(writer), executor_(std::move(executor)) {}

Scheduler::~Scheduler() {
  {
    std::lock_guard lock(mu_);
    stopping_ = true;
  }
  cv_.notify_all();
  if (dispatcher_.joinable()) dispatcher_.join();
  if (executor_) executor_->shutdown(true);  // the jobs under way end first
}

std::string Scheduler::checkpoint_path(const std::string& job_id) const {
  return (std::filesystem::path(config_.data_dir) / "checkpoints" / (job_id + ".ckpt")).string();
}

void Scheduler::start() {
  if (!executor_) executor_ = std::make_unique<ThreadPoolExecutor>(config_.workers);
  dispatcher_ = std::thread([this] { dispatch(); });
}

void Scheduler::wake() { cv_.notify_all(); }

std::optional<Scheduler::Usage> Scheduler::usage(const std::string& job_id) {
  std::lock_guard lock(mu_);
  auto it = running_.find(job_id);
  if (it == running_.end()) return std::nullopt;
  std::lock_guard u(it->second->usage_mu);
  return it->second->usage;
}

bool Scheduler::cancel(const std::string& job_id, const std::string& reason) {
  std::lock_guard lock(mu_);
  auto it = running_.find(job_id);
  if (it != running_.end()) {
    it->second->reason = reason;
    it->second->stop = kCancel;
    return true;
  }
  return store_.cancel_queued(job_id, reason);
}

void Scheduler::drain() {
  std::unique_lock lock(mu_);
  stopping_ = true;
  for (auto& [id, ctl] : running_) {
    ctl->reason = "the daemon is stopping";
    ctl->stop = kDrain;
  }
  cv_.notify_all();
  const auto deadline = Clock::now() + std::chrono::duration<double>(config_.drain_timeout_s);
  cv_.wait_until(lock, deadline, [&] { return active_workers_ == 0; });
  const int still_running = active_workers_;
  if (still_running > 0)
    spdlog::warn("event=drain_timeout running={} note=\"requeued at next start\"", still_running);
  lock.unlock();
  if (dispatcher_.joinable()) dispatcher_.join();
  if (executor_) executor_->shutdown(still_running == 0);
}

void Scheduler::dispatch() {
  std::unique_lock lock(mu_);
  while (!stopping_) {
    if (active_workers_ >= executor_->capacity()) {
      cv_.wait_for(lock, std::chrono::seconds(1));
      continue;
    }
    std::optional<JobRow> row;
    try {
      row = store_.claim_next();
    } catch (const std::exception& e) {
      spdlog::error("event=claim_failed error=\"{}\"", e.what());
    }
    if (!row) {
      cv_.wait_for(lock, std::chrono::seconds(1));
      continue;
    }
    auto ctl = std::make_shared<Control>();
    running_[row->id] = ctl;
    ++active_workers_;
    executor_->submit([this, job = std::move(*row), ctl] {
      run(job, *ctl);
      std::lock_guard done(mu_);
      running_.erase(job.id);
      --active_workers_;
      cv_.notify_all();
    });
  }
}

void Scheduler::check_steps(Job& job) const {
  check_time_step(job);
  if (!scene_built(job)) return;  // checked again once the scene is built (run's progress)
  const long steps = steps_needed(job);
  if (steps > config_.max_steps)
    throw std::invalid_argument("the job needs " + std::to_string(steps) +
                                " steps, above this daemon's limit max_steps = " +
                                std::to_string(config_.max_steps) + "; shorten it or raise dt");
}

void Scheduler::run(const JobRow& row, Control& ctl) {
  spdlog::info("event=job_start job={} user={} kind={} elements={} threads={} resume_step={}",
               row.id, row.user, row.kind, row.elements, row.threads, row.checkpoint_step);
  auto ch = writer_.open(row.id);
  const std::string ckpt = checkpoint_path(row.id);
  const auto t0 = Clock::now();
  double wall_before = row.wall_s;
  std::optional<JobRunner> runner;  // the shared build -> run -> classify -> report
  Job* job = nullptr;
  {
    std::lock_guard lock(ctl.usage_mu);
    ctl.usage = {wall_before, row.peak_bytes,
                 std::max(row.daemon_rss_peak_bytes, process_rss_peak_bytes())};
  }
  // At every poll: the running time so far and the memory peaks (the job's data once its scene
  // is built; a packing stage's own system is not counted).
  auto sample = [&] {
    std::lock_guard lock(ctl.usage_mu);
    ctl.usage.elapsed_s = wall_before + seconds_since(t0);
    if (job && scene_built(*job))
      ctl.usage.peak_bytes =
          std::max(ctl.usage.peak_bytes, static_cast<long>(job->system().memory_bytes()));
    ctl.usage.daemon_rss_peak_bytes =
        std::max(ctl.usage.daemon_rss_peak_bytes, process_rss_peak_bytes());
    return ctl.usage;
  };
  // Into the store, with the running time (before the state event that ends this run). Best
  // effort: a store that does not take writes (a full disk) must not keep the job from ending -
  // its end events wait for the disk below (flush_retrying); the usage figures are then lost.
  auto record_usage = [&] {
    const Usage u = sample();
    try {
      store_.set_usage(row.id, u.elapsed_s, u.peak_bytes, u.daemon_rss_peak_bytes);
    } catch (const SqliteError& e) {
      spdlog::warn("event=usage_not_recorded job={} error=\"{}\"", row.id, e.what());
    }
  };
  JobState state = v1::SUCCEEDED;
  std::string reason;
  try {
    job = &runner.emplace(row.spec, row.threads).job();
    // The store's checkpoint step counts over all stages (Job::overall_step), so a checkpoint
    // taken while a scene-building stage ran (a compression job's packing) counts too.
    const bool resume = row.checkpoint_step > 0;
    bool steps_checked = row.total_steps > 0 || resume;
    if (!steps_checked) {
      check_steps(*job);
      steps_checked = scene_built(*job);
    }
    if (resume) try {
        const CheckpointData data = read_checkpoint(ckpt);
        load_checkpoint(*job, data.state);
      } catch (const std::exception& e) {
        runner.reset();  // a fresh scene is no report of this job
        job = nullptr;
        throw CheckpointFileError(std::string("cannot resume: ") + e.what() +
                                  "; the events logged up to step " + std::to_string(row.step) +
                                  " are kept; submit the spec again to rerun the job");
      }
    if (!row.columns_logged) {
      v1::JobEvent e;
      for (const std::string& c : job->columns()) e.mutable_columns()->add_names(c);
      ch->push(std::move(e));
    }
    auto last_ckpt = Clock::now();
    auto save = [&](long step) {
      ch->flush();  // the log reaches at least `step` before the checkpoint claims it
      const double wall = wall_before + seconds_since(t0);
      if (auto injected = injected_write_failure())
        throw CheckpointFileError("checkpoint '" + ckpt + ".tmp': cannot write: " + *injected);
      write_checkpoint(ckpt, {step, save_checkpoint(*job), {}});
      // The store counts steps over all stages, as progress does: a checkpoint taken while a
      // scene-building stage runs (time-series step 0) still reads as one to resume from.
      store_.set_checkpoint(row.id, job->overall_step(), wall);
      last_ckpt = Clock::now();
      return job->overall_step();
    };
    JobObserver obs;
    obs.frame = [&](const SeriesFrame& f) {
      // Logged before the restart: frames are ordered by stage, then step (a job whose stages
      // restart their clock, as the tensile job does after its pre-relaxation, repeats steps).
      const int stage = static_cast<int>(job->stage_index());
      if (event_order(stage, f.step) <= row.last_frame_step) return;
      v1::JobEvent e;
      e.mutable_frame()->set_step(f.step);
      e.mutable_frame()->set_stage(stage);
      e.mutable_frame()->set_time_ps(f.time_ps);
      e.mutable_frame()->mutable_values()->Add(f.values.begin(), f.values.end());
      ch->push_droppable({std::move(e)}, f.step, false);
    };
    obs.snapshot = [&](const Snapshot& s) {
      const int stage = static_cast<int>(job->stage_index());
      if (event_order(stage, s.step) <= row.last_snapshot_step) return;
      ch->push_droppable(snapshot_events(s, stage), s.step, true);
    };
    obs.progress = [&](const JobProgress& p) {
      // A job whose scene a stage builds (a compression job's packing) knows its step count
      // once that stage is done: refused then, as invalid, when it needs more than max_steps.
      if (!steps_checked && scene_built(*job)) {
        steps_checked = true;
        check_steps(*job);
      }
      if (p.step <= row.last_progress_step) return;
      v1::JobEvent e;
      e.mutable_progress()->set_step(p.step);
      e.mutable_progress()->set_total_steps(p.total_steps);
      e.mutable_progress()->set_time_ps(p.time_ps);
      e.mutable_progress()->set_phase(p.phase);
      if (scene_built(*job))  // the real count replaces the estimate made at submit
        e.mutable_progress()->set_elements(static_cast<long>(job->system().elements().size()));
      ch->push_droppable({std::move(e)}, p.step, false);
    };
    obs.cancelled = [&] {
      const Usage u = sample();
      if (row.time_limit_s > 0 && u.elapsed_s >= row.time_limit_s) {
        int running = kRun;  // a cancel or drain that came first stays what stops the job
        ctl.stop.compare_exchange_strong(running, kTimeout);
      }
      return ctl.stop.load() != kRun;
    };
    obs.checkpoint = [&](long step) {
      if (seconds_since(last_ckpt) < config_.checkpoint_every_s) return;
      // A checkpoint that cannot be written, or whose log cannot be (a full disk): the job goes
      // on; a restart would resume from the previous checkpoint.
      auto skip = [&](const std::exception& e) {
        v1::JobEvent l;
        l.mutable_log()->set_level("warning");
        l.mutable_log()->set_text(std::string(e.what()) +
                                  "; the job continues, a restart resumes from the last good "
                                  "checkpoint");
        ch->push(std::move(l));
        spdlog::warn("event=checkpoint_failed job={} error=\"{}\"", row.id, e.what());
        last_ckpt = Clock::now();
      };
      try {
        save(step);
      } catch (const CheckpointFileError& e) {
        skip(e);
      } catch (const SqliteError& e) {
        skip(e);
      }
    };
    const JobOutcome r = runner->run(obs, [&](Job& j) {
      return ctl.reason + "; results up to step " + std::to_string(j.system().steps()) +
             " (t = " + std::to_string(j.system().time()) + " ps) are kept";
    });
    if (r.cancelled && ctl.stop == kTimeout) {
      const long step = save(job->system().steps());
      record_usage();
      ch->push(state_event(v1::TIMEOUT, timeout_reason(row, sample().elapsed_s, step)));
      ch->flush();
      writer_.close(row.id);
      spdlog::info("event=job_timeout job={} step={} limit_s={:.1f}", row.id, step,
                   row.time_limit_s);
      return;
    }
    if (r.cancelled && ctl.stop == kDrain) {
      const long step = save(job->system().steps());
      record_usage();
      ch->push(state_event(v1::QUEUED, "requeued: " + ctl.reason +
                                           "; resumes from the checkpoint at step " +
                                           std::to_string(step)));
      ch->flush();
      writer_.close(row.id);
      spdlog::info("event=job_requeued job={} step={}", row.id, step);
      return;
    }
    state = r.state;
    reason = r.reason;
  } catch (const NumericalError& e) {  // while resuming
    state = v1::FAILED;
    reason = e.what();
  } catch (const std::invalid_argument& e) {  // a scene built only here (ConfigError included)
    runner.reset();
    job = nullptr;
    state = v1::FAILED;
    reason = std::string("invalid job: ") + e.what();
  } catch (const CheckpointFileError& e) {
    state = v1::FAILED;
    reason = e.what();
  } catch (const SqliteError& e) {
    // The log cannot be written: leave the job RUNNING in the database; reconcile requeues it.
    spdlog::error("event=job_log_failed job={} error=\"{}\"", row.id, e.what());
    writer_.close(row.id);
    return;
  } catch (const std::exception& e) {
    state = v1::FAILED;
    reason = std::string("internal error: ") + e.what();
  }
  const double wall = wall_before + seconds_since(t0);
  try {
    const JobState s = state;
    record_usage();
    if (job) ch->push(report_event(job_report(*job, row.id, s, reason, wall).dump()));
    ch->push(state_event(s, reason));
    // Through a full disk: the end is logged once it takes writes (a drain gives up; the job,
    // still RUNNING in the database, is requeued at the next start).
    if (!ch->flush_retrying([&] { return ctl.stop.load() == kDrain; }))
      throw SqliteError("the daemon stopped before the disk took the job's last events");
    std::error_code ec;
    std::filesystem::remove(ckpt, ec);
    spdlog::info("event=job_end job={} state={} wall_s={:.3f} reason=\"{}\"", row.id,
                 job_state_name(s), wall, reason);
  } catch (const std::exception& e) {
    spdlog::error("event=job_log_failed job={} error=\"{}\"", row.id, e.what());
  }
  writer_.close(row.id);
}

}  // namespace mdem::server
