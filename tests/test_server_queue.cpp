// The daemon's queue as Slurm users read it: a queued job's place in the queue and what it waits
// for (every worker busy, the job ahead of it), through GetJob, ListJobs and `mdem show/ls`; and
// a queued job cancelled before it started is reported as having produced nothing.
#include <gtest/gtest.h>

#include <string>

#include "server_support.h"

namespace {

using namespace mdem::testing;
using mdem::v1::JobInfo;

void cancel(const DaemonProcess& d, const char* token, const std::string& id) {
  mdem::v1::CancelJobRequest req;
  req.set_job_id(id);
  JobInfo info;
  auto ctx = ctx_for(token);
  ASSERT_TRUE(d.stub()->CancelJob(ctx.get(), req, &info).ok());
}

TEST(ServerQueue, AQueuedJobSaysItsPlaceAndWhatItWaitsFor) {
  const fs::path dir = fresh_dir("queue");
  DaemonProcess d(dir);  // one worker
  const std::string running = submit_ok(d, kAliceToken, "a", small_spec(100000));
  wait_for(d, running, [](const JobInfo& j) { return j.state() == mdem::v1::RUNNING; });
  const std::string first = submit_ok(d, kAliceToken, "b", small_spec(5));
  const std::string second = submit_ok(d, kAliceToken, "c", small_spec(5));
  const std::string bobs = submit_ok(d, kBobToken, "d", small_spec(5));

  // Bob runs no job, so his goes first (fewest running jobs), then alice's in order.
  JobInfo info = get(d, kBobToken, bobs);
  EXPECT_EQ(info.queue_position(), 1);
  EXPECT_TRUE(contains(info.waiting_for(), "all 1 worker busy (running another user's job)"))
      << info.waiting_for();
  EXPECT_TRUE(contains(info.waiting_for(), "next to start")) << info.waiting_for();
  info = get(d, kAliceToken, second);
  EXPECT_EQ(info.queue_position(), 3);
  EXPECT_TRUE(contains(info.waiting_for(), "running " + running)) << info.waiting_for();
  EXPECT_TRUE(contains(info.waiting_for(), "behind " + first)) << info.waiting_for();
  info = get(d, kAliceToken, first);
  EXPECT_EQ(info.queue_position(), 2);
  EXPECT_TRUE(contains(info.waiting_for(), "behind another user's job")) << info.waiting_for();
  // An admin sees every job by its id; a running job has no place in the queue.
  EXPECT_TRUE(contains(get(d, kRootToken, first).waiting_for(), "behind " + bobs));
  EXPECT_EQ(get(d, kAliceToken, running).queue_position(), 0);
  EXPECT_EQ(get(d, kAliceToken, running).waiting_for(), "");

  // The CLI shows it: ls's last column, show's waiting line.
  const fs::path token = dir / "alice.token";
  write_private(token, std::string(kAliceToken) + "\n");
  const std::string conn = " --server " + d.address() + " --token-file " + token.string();
  CliResult r = mdem_cli(dir, "ls" + conn);
  EXPECT_EQ(r.code, 0) << slurp(dir / "cli.err");
  EXPECT_TRUE(contains(r.out, "#3 in queue: all 1 worker busy")) << r.out;
  r = mdem_cli(dir, "show " + second + conn);
  EXPECT_TRUE(contains(r.out, "position 3 in the queue; all 1 worker busy")) << r.out;

  // Cancelled while queued: nothing was produced, and the CLI does not claim otherwise.
  r = mdem_cli(dir, "cancel " + second + conn + " --db " + (dir / "r.db").string());
  EXPECT_EQ(r.code, 0) << slurp(dir / "cli.err");
  EXPECT_TRUE(contains(r.out, "before it started; it produced nothing")) << r.out;
  EXPECT_FALSE(contains(r.out, "kept")) << r.out;
  EXPECT_EQ(get(d, kAliceToken, first).queue_position(), 2);  // the queue closed up behind it

  for (const std::string& id : {first, running}) cancel(d, kAliceToken, id);
  cancel(d, kBobToken, bobs);
}

}  // namespace
