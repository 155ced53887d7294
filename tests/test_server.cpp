// mdemd end to end: a real daemon process on port 0 in a temp directory, driven through its gRPC
// API. Submit -> watch -> succeeded; idempotent submit; invalid specs refused with nothing
// queued; access by token; cancel within a second; watch resume without gaps or duplicates; a
// stalled watcher; kill -9 and SIGTERM mid-run resuming to bit-identical results; a corrupt
// checkpoint and an unusable data directory failing clearly; fairness and per-user limits.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <atomic>
#include <cstring>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "grpc/health/v1/health.grpc.pb.h"
#include "server_support.h"

namespace {

using namespace mdem::testing;
using mdem::v1::JobEvent;
using mdem::v1::JobInfo;
using mdem::v1::JobSpec;
using mdem::v1::JobState;
using Clock = std::chrono::steady_clock;

TEST(Server, SubmitWatchSucceedsWithResults) {
  DaemonProcess d(fresh_dir("basic"));
  const std::string id = submit_ok(d, kAliceToken, "r1", small_spec(20, 5));
  grpc::Status st;
  const auto ev = watch(d, kAliceToken, id, 1, -1, &st);
  ASSERT_TRUE(st.ok()) << st.error_message();
  expect_contiguous(ev);
  const auto states = of_kind(ev, JobEvent::kState);
  ASSERT_GE(states.size(), 3u);
  EXPECT_EQ(states.front().state().state(), mdem::v1::QUEUED);
  EXPECT_EQ(states[1].state().state(), mdem::v1::RUNNING);
  EXPECT_EQ(states.back().state().state(), mdem::v1::SUCCEEDED);
  const auto cols = of_kind(ev, JobEvent::kColumns);
  ASSERT_EQ(cols.size(), 1u);
  const auto frames = frames_by_step(ev);
  // 22 ps at 1 ps per frame, plus step 0.
  EXPECT_GE(frames.size(), 23u);
  for (const auto& [step, v] : frames)
    EXPECT_EQ(v.size(), static_cast<size_t>(cols[0].columns().names_size()));
  EXPECT_GE(snapshots_by_step(ev).size(), 5u);
  const auto rep = report_of(ev);
  EXPECT_EQ(rep["state"], "SUCCEEDED");
  EXPECT_EQ(rep["job_id"], id);
  EXPECT_TRUE(rep["summary"].contains("morphology"));
  EXPECT_LT(rep["accuracy"]["energy_balance_error"].get<double>(), 0.01);
  const JobInfo info = get(d, kAliceToken, id);
  EXPECT_EQ(info.state(), mdem::v1::SUCCEEDED);
  EXPECT_EQ(info.last_seq(), ev.back().seq());
  EXPECT_EQ(info.elements(), 70);
  EXPECT_EQ(info.user(), "alice");
  // The checkpoint of a finished job is removed.
  EXPECT_FALSE(fs::exists(d.data_dir() / "checkpoints" / (id + ".ckpt")));
}

TEST(Server, HealthServing) {
  DaemonProcess d(fresh_dir("health"));
  auto stub = grpc::health::v1::Health::NewStub(d.channel());
  grpc::health::v1::HealthCheckRequest req;
  grpc::health::v1::HealthCheckResponse resp;
  auto ctx = ctx_for(nullptr);
  ASSERT_TRUE(stub->Check(ctx.get(), req, &resp).ok());
  EXPECT_EQ(resp.status(), grpc::health::v1::HealthCheckResponse::SERVING);
}

TEST(Server, SubmitIsIdempotentPerRequestId) {
  DaemonProcess d(fresh_dir("idem"));
  const Submitted a = submit(d, kAliceToken, "same-id", small_spec(5));
  const Submitted b = submit(d, kAliceToken, "same-id", small_spec(5));
  ASSERT_TRUE(a.status.ok() && b.status.ok());
  EXPECT_TRUE(a.resp.created());
  EXPECT_FALSE(b.resp.created());
  EXPECT_EQ(a.resp.job().job_id(), b.resp.job().job_id());
  // Another user's identical request id is their own job.
  const Submitted c = submit(d, kBobToken, "same-id", small_spec(5));
  ASSERT_TRUE(c.status.ok());
  EXPECT_NE(c.resp.job().job_id(), a.resp.job().job_id());
  mdem::v1::ListJobsRequest lreq;
  mdem::v1::ListJobsResponse lresp;
  auto ctx = ctx_for(kAliceToken);
  ASSERT_TRUE(d.stub()->ListJobs(ctx.get(), lreq, &lresp).ok());
  EXPECT_EQ(lresp.jobs_size(), 1);
}

TEST(Server, InvalidSpecIsRefusedAndNothingQueued) {
  DaemonProcess d(fresh_dir("invalid"));
  JobSpec bad = small_spec(5);
  bad.mutable_twist()->set_layers(99);
  bad.mutable_twist()->set_torque_nn_nm(std::numeric_limits<double>::quiet_NaN());
  Submitted s = submit(d, kAliceToken, "bad1", bad);
  EXPECT_EQ(s.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.status.error_message().find("twist.layers"), std::string::npos)
      << s.status.error_message();
  EXPECT_NE(s.status.error_message().find("twist.torque_nn_nm"), std::string::npos);
  // A time step above the engine's safe limit.
  JobSpec big_dt = small_spec(5);
  big_dt.mutable_run()->set_dt_ps(0.5);
  s = submit(d, kAliceToken, "bad2", big_dt);
  EXPECT_EQ(s.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.status.error_message().find("dt"), std::string::npos) << s.status.error_message();
  // No kind at all, a bad request id, a missing request id.
  s = submit(d, kAliceToken, "bad3", JobSpec());
  EXPECT_EQ(s.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  s = submit(d, kAliceToken, "white space", small_spec(5));
  EXPECT_EQ(s.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.status.error_message().find("request_id"), std::string::npos);
  s = submit(d, kAliceToken, "", small_spec(5));
  EXPECT_EQ(s.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  s = submit(d, kAliceToken, std::string(10000, 'x'), small_spec(5));
  EXPECT_EQ(s.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  mdem::v1::ListJobsRequest lreq;
  lreq.set_all_users(true);
  mdem::v1::ListJobsResponse lresp;
  auto ctx = ctx_for(kRootToken);
  ASSERT_TRUE(d.stub()->ListJobs(ctx.get(), lreq, &lresp).ok());
  EXPECT_EQ(lresp.jobs_size(), 0);
}

TEST(Server, TokensAndIsolation) {
  DaemonProcess d(fresh_dir("auth"));
  EXPECT_EQ(submit(d, nullptr, "a", small_spec(5)).status.error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(submit(d, "not-a-known-token-at-all", "a", small_spec(5)).status.error_code(),
            grpc::StatusCode::UNAUTHENTICATED);
  const std::string id = submit_ok(d, kAliceToken, "a", small_spec(5));
  grpc::Status st;
  get(d, kBobToken, id, &st);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  get(d, kRootToken, id, &st);
  EXPECT_TRUE(st.ok());
  get(d, kAliceToken, "j-does-not-exist", &st);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::NOT_FOUND);
  {
    mdem::v1::CancelJobRequest req;
    req.set_job_id(id);
    JobInfo info;
    auto ctx = ctx_for(kBobToken);
    EXPECT_EQ(d.stub()->CancelJob(ctx.get(), req, &info).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
  }
  watch(d, kBobToken, id, 1, -1, &st);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  {
    mdem::v1::ListJobsRequest req;
    mdem::v1::ListJobsResponse resp;
    auto ctx = ctx_for(kBobToken);
    ASSERT_TRUE(d.stub()->ListJobs(ctx.get(), req, &resp).ok());
    EXPECT_EQ(resp.jobs_size(), 0);
    req.set_all_users(true);
    auto ctx2 = ctx_for(kBobToken);
    EXPECT_EQ(d.stub()->ListJobs(ctx2.get(), req, &resp).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
    auto ctx3 = ctx_for(kRootToken);
    ASSERT_TRUE(d.stub()->ListJobs(ctx3.get(), req, &resp).ok());
    EXPECT_EQ(resp.jobs_size(), 1);
  }
  wait_finished(d, id);
}

TEST(Server, CancelStopsWithinASecondAndKeepsResults) {
  DaemonProcess d(fresh_dir("cancel"));
  const std::string id = submit_ok(d, kAliceToken, "long", small_spec(100000));
  wait_for(d, id, [](const JobInfo& j) { return j.step() > 200; });
  mdem::v1::CancelJobRequest req;
  req.set_job_id(id);
  JobInfo info;
  auto ctx = ctx_for(kAliceToken);
  const auto t0 = Clock::now();
  ASSERT_TRUE(d.stub()->CancelJob(ctx.get(), req, &info).ok());
  const double took = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_EQ(info.state(), mdem::v1::CANCELLED) << "not stopped " << took << " s after cancel";
  EXPECT_LT(took, 1.0);
  const auto ev = watch(d, kAliceToken, id, 1);
  expect_contiguous(ev);
  EXPECT_GE(frames_by_step(ev).size(), 2u);
  const auto rep = report_of(ev);
  EXPECT_EQ(rep["state"], "CANCELLED");
  EXPECT_GT(rep["performance"]["steps"].get<long>(), 200);
  // Cancelling a finished job changes nothing.
  auto ctx2 = ctx_for(kAliceToken);
  ASSERT_TRUE(d.stub()->CancelJob(ctx2.get(), req, &info).ok());
  EXPECT_EQ(info.state(), mdem::v1::CANCELLED);
  // A queued job is cancelled at once.
  const std::string busy = submit_ok(d, kAliceToken, "busy", small_spec(100000));
  const std::string queued = submit_ok(d, kAliceToken, "queued", small_spec(5));
  req.set_job_id(queued);
  auto ctx3 = ctx_for(kAliceToken);
  ASSERT_TRUE(d.stub()->CancelJob(ctx3.get(), req, &info).ok());
  EXPECT_EQ(info.state(), mdem::v1::CANCELLED);
  req.set_job_id(busy);
  auto ctx4 = ctx_for(kAliceToken);
  ASSERT_TRUE(d.stub()->CancelJob(ctx4.get(), req, &info).ok());
}

TEST(Server, ClosingAWatchNeverCancelsTheJob) {
  DaemonProcess d(fresh_dir("close-watch"));
  const std::string id = submit_ok(d, kAliceToken, "w", small_spec(30));
  const auto first = watch(d, kAliceToken, id, 1, 3);  // reads 3 events, then hangs up
  EXPECT_EQ(first.size(), 3u);
  EXPECT_EQ(wait_finished(d, id).state(), mdem::v1::SUCCEEDED);
}

TEST(Server, WatchResumesWithoutGapsOrDuplicates) {
  DaemonProcess d(fresh_dir("resume-watch"));
  const std::string id = submit_ok(d, kAliceToken, "w", small_spec(40, 10));
  std::vector<JobEvent> pieces;
  long next = 1;
  // Reconnect every few events while the job runs, then read to the end.
  for (int round = 0; round < 6; ++round) {
    const auto part = watch(d, kAliceToken, id, next, 7);
    pieces.insert(pieces.end(), part.begin(), part.end());
    if (!part.empty()) next = part.back().seq() + 1;
  }
  const auto rest = watch(d, kAliceToken, id, next);
  pieces.insert(pieces.end(), rest.begin(), rest.end());
  expect_contiguous(pieces);
  const auto whole = watch(d, kAliceToken, id, 1);
  ASSERT_EQ(whole.size(), pieces.size());
  for (std::size_t k = 0; k < whole.size(); ++k)
    EXPECT_EQ(whole[k].SerializeAsString(), pieces[k].SerializeAsString()) << "event " << k;
  EXPECT_EQ(of_kind(whole, JobEvent::kState).back().state().state(), mdem::v1::SUCCEEDED);
  // Past the end: refused; at the end: an immediately finished stream.
  grpc::Status st;
  watch(d, kAliceToken, id, whole.back().seq() + 5, -1, &st);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::OUT_OF_RANGE);
  EXPECT_TRUE(watch(d, kAliceToken, id, whole.back().seq() + 1, -1, &st).empty());
  EXPECT_TRUE(st.ok());
  watch(d, kAliceToken, id, -3, -1, &st);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::OUT_OF_RANGE);
}

TEST(Server, StalledWatcherSlowsNothingAndMemoryStaysBounded) {
  DaemonProcess d(fresh_dir("stalled"));
  // A snapshot every 0.02 ps (about every step): ~50 MB of events.
  const JobSpec spec = small_spec(200, 0.02, 0.02);
  const std::string ref = submit_ok(d, kAliceToken, "ref", spec);
  const JobInfo ref_done = wait_finished(d, ref, 300);
  const double ref_wall =
      nlohmann::json::parse(ref_done.report_json())["performance"]["wall_s"].get<double>();
  const long rss0 = d.rss_kb();

  const std::string id = submit_ok(d, kAliceToken, "stalled", spec);
  // The stalled watcher: opens the stream and never reads.
  mdem::v1::WatchJobRequest req;
  req.set_job_id(id);
  req.set_from_seq(1);
  auto ctx = ctx_for(kAliceToken, 600);
  auto stub = d.stub();
  auto reader = stub->WatchJob(ctx.get(), req);
  long rss_max = 0;
  JobInfo done = wait_for(
      d, id,
      [&](const JobInfo& j) {
        rss_max = std::max(rss_max, d.rss_kb());
        return finished(j.state());
      },
      300);
  EXPECT_EQ(done.state(), mdem::v1::SUCCEEDED);
  const double wall =
      nlohmann::json::parse(done.report_json())["performance"]["wall_s"].get<double>();
  long bytes = 0;
  for (const auto& e : watch(d, kAliceToken, id, 1)) bytes += e.ByteSizeLong();
  std::cout << "stalled watcher: job wall " << wall << " s (alone " << ref_wall << " s), events "
            << bytes / 1e6 << " MB, daemon RSS " << rss0 / 1024 << " -> max " << rss_max / 1024
            << " MB\n";
  EXPECT_GT(bytes, 30'000'000);
  // The daemon did not hold the stream's backlog in memory.
  EXPECT_LT((rss_max - rss0) * 1024, bytes / 2);
  ctx->TryCancel();
  reader->Finish();
}

// kill -9 mid-run, restart: the job resumes from its checkpoint and its frames, snapshots and
// report equal those of an uninterrupted run, bit for bit.
TEST(Server, KillDashNineResumesToIdenticalResults) {
  DaemonProcess d(fresh_dir("kill9"), {"--checkpoint-every", "0.2"});
  const JobSpec spec = small_spec(600, 10, 0.5);
  const std::string ref = submit_ok(d, kAliceToken, "reference", spec);
  wait_finished(d, ref, 300);
  const auto ref_ev = watch(d, kAliceToken, ref, 1);

  const std::string id = submit_ok(d, kAliceToken, "victim", spec);
  const JobInfo before = wait_for(d, id, [](const JobInfo& j) { return j.step() > 3000; });
  wait_for_recorded_checkpoint(d, id);
  d.kill9();
  d.start();
  const JobInfo after = wait_finished(d, id, 300);
  EXPECT_EQ(after.state(), mdem::v1::SUCCEEDED) << after.reason();
  EXPECT_GE(after.resumes(), 1);
  const auto ev = watch(d, kAliceToken, id, 1);
  expect_contiguous(ev);
  bool resumed = false;
  for (const auto& e : of_kind(ev, JobEvent::kState))
    resumed = resumed ||
              e.state().reason().find("resumed from the checkpoint at step") != std::string::npos;
  EXPECT_TRUE(resumed) << "no resume from a checkpoint (killed at step " << before.step() << ")";

  expect_same_results(ev, ref_ev);
  EXPECT_EQ(snapshots_by_step(ev), snapshots_by_step(ref_ev));
  EXPECT_EQ(report_of(ev)["performance"]["steps"], report_of(ref_ev)["performance"]["steps"]);
}

// SIGTERM drains: the running job checkpoints and is requeued, the daemon exits 0, and after a
// restart the job completes with the uninterrupted run's results.
TEST(Server, SigtermRequeuesRunningJobsFromTheirCheckpoint) {
  DaemonProcess d(fresh_dir("sigterm"), {"--checkpoint-every", "1000"});
  const JobSpec spec = small_spec(150, 0, 0.5);
  const std::string ref = submit_ok(d, kAliceToken, "reference", spec);
  wait_finished(d, ref, 300);
  const auto ref_ev = watch(d, kAliceToken, ref, 1);
  const std::string id = submit_ok(d, kAliceToken, "drained", spec);
  wait_for(d, id, [](const JobInfo& j) { return j.step() > 2000; });
  EXPECT_EQ(d.terminate(), 0) << d.log();
  d.start();
  const JobInfo after = wait_finished(d, id, 300);
  EXPECT_EQ(after.state(), mdem::v1::SUCCEEDED);
  const auto ev = watch(d, kAliceToken, id, 1);
  expect_contiguous(ev);
  bool requeued = false;
  for (const auto& e : of_kind(ev, JobEvent::kState))
    requeued = requeued || (e.state().state() == mdem::v1::QUEUED &&
                            e.state().reason().find("daemon is stopping") != std::string::npos);
  EXPECT_TRUE(requeued);
  const auto f_ref = frames_by_step(ref_ev), f = frames_by_step(ev);
  ASSERT_EQ(f.size(), f_ref.size());
  for (const auto& [step, v] : f_ref) EXPECT_TRUE(same_bits(v, f.at(step))) << "step " << step;
  EXPECT_EQ(report_of(ev)["summary"], report_of(ref_ev)["summary"]);
}

TEST(Server, CorruptCheckpointFailsThatJobOnly) {
  DaemonProcess d(fresh_dir("corrupt"), {"--checkpoint-every", "0.2"});
  const std::string id = submit_ok(d, kAliceToken, "victim", small_spec(800));
  const std::string other = submit_ok(d, kBobToken, "other", small_spec(10));
  const fs::path ckpt = kill_after_checkpoint(d, id);
  ASSERT_TRUE(fs::exists(ckpt));
  {
    std::fstream f(ckpt, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(200);
    f.write("garbage!", 8);
  }
  d.start();
  const JobInfo failed = wait_finished(d, id);
  EXPECT_EQ(failed.state(), mdem::v1::FAILED);
  EXPECT_NE(failed.reason().find("CRC"), std::string::npos) << failed.reason();
  EXPECT_NE(failed.reason().find(ckpt.string()), std::string::npos) << failed.reason();
  // What it logged before is kept.
  EXPECT_GE(frames_by_step(watch(d, kAliceToken, id, 1)).size(), 10u);
  EXPECT_EQ(wait_finished(d, other).state(), mdem::v1::SUCCEEDED);
}

TEST(Server, UnusableDataDirectoryOrTokenFileRefusesToStart) {
  const fs::path dir = fresh_dir("baddata");
  write_private(dir / "tokens", std::string(kAliceToken) + " alice\n");
  std::ofstream(dir / "a-file") << "x";
  auto start = [&](std::vector<std::string> args) {
    args.insert(args.begin(), MDEMD_PATH);
    const int pid = DaemonProcess::spawn(args, dir / "log");
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  auto log = [&] {
    std::ifstream in(dir / "log");
    std::stringstream ss;
    ss << in.rdbuf();
    fs::remove(dir / "log");
    return ss.str();
  };
  EXPECT_EQ(start({"--listen", "127.0.0.1:0", "--data-dir", (dir / "a-file" / "data").string(),
                   "--token-file", (dir / "tokens").string()}),
            1);
  EXPECT_NE(log().find("data directory"), std::string::npos);
  EXPECT_EQ(start({"--listen", "127.0.0.1:0", "--data-dir", (dir / "d").string(), "--token-file",
                   (dir / "missing-tokens").string()}),
            2);
  EXPECT_NE(log().find("token file"), std::string::npos);
  write_private(dir / "bad-tokens", "short bob\n");
  EXPECT_EQ(start({"--listen", "127.0.0.1:0", "--data-dir", (dir / "d").string(), "--token-file",
                   (dir / "bad-tokens").string()}),
            2);
  EXPECT_NE(log().find("line 1"), std::string::npos);
  EXPECT_EQ(start({"--data-dir", (dir / "d").string()}), 2);
  EXPECT_NE(log().find("--token-file"), std::string::npos);
  // A token file others may read (or the group write) is refused, naming the file, its mode and
  // the fix (a private one is accepted: every DaemonProcess starts with one, see daemon.h).
  for (const auto mode : {fs::perms::others_read, fs::perms::group_read, fs::perms::group_write}) {
    write_private(dir / "open-tokens", std::string(kAliceToken) + " alice\n");
    fs::permissions(dir / "open-tokens", mode, fs::perm_options::add);
    EXPECT_EQ(start({"--listen", "127.0.0.1:0", "--data-dir", (dir / "d").string(), "--token-file",
                     (dir / "open-tokens").string()}),
              2);
    const std::string text = log();
    EXPECT_NE(text.find((dir / "open-tokens").string()), std::string::npos) << text;
    EXPECT_NE(text.find("chmod 600"), std::string::npos) << text;
    const char* expected = mode == fs::perms::others_read  ? "mode 0604"
                           : mode == fs::perms::group_read ? "mode 0640"
                                                           : "mode 0620";
    EXPECT_NE(text.find(expected), std::string::npos) << text;
  }
  EXPECT_EQ(start({"--data-dir", (dir / "d").string()}), 2);
  EXPECT_NE(log().find("--token-file"), std::string::npos);
  EXPECT_EQ(start({"--data-dir", (dir / "d").string(), "--token-file", (dir / "tokens").string(),
                   "--workers", "0"}),
            2);
  EXPECT_NE(log().find("--workers"), std::string::npos);
  EXPECT_EQ(start({"--data-dir", (dir / "d").string(), "--token-file", (dir / "tokens").string(),
                   "--checkpoint-every", "nan"}),
            2);
  EXPECT_NE(log().find("--checkpoint-every"), std::string::npos);
  std::ofstream(dir / "cfg.yaml") << "workers: 2\nbogus_key: 1\n";
  EXPECT_EQ(start({"--config", (dir / "cfg.yaml").string()}), 2);
  EXPECT_NE(log().find("bogus_key"), std::string::npos);
}

TEST(Server, FairOrderBetweenUsersAndPerUserLimits) {
  DaemonProcess d(fresh_dir("fair"),
                  {"--workers", "1", "--max-queued-per-user", "3", "--max-elements", "5000"});
  const std::string a1 = submit_ok(d, kAliceToken, "a1", small_spec(15));
  const std::string a2 = submit_ok(d, kAliceToken, "a2", small_spec(5));
  const std::string a3 = submit_ok(d, kAliceToken, "a3", small_spec(5));
  const Submitted a4 = submit(d, kAliceToken, "a4", small_spec(5));
  EXPECT_EQ(a4.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(a4.status.error_message().find("max_queued_per_user"), std::string::npos);
  const std::string b1 = submit_ok(d, kBobToken, "b1", small_spec(5));
  JobSpec huge = small_spec(5);
  huge.mutable_twist()->set_layers(6);
  huge.mutable_twist()->set_length_nm(200);
  const Submitted b2 = submit(d, kBobToken, "b2", huge);
  EXPECT_EQ(b2.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_NE(b2.status.error_message().find("max_elements"), std::string::npos);
  for (const auto& id : {a1, a2, a3, b1}) wait_finished(d, id, 300);
  // Bob's job, submitted after alice's three, ran second: alice had just had her turn. The order
  // is read from the daemon's store, which keeps start times to the millisecond (JobInfo shows
  // them to the second, and these small jobs start within one).
  std::vector<std::pair<std::string, std::string>> started;
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(
        sqlite3_open_v2((d.data_dir() / "jobs.db").c_str(), &db, SQLITE_OPEN_READONLY, nullptr),
        SQLITE_OK);
    sqlite3_stmt* q = nullptr;
    ASSERT_EQ(sqlite3_prepare_v2(db, "SELECT started_at, id FROM jobs", -1, &q, nullptr),
              SQLITE_OK);
    while (sqlite3_step(q) == SQLITE_ROW)
      started.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(q, 0)),
                           reinterpret_cast<const char*>(sqlite3_column_text(q, 1)));
    sqlite3_finalize(q);
    sqlite3_close(db);
  }
  ASSERT_EQ(started.size(), 4u);
  for (const auto& [t, id] : started) EXPECT_NE(t.find('.'), std::string::npos) << t;  // ms kept
  std::sort(started.begin(), started.end());
  EXPECT_EQ(started[0].second, a1);
  EXPECT_EQ(started[1].second, b1);
}

}  // namespace

namespace {

// --tls-cert/--tls-key: a TLS client that trusts the certificate is served; a plaintext client
// is not.
TEST(Server, ServesTlsWhenGivenACertificate) {
  const fs::path dir = fresh_dir("tls");
  const std::string cmd =
      "openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=localhost "
      "-addext subjectAltName=DNS:localhost,IP:127.0.0.1 -keyout " +
      (dir / "key.pem").string() + " -out " + (dir / "cert.pem").string() + " >/dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << "openssl could not make a test certificate";
  DaemonProcess d(
      dir, {"--tls-cert", (dir / "cert.pem").string(), "--tls-key", (dir / "key.pem").string()});
  grpc::SslCredentialsOptions ssl;
  ssl.pem_root_certs = slurp(dir / "cert.pem");
  auto tls = grpc::CreateChannel(d.address(), grpc::SslCredentials(ssl));
  auto stub = mdem::v1::JobService::NewStub(tls);
  mdem::v1::ListJobsRequest req;
  mdem::v1::ListJobsResponse resp;
  auto ctx = ctx_for(kAliceToken, 10);
  const grpc::Status ok = stub->ListJobs(ctx.get(), req, &resp);
  EXPECT_TRUE(ok.ok()) << ok.error_message();
  auto plain = mdem::v1::JobService::NewStub(d.channel());  // insecure
  auto ctx2 = ctx_for(kAliceToken, 3);
  EXPECT_FALSE(plain->ListJobs(ctx2.get(), req, &resp).ok());
}

}  // namespace

namespace {

// `mdem submit --watch` stores the daemon's results in the local database, where `mdem export`
// reads them exactly as those of `mdem run`: the same job gives the same CSV, bit for bit.
TEST(Server, CliSubmitWatchExportsLikeAnEmbeddedRun) {
  const fs::path dir = fresh_dir("cli");
  DaemonProcess d(dir);
  const std::string job =
      "twist --layers 2 --length 13.56 --torque 2 --hold 10 --threads 1 "
      "--temperature 300 --snapshot-every 5 ";
  const std::string db = " --db " + (dir / "results.db").string();
  const CliResult sub = mdem_submit_watch(d, dir, job + db);
  ASSERT_EQ(sub.code, 0) << sub.out << slurp(dir / "cli.err");
  const std::string remote_id = nlohmann::json::parse(sub.out)["job_id"];
  const CliResult run = mdem_cli(dir, "run " + job + db + " --json");
  ASSERT_EQ(run.code, 0) << slurp(dir / "cli.err");
  const std::string local_id = nlohmann::json::parse(run.out)["job_id"];
  for (const auto& [id, name] : {std::pair{remote_id, "remote"}, std::pair{local_id, "local"}}) {
    ASSERT_EQ(mdem_cli(dir, "export " + id + " --format csv --out " +
                                (dir / (std::string(name) + ".csv")).string() + db)
                  .code,
              0)
        << slurp(dir / "cli.err");
    ASSERT_EQ(mdem_cli(dir, "export " + id + " --format xyz --out " +
                                (dir / (std::string(name) + ".xyz")).string() + db)
                  .code,
              0);
  }
  const std::string csv = slurp(dir / "remote.csv");
  EXPECT_GT(std::count(csv.begin(), csv.end(), '\n'), 10);
  EXPECT_EQ(csv, slurp(dir / "local.csv"));
  EXPECT_EQ(slurp(dir / "remote.xyz"), slurp(dir / "local.xyz"));
  // The local record knows it came from the daemon and finished.
  const CliResult show = mdem_cli(dir, "show " + remote_id + db + " --json");
  ASSERT_EQ(show.code, 0);
  EXPECT_EQ(nlohmann::json::parse(show.out)["state"], "SUCCEEDED");
}

}  // namespace

namespace {

// Wrong, missing and huge values on the other RPCs.
TEST(Server, RpcInputsAreCheckedWithClearStatuses) {
  DaemonProcess d(fresh_dir("inputs"));
  grpc::Status st;
  get(d, kAliceToken, "", &st);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(st.error_message().find("job_id"), std::string::npos);
  get(d, kAliceToken, std::string(100000, 'j'), &st);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(st.error_message().find("at most 128"), std::string::npos) << st.error_message();
  get(d, kAliceToken, "no-such-job", &st);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::NOT_FOUND);
  {
    mdem::v1::CancelJobRequest req;  // no job id
    JobInfo info;
    auto ctx = ctx_for(kAliceToken);
    EXPECT_EQ(d.stub()->CancelJob(ctx.get(), req, &info).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT);
  }
  for (int limit : {-1, 1001, std::numeric_limits<int>::max()}) {
    mdem::v1::ListJobsRequest req;
    req.set_limit(limit);
    mdem::v1::ListJobsResponse resp;
    auto ctx = ctx_for(kAliceToken);
    const grpc::Status s = d.stub()->ListJobs(ctx.get(), req, &resp);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << limit;
    EXPECT_NE(s.error_message().find("limit"), std::string::npos);
  }
  watch(d, kAliceToken, "", 1, -1, &st);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  // A spec far over gRPC's message limit never reaches the queue.
  JobSpec huge = small_spec(5);
  huge.set_name(std::string(5 << 20, 'x'));
  EXPECT_EQ(submit(d, kAliceToken, "huge", huge).status.error_code(),
            grpc::StatusCode::RESOURCE_EXHAUSTED);
  // Non-finite and negative run settings.
  JobSpec bad = small_spec(5);
  bad.mutable_run()->set_dt_ps(std::numeric_limits<double>::infinity());
  bad.mutable_outputs()->set_energy_every_ps(-1);
  const Submitted s = submit(d, kAliceToken, "bad", bad);
  EXPECT_EQ(s.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(s.status.error_message().find("run.dt_ps"), std::string::npos);
  EXPECT_NE(s.status.error_message().find("outputs.energy_every_ps"), std::string::npos);
  mdem::v1::ListJobsRequest lreq;
  mdem::v1::ListJobsResponse lresp;
  auto ctx = ctx_for(kAliceToken);
  ASSERT_TRUE(d.stub()->ListJobs(ctx.get(), lreq, &lresp).ok());
  EXPECT_EQ(lresp.jobs_size(), 0);
}

}  // namespace
