// A per-job wall-time limit as Slurm's --time (issue 16, service.md "States"): a job that reaches
// it stops at its next poll, writes a checkpoint and ends in TIMEOUT with a message giving the
// limit, the running time and how to continue; a daemon restart neither loses nor re-runs it;
// `mdem resume` queues it again and it ends with the results of a run that was never stopped,
// bit for bit. Also: the limit's refusals on the RPC and in mdemd's settings, the default and
// maximum limits, running time and memory peaks in GetJob and `mdem ls/show`, and times shown to
// the second everywhere.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <regex>
#include <string>

#include "server_support.h"

namespace {

using namespace mdem::testing;
using mdem::v1::JobInfo;

Submitted submit_limited(const DaemonProcess& d, const std::string& rid, const JobSpec& spec,
                         double time_limit_s) {
  mdem::v1::SubmitJobRequest req;
  req.set_request_id(rid);
  *req.mutable_spec() = spec;
  req.set_time_limit_s(time_limit_s);
  Submitted s;
  auto ctx = ctx_for(kAliceToken);
  s.status = d.stub()->SubmitJob(ctx.get(), req, &s.resp);
  return s;
}

grpc::Status resume(const DaemonProcess& d, const std::string& id, double time_limit_s,
                    JobInfo* info = nullptr) {
  mdem::v1::ResumeJobRequest req;
  req.set_job_id(id);
  req.set_time_limit_s(time_limit_s);
  JobInfo out;
  auto ctx = ctx_for(kAliceToken);
  const grpc::Status s = d.stub()->ResumeJob(ctx.get(), req, &out);
  if (info) *info = out;
  return s;
}

const std::regex kSecondStyle(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)");

TEST(ServerTimeout, LimitEndsInTimeoutKeepsTheCheckpointAndResumesToTheSameResult) {
  const fs::path dir = fresh_dir("timeout");
  // No cadence checkpoint during the test: the one on disk is the timeout's.
  DaemonProcess d(dir, {"--checkpoint-every", "1000"});
  const JobSpec spec = small_spec(300, 0, 0.5);
  const std::string ref = submit_ok(d, kAliceToken, "reference", spec);
  const JobInfo ref_info = wait_finished(d, ref, 300);
  ASSERT_EQ(ref_info.state(), mdem::v1::SUCCEEDED) << ref_info.reason();
  const auto ref_ev = watch(d, kAliceToken, ref, 1);
  const double ref_wall = ref_info.elapsed_s();
  ASSERT_GT(ref_wall, 0.2) << "the reference ran too fast to stop it half-way";
  std::printf("reference: %.3f s of running time, %ld steps\n", ref_wall,
              static_cast<long>(ref_info.step()));

  // A limit of a quarter of the uninterrupted run's running time (a margin for a loaded machine,
  // where the same run's time varies by tens of per cent).
  const double limit = ref_wall / 4;
  const Submitted s = submit_limited(d, "limited", spec, limit);
  ASSERT_TRUE(s.status.ok()) << s.status.error_message();
  const std::string id = s.resp.job().job_id();
  EXPECT_DOUBLE_EQ(s.resp.job().time_limit_s(), limit);
  const JobInfo out = wait_for(
      d, id, [](const JobInfo& j) { return finished(j.state()) || j.state() == mdem::v1::TIMEOUT; },
      300);
  std::printf("limited: %.3f s limit, stopped after %.3f s at step %ld\n", limit, out.elapsed_s(),
              static_cast<long>(out.step()));
  ASSERT_EQ(out.state(), mdem::v1::TIMEOUT) << out.reason();
  // Stopped at its next poll: past the limit, by well under the run's length.
  EXPECT_GE(out.elapsed_s(), limit);
  EXPECT_LT(out.elapsed_s(), limit + 0.5 * ref_wall);
  EXPECT_GT(out.step(), 0);
  EXPECT_LT(out.step(), ref_info.step());
  EXPECT_TRUE(contains(out.reason(), "wall-time limit 00:00:0")) << out.reason();
  EXPECT_TRUE(contains(out.reason(), "of running time")) << out.reason();
  EXPECT_TRUE(contains(out.reason(), "checkpoint kept")) << out.reason();
  EXPECT_TRUE(contains(out.reason(), "mdem resume " + id + " --time-limit")) << out.reason();
  EXPECT_TRUE(std::regex_match(out.finished_at(), kSecondStyle)) << out.finished_at();
  EXPECT_TRUE(fs::exists(checkpoint_path(d, id)));
  // Its data peak: at least the element arrays (339 bytes each, test_memory_bytes.cpp) and not
  // far above (neighbour lists, bonds, buffers: < 4 kB per element here).
  EXPECT_GE(out.job_data_peak_bytes(), 339 * out.elements());
  EXPECT_LE(out.job_data_peak_bytes(), 4000 * out.elements());
  EXPECT_GE(out.daemon_rss_peak_bytes(), out.job_data_peak_bytes());

  // Only a TIMEOUT job resumes; bad grants are refused naming the field.
  EXPECT_EQ(resume(d, ref, 0).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  for (const double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity(), 1e9}) {
    const grpc::Status st = resume(d, id, bad);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << bad;
    EXPECT_TRUE(contains(st.error_message(), "time_limit_s")) << st.error_message();
  }

  // A restart neither loses nor re-runs it.
  const long seq = out.last_seq();
  d.kill9();
  d.start();
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  JobInfo again = get(d, kAliceToken, id);
  EXPECT_EQ(again.state(), mdem::v1::TIMEOUT);
  EXPECT_EQ(again.last_seq(), seq);
  EXPECT_EQ(again.step(), out.step());
  EXPECT_TRUE(fs::exists(checkpoint_path(d, id)));

  // `mdem ls/show --server` show it with its limit, running time and memory.
  write_private(dir / "alice.token", std::string(kAliceToken) + "\n");
  const std::string conn =
      " --server " + d.address() + " --token-file " + (dir / "alice.token").string();
  CliResult r = mdem_cli(dir, "ls" + conn);
  EXPECT_EQ(r.code, 0) << slurp(dir / "cli.err");
  EXPECT_TRUE(contains(r.out, "LIMIT") && contains(r.out, "MEM")) << r.out;
  EXPECT_TRUE(contains(r.out, "TIMEOUT")) << r.out;
  r = mdem_cli(dir, "show " + id + conn);
  EXPECT_TRUE(contains(r.out, "time limit:  00:00:0")) << r.out;
  EXPECT_TRUE(contains(r.out, "job data peak ") && contains(r.out, "daemon RSS peak ")) << r.out;
  EXPECT_FALSE(std::regex_search(r.out, std::regex(R"(\d\d:\d\d:\d\d\.\d+Z)"))) << r.out;
  r = mdem_cli(dir, "show " + id + conn + " --json");
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_TRUE(std::regex_match(j["created_at"].get<std::string>(), kSecondStyle)) << r.out;
  EXPECT_EQ(j["state"], "TIMEOUT");
  EXPECT_GT(j["job_data_peak_bytes"].get<long>(), 0);

  // `mdem resume` with no limit (this daemon has no default): it runs to the end, and its frames
  // and summary equal those of the run that was never stopped, bit for bit.
  r = mdem_cli(dir, "resume " + id + conn + " --db " + (dir / "r.db").string() + " --watch --json");
  EXPECT_EQ(r.code, 0) << slurp(dir / "cli.err");
  const JobInfo done = wait_finished(d, id, 300);
  ASSERT_EQ(done.state(), mdem::v1::SUCCEEDED) << done.reason();
  EXPECT_EQ(done.time_limit_s(), 0);
  EXPECT_GE(done.elapsed_s(), out.elapsed_s());  // running time adds up across the resume
  const auto ev = watch(d, kAliceToken, id, 1);
  expect_contiguous(ev);
  bool resumed = false, timed_out = false;
  for (const auto& e : of_kind(ev, JobEvent::kState)) {
    timed_out = timed_out || e.state().state() == mdem::v1::TIMEOUT;
    resumed = resumed || contains(e.state().reason(), "resumed by alice from the checkpoint");
    EXPECT_TRUE(std::regex_match(e.time(), kSecondStyle)) << e.time();
  }
  EXPECT_TRUE(timed_out && resumed);
  expect_same_results(ev, ref_ev);
  EXPECT_EQ(report_of(ev)["performance"]["steps"], report_of(ref_ev)["performance"]["steps"]);
  EXPECT_FALSE(fs::exists(checkpoint_path(d, id)));  // removed once the job ended for good
}

TEST(ServerTimeout, RefusedLimitsAndTheDaemonsDefaultAndMaximum) {
  const fs::path dir = fresh_dir("timelimits");
  DaemonProcess d(dir, {"--default-time-limit", "10m", "--max-time-limit", "1h"});
  const JobSpec spec = small_spec(1);
  for (const double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity(),
                           -std::numeric_limits<double>::infinity(), 30 * 86400.0 + 1}) {
    const Submitted s = submit_limited(d, "bad", spec, bad);
    EXPECT_EQ(s.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << bad;
    EXPECT_TRUE(contains(s.status.error_message(), "time_limit_s")) << s.status.error_message();
  }
  Submitted s = submit_limited(d, "above", spec, 7200);
  EXPECT_EQ(s.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_TRUE(contains(s.status.error_message(), "max_time_limit = 01:00:00"))
      << s.status.error_message();
  auto list = [&] {
    mdem::v1::ListJobsRequest req;
    mdem::v1::ListJobsResponse resp;
    auto ctx = ctx_for(kAliceToken);
    EXPECT_TRUE(d.stub()->ListJobs(ctx.get(), req, &resp).ok());
    return resp;
  };
  EXPECT_EQ(list().jobs_size(), 0);  // nothing was queued
  s = submit_limited(d, "default", spec, 0);
  ASSERT_TRUE(s.status.ok()) << s.status.error_message();
  EXPECT_EQ(s.resp.job().time_limit_s(), 600);
  s = submit_limited(d, "own", spec, 1800);
  ASSERT_TRUE(s.status.ok()) << s.status.error_message();
  EXPECT_EQ(s.resp.job().time_limit_s(), 1800);
  EXPECT_EQ(wait_finished(d, s.resp.job().job_id()).state(), mdem::v1::SUCCEEDED);
  EXPECT_FALSE(resume(d, s.resp.job().job_id(), 0).ok());  // not in TIMEOUT

  // mdemd's settings: each bad value refused at start, naming the flag and the forms.
  for (const std::vector<std::string>& bad :
       {std::vector<std::string>{"--max-time-limit", "0"},
        {"--max-time-limit", "soon"},
        {"--default-time-limit", "-1h"},
        {"--default-time-limit", "40d"},
        {"--default-time-limit", "2h", "--max-time-limit", "1h"}}) {
    std::vector<std::string> args = {MDEMD_PATH, "--data-dir", (dir / "other").string(),
                                     "--token-file", (dir / "tokens").string()};
    args.insert(args.end(), bad.begin(), bad.end());
    const int code = DaemonProcess::run(args, dir / "bad.out", dir / "bad.err");
    EXPECT_EQ(code, 2) << bad[0] << " " << bad[1];
    const std::string msg = slurp(dir / "bad.err");
    EXPECT_TRUE(contains(msg, bad[0]) || contains(msg, bad.back())) << msg;
  }
}

}  // namespace
