// Studies on mdemd: the daemon keeps each job's study id and varied values (SubmitJobRequest
// .study), lists a study's jobs (ListJobs study_id), and a second client with a fresh results
// database lists, follows and cancels a study that another client submitted. Bad study ids and
// study tags are refused at the daemon naming the field and what is allowed.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "mdem/cli.h"
#include "server_support.h"

using namespace mdem;
using mdem::testing::contains;
using mdem::testing::DaemonProcess;
namespace fs = std::filesystem;

namespace {

struct Cli {
  int code;
  std::string out, err;
};

template <class Command>
Cli call(Command command, const std::vector<std::string>& args) {
  std::ostringstream out, err;
  const int code = command(args, out, err);
  return {code, out.str(), err.str()};
}

std::vector<std::string> with(std::vector<std::string> args, const std::vector<std::string>& more) {
  args.insert(args.end(), more.begin(), more.end());
  return args;
}

// The tiny twist job (7 tubes of 8 segments, 5 nN·nm): hold_ps sets how long it runs.
std::vector<std::string> tiny_twist(const std::string& db, const std::string& hold) {
  return {"twist",  "--layers", "2",         "--length", "10.848", "--torque", "5",
          "--hold", hold,       "--threads", "1",        "--db",   db};
}

std::string submit_study(const std::vector<std::string>& args) {
  const Cli r = call(cli::study, args);
  EXPECT_EQ(r.code, cli::kOk) << r.err;
  return nlohmann::json::parse(r.out).at("study_id");
}

}  // namespace

TEST(StudyDaemon, ASecondClientListsWatchesAndCancelsAStudyAnotherSubmitted) {
  const fs::path dir = mdem::testing::fresh_dir("study-daemon");
  DaemonProcess daemon(dir);  // one worker: the study's jobs queue behind each other
  mdem::testing::write_private(dir / "alice.token", std::string(mdem::testing::kAliceToken) + "\n");
  const std::vector<std::string> conn = {"--server", daemon.address(), "--token-file",
                                         (dir / "alice.token").string()};
  const std::string first_db = (dir / "first.db").string();
  const std::string second_db = (dir / "second.db").string();
  const std::string id = submit_study(
      with(tiny_twist(first_db, "20"), with({"--vary", "safety=0.6,0.3", "--json"}, conn)));

  // The second client has never seen the study: the daemon lists its jobs and values.
  const Cli ls = call(cli::ls, with({"--study", id, "--json"}, conn));
  ASSERT_EQ(ls.code, cli::kOk) << ls.err;
  const nlohmann::json jobs = nlohmann::json::parse(ls.out);
  ASSERT_EQ(jobs.size(), 2u);
  EXPECT_EQ(jobs[0]["run"], 0);
  EXPECT_EQ(jobs[0]["point"][0].get<double>(), 0.6);
  EXPECT_EQ(jobs[1]["point"][0].get<double>(), 0.3);
  const Cli table = call(cli::ls, with({"--study", id}, conn));
  EXPECT_TRUE(contains(table.out, "safety=0.3")) << table.out;
  EXPECT_TRUE(contains(table.out, "on mdemd at " + daemon.address())) << table.out;

  // It follows the study into its own, fresh database and gets the table with the errors.
  const Cli watched = call(cli::watch, with({"--study", id, "--db", second_db, "--json"}, conn));
  ASSERT_EQ(watched.code, cli::kOk) << watched.err;
  const nlohmann::json t = nlohmann::json::parse(watched.out);
  ASSERT_EQ(t["runs"].size(), 2u);
  for (const auto& run : t["runs"]) EXPECT_EQ(run["state"], "SUCCEEDED");
  // The coarse step's twist angle against the fine one's: a small, nonzero difference.
  const double e0 = t["runs"][0]["results"]["twist_angle_deg"]["relative_error"].get<double>();
  EXPECT_GT(e0, 0);
  EXPECT_LT(e0, 1e-2);
  // Recorded there: `mdem ls --study` of that database now lists it without the daemon.
  const Cli local = call(cli::ls, {"--study", id, "--db", second_db, "--json"});
  ASSERT_EQ(local.code, cli::kOk) << local.err;
  EXPECT_EQ(nlohmann::json::parse(local.out).size(), 2u);

  // A long study, cancelled as one from a third, fresh client: every job ends CANCELLED.
  const std::string slow = submit_study(with(
      tiny_twist(first_db, "100000"), with({"--vary", "safety=0.6,0.3,0.15", "--json"}, conn)));
  const std::string third_db = (dir / "third.db").string();
  const Cli cancelled = call(cli::cancel, with({"--study", slow, "--db", third_db}, conn));
  EXPECT_EQ(cancelled.code, cli::kOk) << cancelled.err;
  for (const auto& j :
       nlohmann::json::parse(call(cli::ls, with({"--study", slow, "--json"}, conn)).out)) {
    const v1::JobInfo info = mdem::testing::wait_finished(daemon, j["job_id"].get<std::string>());
    EXPECT_EQ(info.state(), v1::CANCELLED) << info.reason();
    EXPECT_EQ(info.study().study_id(), slow);
  }
  // Another user does not see alice's study.
  mdem::testing::write_private(dir / "bob.token", std::string(mdem::testing::kBobToken) + "\n");
  const Cli bob = call(cli::ls, {"--study", id, "--json", "--server", daemon.address(),
                                 "--token-file", (dir / "bob.token").string()});
  EXPECT_EQ(bob.code, cli::kOk) << bob.err;
  EXPECT_EQ(nlohmann::json::parse(bob.out).size(), 0u);
  // A study neither here nor on the daemon: named, with where it looked.
  const Cli none =
      call(cli::watch, with({"--study", "s-19990101-000000-0000", "--db", second_db}, conn));
  EXPECT_NE(none.code, cli::kOk);
  EXPECT_TRUE(contains(none.err, "no study 's-19990101-000000-0000'")) << none.err;
  fs::remove_all(dir);
}

TEST(StudyDaemon, BadStudyIdsAndTagsAreRefusedNamingTheFieldAndTheForm) {
  const fs::path dir = mdem::testing::fresh_dir("study-daemon-bad");
  DaemonProcess daemon(dir);
  mdem::testing::write_private(dir / "alice.token", std::string(mdem::testing::kAliceToken) + "\n");
  const std::vector<std::string> conn = {"--server", daemon.address(), "--token-file",
                                         (dir / "alice.token").string()};
  // ListJobs: a wrong charset, a huge id, a missing "s-".
  for (const std::string& bad : {std::string("s-a b"), "s-" + std::string(10000, 'x'),
                                 std::string("j-123"), std::string("s-")}) {
    const Cli r = call(cli::ls, with({"--study", bad}, conn));
    EXPECT_EQ(r.code, cli::kUsage) << bad.substr(0, 20) << ": " << r.err;
    EXPECT_TRUE(contains(r.err, "study_id")) << r.err;
    EXPECT_TRUE(contains(r.err, "starting with 's-'")) << r.err;
    EXPECT_LT(r.err.size(), 1000u);  // a huge id is not echoed whole
  }
  // SubmitJob: each bad study tag refused with INVALID_ARGUMENT naming its field; nothing queued.
  const auto tag = [](const std::string& id, int run,
                      std::vector<std::pair<std::string, double>> v) {
    v1::StudyRun s;
    s.set_study_id(id);
    s.set_run(run);
    for (const auto& [f, x] : v) {
      v1::StudyValue* sv = s.add_values();
      sv->set_field(f);
      sv->set_value(x);
    }
    return s;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<std::pair<v1::StudyRun, std::string>> cases = {
      {tag("s-ok", 0, {{"run.safety", nan}}), "study.values[0].value"},
      {tag("s-ok", 0, {{"run.safety", inf}}), "not finite"},
      {tag("s-ok", -1, {{"run.safety", 0.3}}), "study.run"},
      {tag("s-ok", 10000, {{"run.safety", 0.3}}), "allowed: 0..9999"},
      {tag("s-ok", 0, {}), "study.values: 0"},
      {tag("s-ok", 0, std::vector<std::pair<std::string, double>>(17, {"run.safety", 0.3})),
       "allowed: 1..16"},
      {tag("s-ok", 0, {{"Run Safety", 0.3}}), "study.values[0].field"},
      {tag("s-ok", 0, {{std::string(200, 'a'), 0.3}}), "1..128 characters"},
      {tag("s-bad id", 0, {{"run.safety", 0.3}}), "study.study_id"},
      {tag("", 3, {{"run.safety", 0.3}}), "without study.study_id"},
  };
  int n = 0;
  for (const auto& [study, expected] : cases) {
    v1::SubmitJobRequest req;
    req.set_request_id("bad-" + std::to_string(n++));
    *req.mutable_spec() = mdem::testing::small_spec(5);
    *req.mutable_study() = study;
    v1::SubmitJobResponse resp;
    auto ctx = mdem::testing::ctx_for(mdem::testing::kAliceToken);
    const grpc::Status s = daemon.stub()->SubmitJob(ctx.get(), req, &resp);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << expected;
    EXPECT_TRUE(contains(s.error_message(), expected)) << s.error_message();
  }
  const Cli all = call(cli::ls, with({"--json"}, conn));
  EXPECT_EQ(nlohmann::json::parse(all.out).size(), 0u) << all.out;
  fs::remove_all(dir);
}
