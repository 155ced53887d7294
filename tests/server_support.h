#pragma once
// What the daemon's tests share beyond the process harness: a small twist job, waiting on a
// job's state, and reading its event log.
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <vector>

#include "daemon.h"
#include "grpc/health/v1/health.grpc.pb.h"

namespace mdem::testing {

using v1::JobEvent;
using v1::JobInfo;
using v1::JobSpec;
using v1::JobState;
using Clock = std::chrono::steady_clock;

// 7 tubes x 10 segments = 70 elements, seeded at 300 K so that every step changes the state.
inline JobSpec small_spec(double hold_ps, double snapshot_every_ps = 0,
                          double energy_every_ps = 1) {
  JobSpec s;
  s.set_name("test");
  s.set_seed(7);
  s.mutable_run()->set_threads(1);
  s.mutable_outputs()->set_energy_every_ps(energy_every_ps);
  s.mutable_outputs()->set_snapshot_every_ps(snapshot_every_ps);
  auto* t = s.mutable_twist();
  t->set_layers(2);
  t->set_length_nm(13.56);
  t->set_torque_nn_nm(2);
  t->set_torque_rate_nn_nm_per_ps(1);
  t->set_hold_ps(hold_ps);
  t->set_temperature_k(300);
  return s;
}

inline bool finished(JobState s) {
  return s == mdem::v1::SUCCEEDED || s == mdem::v1::FAILED || s == mdem::v1::CANCELLED;
}

// Polls until pred(job) or timeout; returns the last JobInfo.
template <class Pred>
JobInfo wait_for(const DaemonProcess& d, const std::string& id, Pred pred, double timeout_s = 120) {
  const auto end = Clock::now() + std::chrono::duration<double>(timeout_s);
  JobInfo info;
  while (Clock::now() < end) {
    info = get(d, kRootToken, id);
    if (pred(info)) return info;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ADD_FAILURE() << "timed out waiting on job " << id << " (state "
                << mdem::v1::JobState_Name(info.state()) << ", step " << info.step() << ")";
  return info;
}

inline JobInfo wait_finished(const DaemonProcess& d, const std::string& id,
                             double timeout_s = 120) {
  return wait_for(
      d, id, [](const JobInfo& j) { return finished(j.state()); }, timeout_s);
}

inline std::vector<JobEvent> of_kind(const std::vector<JobEvent>& ev, JobEvent::EventCase k) {
  std::vector<JobEvent> out;
  for (const JobEvent& e : ev)
    if (e.event_case() == k) out.push_back(e);
  return out;
}

inline void expect_contiguous(const std::vector<JobEvent>& ev, long first = 1) {
  for (std::size_t k = 0; k < ev.size(); ++k)
    ASSERT_EQ(ev[k].seq(), first + static_cast<long>(k)) << "gap or duplicate at index " << k;
}

// step -> frame values, failing on a step seen twice.
inline std::map<long, std::vector<double>> frames_by_step(const std::vector<JobEvent>& ev) {
  std::map<long, std::vector<double>> m;
  for (const JobEvent& e : of_kind(ev, JobEvent::kFrame)) {
    const auto& f = e.frame();
    EXPECT_FALSE(m.count(f.step())) << "frame at step " << f.step() << " twice";
    m[f.step()] = {f.values().begin(), f.values().end()};
  }
  return m;
}

inline fs::path checkpoint_path(const DaemonProcess& d, const std::string& id) {
  return d.data_dir() / "checkpoints" / (id + ".ckpt");
}

// Waits until job `id` has written its checkpoint file (a fixed sleep after some step would race
// a job that finishes sooner on a faster engine); the job's state then.
inline JobInfo wait_for_checkpoint(const DaemonProcess& d, const std::string& id) {
  const fs::path ckpt = checkpoint_path(d, id);
  return wait_for(d, id, [&](const JobInfo&) { return fs::exists(ckpt); });
}

// Waits until job `id` has a checkpoint the daemon has recorded. The daemon records a checkpoint
// in its database only after the file is in place, so a kill right after the file appears can
// find none recorded and restart the job from step 0 (CI runs failed so, twice): this waits for
// the file to be replaced once more, by which time the first one is recorded.
inline JobInfo wait_for_recorded_checkpoint(const DaemonProcess& d, const std::string& id) {
  wait_for_checkpoint(d, id);
  const fs::path file = checkpoint_path(d, id);
  std::error_code ec;
  const auto first = fs::last_write_time(file, ec);
  return wait_for(d, id, [&](const JobInfo&) {
    std::error_code e;
    const auto now = fs::last_write_time(file, e);
    return !e && now != first;
  });
}

// Lets job `id` (checkpointing every 0.2 s) run past step 2000 and checkpoint, then kill -9s the
// daemon; the job's checkpoint file (left in place).
inline fs::path kill_after_checkpoint(DaemonProcess& d, const std::string& id) {
  wait_for(d, id, [](const JobInfo& j) { return j.step() > 2000; });
  wait_for_recorded_checkpoint(d, id);
  d.kill9();
  const fs::path ckpt = checkpoint_path(d, id);
  EXPECT_TRUE(fs::exists(ckpt)) << ckpt;
  return ckpt;
}

// step -> the concatenated bytes of that snapshot.
inline std::map<long, std::string> snapshots_by_step(const std::vector<JobEvent>& ev) {
  std::map<long, std::string> m;
  for (const JobEvent& e : of_kind(ev, JobEvent::kSnapshot))
    m[e.snapshot().step()] += e.snapshot().data();
  return m;
}

inline nlohmann::json report_of(const std::vector<JobEvent>& ev) {
  const auto r = of_kind(ev, JobEvent::kReport);
  if (r.empty()) return {};
  return nlohmann::json::parse(r.back().report().json());
}

inline bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

// A resumed job's frames (every step, bit for bit), summary and accuracy equal its reference's.
inline void expect_same_results(const std::vector<JobEvent>& ev,
                                const std::vector<JobEvent>& ref_ev) {
  const auto f_ref = frames_by_step(ref_ev), f = frames_by_step(ev);
  ASSERT_EQ(f.size(), f_ref.size());
  for (const auto& [step, v] : f_ref) {
    ASSERT_TRUE(f.count(step)) << "frame at step " << step << " missing";
    EXPECT_TRUE(same_bits(v, f.at(step))) << "frame at step " << step << " differs";
  }
  const auto r_ref = report_of(ref_ev), r = report_of(ev);
  EXPECT_EQ(r["summary"], r_ref["summary"]);
  EXPECT_EQ(r["accuracy"], r_ref["accuracy"]);
}

// The daemon's grpc.health.v1 status (UNKNOWN when the call fails).
inline grpc::health::v1::HealthCheckResponse::ServingStatus health(const DaemonProcess& d) {
  auto stub = grpc::health::v1::Health::NewStub(d.channel());
  grpc::health::v1::HealthCheckRequest req;
  grpc::health::v1::HealthCheckResponse resp;
  auto ctx = ctx_for(nullptr, 5);
  if (!stub->Check(ctx.get(), req, &resp).ok())
    return grpc::health::v1::HealthCheckResponse::UNKNOWN;
  return resp.status();
}

}  // namespace mdem::testing
