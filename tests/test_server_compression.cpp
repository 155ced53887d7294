// The compression job on mdemd: a tiny job submitted over gRPC runs to SUCCEEDED with its report;
// invalid and oversized compression specs are refused (INVALID_ARGUMENT, RESOURCE_EXHAUSTED)
// with nothing queued; `mdem submit compression --watch` stores what `mdem run compression`
// stores, so export gives the same CSV.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "daemon.h"

namespace {

using namespace mdem::testing;
using mdem::v1::JobEvent;
using mdem::v1::JobInfo;
using mdem::v1::JobSpec;
using Clock = std::chrono::steady_clock;

// About 19 grains of 1-1.5 nm in a sphere of 4 nm, crushed by 1 nm and unloaded in 20 ps.
JobSpec tiny_spec() {
  JobSpec s;
  s.set_name("tiny crush");
  s.set_seed(3);
  s.mutable_run()->set_threads(1);
  s.mutable_outputs()->set_snapshot_every_ps(5);
  auto* c = s.mutable_compression();
  c->set_outer_radius_nm(4);
  c->set_grain_radius_min_nm(1);
  c->set_grain_radius_max_nm(1.5);
  c->set_peak_displacement_nm(1);
  c->set_platen_speed_nm_per_ps(0.05);
  return s;
}

// Every event of a job until its stream ends.
std::vector<JobEvent> watch_all(const DaemonProcess& d, const std::string& id) {
  grpc::Status s;
  std::vector<JobEvent> out = watch(d, kAliceToken, id, 1, -1, &s, 120);
  EXPECT_TRUE(s.ok()) << s.error_message();
  return out;
}

JobInfo get_ok(const DaemonProcess& d, const std::string& id) {
  grpc::Status s;
  JobInfo info = get(d, kAliceToken, id, &s);
  EXPECT_TRUE(s.ok());
  return info;
}

// Watches the job to its end, then returns what the daemon says of it.
JobInfo wait_finished(const DaemonProcess& d, const std::string& id) {
  watch_all(d, id);
  return get_ok(d, id);
}

long queued_jobs(const DaemonProcess& d) {
  mdem::v1::ListJobsRequest req;
  req.set_all_users(true);
  mdem::v1::ListJobsResponse resp;
  auto ctx = ctx_for(kRootToken);
  EXPECT_TRUE(d.stub()->ListJobs(ctx.get(), req, &resp).ok());
  return resp.jobs_size();
}

TEST(ServerCompression, TinyJobSucceedsWithItsReport) {
  DaemonProcess d(fresh_dir("compression"));
  const Submitted sub = submit(d, kAliceToken, "c1", tiny_spec());
  ASSERT_TRUE(sub.status.ok()) << sub.status.error_message();
  const std::string id = sub.resp.job().job_id();
  EXPECT_EQ(sub.resp.job().kind(), "compression");
  const std::vector<JobEvent> ev = watch_all(d, id);
  ASSERT_FALSE(ev.empty());
  nlohmann::json report;
  long frames = 0, snapshots = 0;
  std::vector<mdem::v1::JobState> states;
  for (const JobEvent& e : ev) {
    if (e.has_report()) report = nlohmann::json::parse(e.report().json());
    if (e.has_frame()) ++frames;
    if (e.has_snapshot()) ++snapshots;
    if (e.has_state()) states.push_back(e.state().state());
  }
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.back(), mdem::v1::SUCCEEDED);
  EXPECT_GE(frames, 21);
  EXPECT_GE(snapshots, 4);
  ASSERT_TRUE(report.is_object());
  EXPECT_EQ(report["kind"], "compression");
  EXPECT_EQ(report["state"], "SUCCEEDED");
  EXPECT_EQ(report["job_id"], id);
  for (const char* k : {"grains", "bonds", "porosity", "peak_force_nN", "bonds_broken",
                        "bonds_yielded", "fragments", "slip_max_nm"})
    EXPECT_TRUE(report["summary"].contains(k)) << k << " in " << report["summary"].dump();
  EXPECT_NEAR(report["summary"]["peak_force_displacement_nm"].get<double>(), 1.0, 0.05);
  EXPECT_LT(report["accuracy"]["energy_balance_error"].get<double>(), 0.05);
  const JobInfo info = get_ok(d, id);
  EXPECT_EQ(info.state(), mdem::v1::SUCCEEDED);
  EXPECT_EQ(info.kind(), "compression");
  // The element count: the bound from the spec at submit (the particle is packed by the worker),
  // the real count (the grains and the two platens) once the worker built it.
  const long built = report["summary"]["grains"].get<long>() + 2;
  EXPECT_EQ(info.elements(), built);
  EXPECT_GT(info.total_steps(), 0);  // known once the worker built the job
  EXPECT_EQ(info.step(), info.total_steps());
  EXPECT_EQ(info.spec().compression().material(), mdem::v1::GOLD);  // finalized at submit
  EXPECT_DOUBLE_EQ(info.spec().compression().local_damping(), 0.7);
}

TEST(ServerCompression, InvalidSpecsAreRefusedAndNothingQueued) {
  DaemonProcess d(fresh_dir("compression-invalid"),
                  {"--max-elements", "1000"});  // the element bound of a big particle
  // Every bad field at once, each named.
  JobSpec bad = tiny_spec();
  bad.mutable_compression()->set_porosity(std::numeric_limits<double>::quiet_NaN());
  bad.mutable_compression()->set_outer_radius_nm(1);
  bad.mutable_compression()->set_bond(static_cast<mdem::v1::GrainBondKind>(9));
  bad.mutable_compression()->set_platen_speed_nm_per_ps(-1);
  grpc::Status st = submit(d, kAliceToken, "bad1", bad).status;
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  for (const char* field : {"compression.porosity", "compression.outer_radius_nm",
                            "compression.bond", "compression.platen_speed_nm_per_ps"})
    EXPECT_TRUE(contains(st.error_message(), field)) << field << "\n" << st.error_message();
  // A custom material without its properties.
  JobSpec custom = tiny_spec();
  custom.mutable_compression()->set_material(mdem::v1::CUSTOM);
  st = submit(d, kAliceToken, "bad2", custom).status;
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_TRUE(contains(st.error_message(), "compression.youngs_gpa: is required"))
      << st.error_message();
  // More grains than any daemon takes: refused by validation, before anything is packed.
  JobSpec huge = tiny_spec();
  huge.mutable_compression()->set_outer_radius_nm(1000);
  huge.mutable_compression()->set_grain_radius_min_nm(0.5);
  huge.mutable_compression()->set_grain_radius_max_nm(0.5);
  const auto t0 = Clock::now();
  st = submit(d, kAliceToken, "bad3", huge).status;
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_TRUE(contains(st.error_message(), "at most 2000000 grains")) << st.error_message();
  // Within the spec's limit but above this daemon's max_elements: refused from the estimate.
  JobSpec big = tiny_spec();
  big.mutable_compression()->set_outer_radius_nm(30);
  st = submit(d, kAliceToken, "bad4", big).status;
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_TRUE(contains(st.error_message(), "max_elements")) << st.error_message();
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 5.0);
  EXPECT_EQ(queued_jobs(d), 0);
}

// Packing is a simulation of its own (minutes for a thesis-size particle), so the daemon does
// not build a compression job in the submit call: the worker does, and a time step above the
// safe limit or more steps than max_steps fail the job there with the reason.
TEST(ServerCompression, TimeStepAndStepLimitAreCheckedByTheWorker) {
  DaemonProcess d(fresh_dir("compression-worker-checks"), {"--max-steps", "1000"});
  JobSpec big_dt = tiny_spec();
  big_dt.mutable_run()->set_dt_ps(0.9);
  Submitted sub = submit(d, kAliceToken, "dt", big_dt);
  ASSERT_TRUE(sub.status.ok());
  JobInfo info = wait_finished(d, sub.resp.job().job_id());
  EXPECT_EQ(info.state(), mdem::v1::FAILED);
  EXPECT_TRUE(contains(info.reason(), "invalid job")) << info.reason();
  EXPECT_TRUE(contains(info.reason(), "dt")) << info.reason();
  JobSpec slow = tiny_spec();
  slow.mutable_compression()->set_platen_speed_nm_per_ps(0.0001);
  sub = submit(d, kAliceToken, "steps", slow);
  ASSERT_TRUE(sub.status.ok());
  info = wait_finished(d, sub.resp.job().job_id());
  EXPECT_EQ(info.state(), mdem::v1::FAILED);
  EXPECT_TRUE(contains(info.reason(), "max_steps = 1000")) << info.reason();
}

// `mdem submit compression --watch` and `mdem run compression` with the same flags: the same
// results in the local database, so `mdem export` gives the same CSV, bit for bit.
TEST(ServerCompression, CliSubmitWatchExportsLikeAnEmbeddedRun) {
  const fs::path dir = fresh_dir("compression-cli");
  DaemonProcess d(dir);
  const std::string job =
      "compression --outer-radius 4 --grain-radius 1,1.5 --peak 1 --speed 0.05 --threads 1 "
      "--seed 3 --snapshot-every 5 ";
  const std::string db = " --db " + (dir / "results.db").string();
  const CliResult sub = mdem_submit_watch(d, dir, job + db);
  ASSERT_EQ(sub.code, 0) << sub.out << slurp(dir / "cli.err");
  const auto remote = nlohmann::json::parse(sub.out);
  EXPECT_EQ(remote["state"], "SUCCEEDED");
  const CliResult run = mdem_cli(dir, "run " + job + db + " --json");
  ASSERT_EQ(run.code, 0) << slurp(dir / "cli.err");
  const auto local = nlohmann::json::parse(run.out);
  EXPECT_EQ(remote["summary"], local["summary"]);
  for (const auto& [id, name] : {std::pair{remote["job_id"].get<std::string>(), "remote"},
                                 std::pair{local["job_id"].get<std::string>(), "local"}})
    ASSERT_EQ(mdem_cli(dir, "export " + id + " --format csv --out " +
                                (dir / (std::string(name) + ".csv")).string() + db)
                  .code,
              0)
        << slurp(dir / "cli.err");
  const std::string csv = slurp(dir / "remote.csv");
  EXPECT_GT(std::count(csv.begin(), csv.end(), '\n'), 20);
  EXPECT_EQ(csv, slurp(dir / "local.csv"));
  const CliResult ls = mdem_cli(dir, "ls" + db);
  EXPECT_EQ(ls.code, 0);
  EXPECT_TRUE(contains(ls.out, "compression")) << ls.out;
}

}  // namespace
