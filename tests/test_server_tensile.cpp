// The tensile job on mdemd: a tiny film given by numbers (16 tubes of 40 segments in 60 x 60 x
// 11 nm, 8 NPs deposited after the relaxation) runs through every stage (pre-relaxation,
// relaxation, deposit, NP pre-relaxation, tensile test), is killed -9 once it has checkpointed
// inside its test, resumes from the checkpoint, and ends with the frames, snapshots and report of
// an uninterrupted run, bit for bit; so does one killed in its relaxation. A spec out of range is
// refused at submit with the field and its range.
#include <gtest/gtest.h>

#include "server_support.h"

namespace {

using namespace mdem::testing;
using mdem::v1::JobEvent;
using mdem::v1::JobInfo;
using mdem::v1::JobSpec;

JobSpec tiny_film_spec() {
  JobSpec s;
  s.set_seed(3);
  s.mutable_run()->set_threads(1);
  s.mutable_outputs()->set_snapshot_every_ps(5);
  auto* t = s.mutable_tensile();
  t->set_side_nm(60);
  t->set_tubes(16);
  t->set_segments_per_tube(40);
  t->set_nanoparticles(8);
  t->set_prerelax_max_ps(5);
  t->set_relax_ps(20);
  t->set_grip_width_nm(10);
  t->set_target_strain_percent(1);
  t->set_strain_rate_per_ps(1e-3);
  t->set_ramp_ps(10);
  return s;
}

// The job's events of one kind in log order. The tensile job restarts its step count after the
// pre-relaxation (tensile.md §3.3), so steps repeat across stages: frames and snapshots are
// compared in order, not by step.
std::vector<std::pair<long, std::vector<double>>> frame_sequence(const std::vector<JobEvent>& ev) {
  std::vector<std::pair<long, std::vector<double>>> out;
  for (const JobEvent& e : of_kind(ev, JobEvent::kFrame))
    out.emplace_back(e.frame().step(),
                     std::vector<double>(e.frame().values().begin(), e.frame().values().end()));
  return out;
}
std::vector<std::pair<long, std::string>> snapshot_sequence(const std::vector<JobEvent>& ev) {
  std::vector<std::pair<long, std::string>> out;
  for (const JobEvent& e : of_kind(ev, JobEvent::kSnapshot))
    out.emplace_back(e.snapshot().step(), e.snapshot().data());
  return out;
}

// The overall step (progress counts over all stages) at which the reference entered a phase.
long phase_start_step(const std::vector<JobEvent>& ev, std::initializer_list<std::string> phases) {
  for (const JobEvent& e : of_kind(ev, JobEvent::kProgress))
    for (const std::string& p : phases)
      if (e.progress().phase() == p) return e.progress().step();
  return -1;
}

// Runs a reference, then a victim killed -9 by its first checkpoint taken 20 steps into the
// phase, and compares the resumed victim's log with the reference's.
void kill_in_phase_and_compare(const std::string& dir, std::initializer_list<std::string> phases) {
  DaemonProcess d(fresh_dir(dir), {"--checkpoint-every", "0.05"});
  const std::string ref = submit_ok(d, kAliceToken, "reference", tiny_film_spec());
  const JobInfo ref_info = wait_finished(d, ref, 300);
  ASSERT_EQ(ref_info.state(), mdem::v1::SUCCEEDED) << ref_info.reason();
  const auto ref_ev = watch(d, kAliceToken, ref, 1);
  const auto report = report_of(ref_ev);
  ASSERT_TRUE(report.contains("summary")) << report.dump();
  // The film as asked: 16 x 40 segments and the 8 NPs; the test reached its 1 % (it ends at
  // the first 1 ps sample at or past it: 1e-3 /ps x 1 ps above at most, plus rounding).
  EXPECT_EQ(report["summary"]["segments"], 640) << report.dump();
  EXPECT_EQ(report["summary"]["nanoparticles"], 8);
  const double final_strain = report["summary"]["final_strain"].get<double>();
  EXPECT_GE(final_strain, 0.01 - 1e-9);
  EXPECT_LE(final_strain, 0.01 + 1.1e-3);
  const long phase_start = phase_start_step(ref_ev, phases);
  ASSERT_GE(phase_start, 0) << "no progress in the phase";

  const std::string id = submit_ok(d, kAliceToken, "victim", tiny_film_spec());
  // 20 steps in, checkpoints every 0.05 s: at the step the job picks after the pre-relaxation
  // the test phase lasts a fraction of a second, and a checkpoint must come before it ends.
  wait_for(d, id, [&](const JobInfo& j) { return j.step() > phase_start + 20; });
  const fs::path ckpt = checkpoint_path(d, id);
  std::error_code ec;
  const auto stamp = fs::last_write_time(ckpt, ec);
  const JobInfo before = wait_for(d, id, [&](const JobInfo&) {
    std::error_code e2;
    return fs::last_write_time(ckpt, e2) != stamp;
  });
  ASSERT_FALSE(finished(before.state())) << "the victim ended before a checkpoint in the phase";
  d.kill9();
  d.start();
  const JobInfo after = wait_finished(d, id, 300);
  EXPECT_EQ(after.state(), mdem::v1::SUCCEEDED) << after.reason();
  EXPECT_GE(after.resumes(), 1) << "killed at progress step " << before.step();
  const auto ev = watch(d, kAliceToken, id, 1);
  expect_contiguous(ev);
  const auto f_ref = frame_sequence(ref_ev), f = frame_sequence(ev);
  ASSERT_EQ(f.size(), f_ref.size());
  for (std::size_t k = 0; k < f.size(); ++k) {
    EXPECT_EQ(f[k].first, f_ref[k].first) << "frame " << k;
    EXPECT_TRUE(same_bits(f[k].second, f_ref[k].second)) << "frame " << k << " differs";
  }
  const auto s_ref = snapshot_sequence(ref_ev), s = snapshot_sequence(ev);
  ASSERT_EQ(s.size(), s_ref.size());
  for (std::size_t k = 0; k < s.size(); ++k)
    EXPECT_TRUE(s[k] == s_ref[k]) << "snapshot event " << k << " differs";
  EXPECT_EQ(report_of(ev)["summary"], report["summary"]);
  EXPECT_EQ(report_of(ev)["accuracy"], report["accuracy"]);
}

TEST(ServerTensile, KillDashNineInTheTestResumesToIdenticalResults) {
  kill_in_phase_and_compare("kill9-tensile", {"ramp", "straining"});
}

// Killed in the relaxation: the stages after it restart the clock (the deposit), so their frames
// repeat the relaxation's steps and must still be logged after the resume.
TEST(ServerTensile, KillDashNineInTheRelaxationResumesToIdenticalResults) {
  kill_in_phase_and_compare("kill9-tensile-relax", {"relax"});
}

TEST(ServerTensile, SpecOutOfRangeIsRefusedAtSubmit) {
  DaemonProcess d(fresh_dir("tensile-invalid"));
  JobSpec s = tiny_film_spec();
  s.mutable_tensile()->set_target_strain_percent(400);
  const grpc::Status st = submit(d, kAliceToken, "bad", s).status;
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(st.error_message().find("tensile.target_strain_percent"), std::string::npos)
      << st.error_message();
  EXPECT_NE(st.error_message().find("<= 300 %"), std::string::npos) << st.error_message();
}

}  // namespace
