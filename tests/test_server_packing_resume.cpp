// kill -9 while a compression job packs its particle (a stage of its own, at time-series step 0):
// the daemon resumes from the checkpoint taken during the packing, and the job ends with the
// frames and report of an uninterrupted run, bit for bit.
#include <gtest/gtest.h>

#include "server_support.h"

namespace {

using namespace mdem::testing;
using mdem::v1::JobEvent;
using mdem::v1::JobInfo;
using mdem::v1::JobSpec;

// An Au sphere of R = 14 nm (about 470 grains), crushed by 1 nm quickly. The whole job takes
// ~0.4 s on one thread (measured with the integrator in SIMD lanes), so the daemon checkpoints
// every 0.03 s: the kill must fall after a checkpoint taken while packing.
JobSpec packing_spec() {
  JobSpec s;
  s.set_seed(5);
  s.mutable_run()->set_threads(1);
  s.mutable_outputs()->set_snapshot_every_ps(0);
  auto* c = s.mutable_compression();
  c->set_outer_radius_nm(14);
  c->set_peak_displacement_nm(1);
  c->set_platen_speed_nm_per_ps(0.1);
  return s;
}

TEST(ServerPacking, KillDashNineWhilePackingResumesToIdenticalResults) {
  DaemonProcess d(fresh_dir("kill9-packing"), {"--checkpoint-every", "0.03"});
  const std::string ref = submit_ok(d, kAliceToken, "reference", packing_spec());
  const JobInfo ref_info = wait_finished(d, ref, 300);
  ASSERT_EQ(ref_info.state(), mdem::v1::SUCCEEDED) << ref_info.reason();
  const auto ref_ev = watch(d, kAliceToken, ref, 1);

  const std::string id = submit_ok(d, kAliceToken, "victim", packing_spec());
  // Killed as soon as a recorded checkpoint exists: still packing (no frame logged yet).
  const JobInfo before = wait_for_recorded_checkpoint(d, id);
  d.kill9();
  d.start();
  const JobInfo after = wait_finished(d, id, 300);
  EXPECT_EQ(after.state(), mdem::v1::SUCCEEDED) << after.reason();
  EXPECT_GE(after.resumes(), 1);
  const auto ev = watch(d, kAliceToken, id, 1);
  expect_contiguous(ev);
  // Resumed from a checkpoint before the compression's first frame was logged: while packing.
  long resumed_at = -1, first_frame = -1;
  for (std::size_t k = 0; k < ev.size(); ++k) {
    if (resumed_at < 0 && ev[k].has_state() &&
        ev[k].state().reason().find("resumed from the checkpoint at step") != std::string::npos)
      resumed_at = static_cast<long>(k);
    if (first_frame < 0 && ev[k].has_frame()) first_frame = static_cast<long>(k);
  }
  ASSERT_GE(resumed_at, 0) << "not resumed from a checkpoint (killed at progress step "
                           << before.step() << ")";
  EXPECT_LT(resumed_at, first_frame) << "the kill came after the packing";

  expect_same_results(ev, ref_ev);
}

}  // namespace
