// Studies (`mdem study`): Richardson's estimate against known answers (a polynomial of known
// order, and a harmonic oscillator integrated by the engine's velocity Verlet against its
// closed form), a small twist study end to end (errors fall with the step at the measured order,
// stored with the study, listed and drawn), the same study on mdemd (queued, watched, cancelled
// as one), and bad --vary input refused with what is allowed.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "../client/src/results_store.h"
#include "../client/src/study_errors.h"
#include "../client/src/study_store.h"
#include "daemon.h"
#include "mdem/cli.h"
#include "mdem/core/cnt.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/integrate/system.h"
#include "mdem/scene/tube_builder.h"
#include "support.h"

using namespace mdem;
using mdem::testing::contains;
using mdem::testing::TempDir;
namespace fs = std::filesystem;

namespace {

mdem::testing::CliResult study(std::vector<std::string> args) {
  std::ostringstream out, err;
  const int code = cli::study(args, out, err);
  return {code, out.str(), err.str()};
}

// The tiny twist job of the end-to-end study: 7 tubes of 8 segments, 5 nN·nm, 20 ps hold.
std::vector<std::string> tiny_twist(const std::string& db) {
  return {"twist",  "--layers", "2",         "--length", "10.848", "--torque", "5",
          "--hold", "20",       "--threads", "1",        "--db",   db};
}

}  // namespace

TEST(StudyRichardson, RecoversTheOrderAndLimitOfAKnownFunction) {
  // f(h) = 1 + 0.3 h² + 0.05 h³: order 2 as h -> 0, limit 1.
  auto f = [](double h) { return 1 + 0.3 * h * h + 0.05 * h * h * h; };
  const auto r = cli::richardson(f(0.4), f(0.2), f(0.1), 2.0);
  ASSERT_TRUE(r.has_value());
  EXPECT_NEAR(r->order, 2.0, 0.15);
  // The extrapolation is closer to the limit than the finest value by far, and the estimated
  // error of the finest value brackets its true error within 20 %.
  EXPECT_LT(std::abs(r->limit - 1.0), 0.1 * std::abs(f(0.1) - 1.0));
  const double estimated = std::abs(f(0.1) - r->limit), actual = std::abs(f(0.1) - 1.0);
  EXPECT_GT(estimated, 0.8 * actual);
  EXPECT_LT(estimated, 1.2 * actual);
  // No asymptotic range: differences of opposite sign or zero, or no refinement.
  EXPECT_FALSE(cli::richardson(1.0, 2.0, 1.5, 2.0).has_value());
  EXPECT_FALSE(cli::richardson(1.0, 1.0, 1.0, 2.0).has_value());
  EXPECT_FALSE(cli::richardson(3.0, 2.0, 1.5, 1.0).has_value());
  EXPECT_FALSE(cli::richardson(NAN, 2.0, 1.5, 2.0).has_value());
}

TEST(StudyRichardson, BracketsTheEnginesHarmonicOscillatorAgainstItsClosedForm) {
  // Two CNT segments joined by the axial spring kn·A, released with a relative velocity v0:
  // the stretch is (v0/ω) sin(ωt), ω = √(kn A / μ), μ = m/2. Velocity Verlet at three steps.
  const double k = cnt::kBondKn * cnt::kBondArea;
  const double omega = std::sqrt(k / (0.5 * cnt::kMass));
  const double v0 = 0.05, t_end = 0.3 * 2 * std::numbers::pi / omega;
  const double exact = v0 / omega * std::sin(omega * t_end);
  auto stretch_at_end = [&](int steps) {
    Elements el;
    add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 2, 0);
    auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
    IntegratorSettings s;
    s.dt = t_end / steps;
    s.threads = 1;
    System sys(std::move(el), s);
    sys.add(std::move(bonds));
    sys.elements().v[1] = Vec3(v0, 0, 0);
    sys.initialize();
    sys.run(steps);
    const auto& x = sys.elements().x;
    return (x[1] - x[0]).norm() - cnt::kSegmentLength;
  };
  const double coarse = stretch_at_end(10), mid = stretch_at_end(20), fine = stretch_at_end(40);
  const auto r = cli::richardson(coarse, mid, fine, 2.0);
  ASSERT_TRUE(r.has_value());
  EXPECT_NEAR(r->order, 2.0, 0.2);  // velocity Verlet is second order
  const double actual = std::abs(fine - exact), estimated = std::abs(fine - r->limit);
  EXPECT_LT(std::abs(r->limit - exact), 0.1 * actual);
  EXPECT_GT(estimated, 0.8 * actual);
  EXPECT_LT(estimated, 1.2 * actual);
}

TEST(StudyErrors, ReferenceIsTheMostAccurateRunWithoutAConstantRatio) {
  // Runs at h = 0.9, 0.6, 0.25 (no constant ratio): the reference is the run with the most
  // element-steps; a failed run has no error.
  std::vector<cli::StudyRun> runs(4);
  const double h[] = {0.9, 0.6, 0.25, 0.1};
  for (int i = 0; i < 4; ++i) {
    runs[i].job_id = "j" + std::to_string(i);
    runs[i].point = {h[i]};
    runs[i].succeeded = i != 3;
    runs[i].element_steps = 100 / h[i];
    runs[i].results["x_nm"] = 2 + h[i] * h[i];
  }
  SummaryField x{"x_nm", SummaryField::Type::Real, "nm", "x", 1, 6, false, true};
  const cli::StudyErrors e = cli::study_errors(runs, {0.9, 0.6, 0.25, 0.1}, {x});
  EXPECT_EQ(e.finest, 2u);
  EXPECT_TRUE(e.richardson_runs.empty());
  ASSERT_EQ(e.results.size(), 1u);
  EXPECT_DOUBLE_EQ(e.results[0].reference, 2 + 0.25 * 0.25);
  EXPECT_FALSE(e.results[0].extrapolated);
  EXPECT_DOUBLE_EQ(e.results[0].error[0], 0.81 - 0.0625);
  EXPECT_DOUBLE_EQ(e.results[0].error[2], 0.0);
  EXPECT_TRUE(std::isnan(e.results[0].error[3]));
  // No run succeeded: no reference, said so.
  for (auto& r : runs) r.succeeded = false;
  EXPECT_THROW(cli::study_errors(runs, {}, {x}), std::invalid_argument);
}

TEST(Study, ThreeSafetyFactorsOnATinyTwistConvergeAtTheMeasuredOrder) {
  TempDir dir("mdem-study");
  const std::string db = dir.file("results.db");
  std::vector<std::string> args = tiny_twist(db);
  args.insert(args.end(), {"--vary", "safety=0.6,0.3,0.15", "--json"});
  const auto r = study(args);
  ASSERT_EQ(r.code, cli::kOk) << r.err << r.out;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["runs"].size(), 3u);
  // Every declared result of the twist kind is there; the twist angle's errors fall with the
  // step, at an observed order above 0.5, against Richardson's extrapolation.
  std::map<std::string, nlohmann::json> results;
  for (const auto& res : j["results"]) results[res["key"]] = res;
  for (const char* key :
       {"twist_angle_deg", "shift_angle_deg", "rope_radius_nm", "topological_charge"})
    EXPECT_TRUE(results.count(key)) << key;
  for (const char* key : {"twist_angle_deg", "shift_angle_deg"}) {
    const auto& res = results[key];
    EXPECT_TRUE(res["extrapolated"].get<bool>()) << key;
    EXPECT_GT(res["observed_order"].get<double>(), 0.5) << key;
    double last = INFINITY;
    for (const auto& run : j["runs"]) {
      const double err = run["results"][key]["relative_error"].get<double>();
      EXPECT_GT(err, 0) << key;
      EXPECT_LT(err, last) << key;
      last = err;
    }
  }
  // The energy-balance error falls with the step too (second order: by about 4 per halving).
  const double b0 = j["runs"][0]["energy_balance_error"].get<double>();
  const double b2 = j["runs"][2]["energy_balance_error"].get<double>();
  EXPECT_GT(b0 / b2, 8.0);

  // Stored with the study: its runs and one error row per run and result.
  const std::string id = j["study_id"];
  cli::ResultsStore jobs(db);
  cli::StudyStore studies(db);
  ASSERT_TRUE(studies.find(id).has_value());
  EXPECT_EQ(studies.runs(id).size(), 3u);
  EXPECT_EQ(studies.errors(id).size(), 3u * results.size());
  for (const auto& run : studies.runs(id)) EXPECT_EQ(jobs.find(run.job_id)->state, "SUCCEEDED");

  // `mdem ls --study` lists its jobs; `mdem study show` prints the table again.
  std::ostringstream out, err;
  ASSERT_EQ(cli::ls({"--study", id, "--db", db}, out, err), cli::kOk) << err.str();
  EXPECT_TRUE(contains(out.str(), "safety=0.15")) << out.str();
  const auto shown = study({"show", id.substr(0, 12), "--db", db});
  ASSERT_EQ(shown.code, cli::kOk) << shown.err;
  EXPECT_TRUE(contains(shown.out, "Richardson's extrapolation from safety = 0.6, 0.3, 0.15"))
      << shown.out;
  EXPECT_TRUE(contains(shown.out, "twist angle:")) << shown.out;

  // `mdem plot` of the study, where gnuplot is installed.
  if (std::system("command -v gnuplot >/dev/null 2>&1") == 0) {
    std::ostringstream pout, perr;
    const std::string png = dir.file("study.png");
    ASSERT_EQ(cli::plot({id, "--db", db, "--out", png}, pout, perr), cli::kOk) << perr.str();
    EXPECT_GT(std::filesystem::file_size(png), 1000u);
    EXPECT_TRUE(contains(pout.str(), "3 result(s)")) << pout.str();  // Q is 0 at every run
  }
}

TEST(Study, WithMultipleTimeSteppingTheReferenceIsTheRunWithTheMostOuterSteps) {
  // respa_k = 2 and 1 at one dt take the same steps; the slow forces are resolved only at the
  // outer steps, so respa_k = 1 is the more accurate run and the reference, whatever the order
  // of the list (it was the first listed run, by a tie in element-steps).
  TempDir dir("mdem-study-respa");
  const std::string db = dir.file("results.db");
  std::vector<std::string> args = tiny_twist(db);
  args.insert(args.end(), {"--dt", "0.004", "--vary", "respa_k=2,1", "--json"});
  const auto r = study(args);
  ASSERT_EQ(r.code, cli::kOk) << r.err << r.out;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["runs"].size(), 2u);
  EXPECT_TRUE(contains(j["reference"].get<std::string>(), "respa_k=1 ")) << j["reference"];
  for (const auto& res : j["results"])
    if (res["key"] == "twist_angle_deg") {
      EXPECT_EQ(j["runs"][1]["results"]["twist_angle_deg"]["error"].get<double>(), 0.0);
      EXPECT_GT(j["runs"][0]["results"]["twist_angle_deg"]["error"].get<double>(), 0.0);
    }
}

TEST(Study, BadVaryInputIsRefusedWithWhatIsAllowed) {
  TempDir dir("mdem-study-bad");
  const std::string db = dir.file("results.db");
  const std::vector<std::string> base = tiny_twist(db);
  auto refused = [&](const std::vector<std::string>& vary, const std::string& says) {
    std::vector<std::string> args = base;
    args.insert(args.end(), vary.begin(), vary.end());
    const auto r = study(args);
    EXPECT_EQ(r.code, cli::kUsage) << says;
    EXPECT_TRUE(contains(r.err, says)) << r.err;
  };
  refused({"--vary", "safty=0.3,0.2"}, "did you mean 'safety'?");
  refused({"--vary", "safty=0.3,0.2"}, "allowed: seed, run.dt_ps, run.safety");
  refused({"--vary", "boundary=1,2"}, "'boundary' is not a numeric field");
  refused({"--vary", "safety=0.3,abc"}, "'abc' is not a number");
  refused({"--vary", "safety=0.3,nan"}, "'nan' is not finite");
  refused({"--vary", "safety=0.3,inf"}, "'inf' is not finite");
  refused({"--vary", "safety=0.3,1.5"}, "run.safety: 1.5 is out of range (allowed: > 0 and <= 1");
  refused({"--vary", "rate=1e300"}, "twist.torque_rate_nn_nm_per_ps: 1e+300 is out of range");
  refused({"--vary", "safety="}, "no values");
  refused({"--vary", "safety=0.3,,0.2"}, "an empty value");
  refused({"--vary", "safety=0.3,"}, "an empty value");
  refused({"--vary", "safety"}, "has no '='");
  refused({"--vary"}, "--vary: missing value");
  refused({}, "--vary: missing");
  refused({"--vary", "layers=2.5"}, "not a whole number");
  refused({"--vary", "layers=99999999999"}, "cannot hold it");
  refused({"--vary", "seed=-1"}, "cannot hold it");
  refused({"--vary", "safety=0.3,0.3"}, "listed twice");
  refused({"--vary", "safety=0.3", "--vary", "run.safety=0.2"}, "varied twice");
  std::string many;
  for (int i = 1; i <= 65; ++i) many += (many.empty() ? "" : ",") + std::to_string(i * 0.01);
  refused({"--vary", "safety=" + many}, "more than 64 values");
  refused(
      {"--vary", "safety=0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8,0.9", "--vary", "torque=1,2,3,4,5,6,7,8"},
      "72 runs");
  refused({"--dt", "0.001", "--vary", "safety=0.3,0.2"}, "the safety factor would change nothing");
  // A refused study ran nothing and stored nothing.
  EXPECT_FALSE(std::filesystem::exists(db));
  // An unknown kind, and a study id that does not exist.
  EXPECT_EQ(study({"bundle", "--vary", "safety=0.3"}).code, cli::kUsage);
  const auto none = study({"show", "s-2000", "--db", db});
  EXPECT_NE(none.code, cli::kOk);
  EXPECT_TRUE(contains(none.err, "no study 's-2000'")) << none.err;
}

TEST(Study, OnTheDaemonItsJobsAreQueuedWatchedAndCancelledAsOne) {
  const auto dir = mdem::testing::fresh_dir("study");
  mdem::testing::DaemonProcess daemon(dir);
  mdem::testing::write_private(dir / "alice.token", std::string(mdem::testing::kAliceToken) + "\n");
  const std::string db = (dir / "results.db").string();
  const std::vector<std::string> conn = {"--server", daemon.address(), "--token-file",
                                         (dir / "alice.token").string()};
  std::vector<std::string> args = tiny_twist(db);
  args.insert(args.end(), {"--vary", "safety=0.6,0.3", "--json"});
  args.insert(args.end(), conn.begin(), conn.end());
  const auto queued = study(args);
  ASSERT_EQ(queued.code, cli::kOk) << queued.err;
  const std::string id = nlohmann::json::parse(queued.out)["study_id"];

  // Both jobs followed into the local database, then the study's table.
  std::vector<std::string> watch = {"--study", id, "--db", db, "--json"};
  watch.insert(watch.end(), conn.begin(), conn.end());
  std::ostringstream out, err;
  ASSERT_EQ(cli::watch(watch, out, err), cli::kOk) << err.str();
  const nlohmann::json t = nlohmann::json::parse(out.str());
  ASSERT_EQ(t["runs"].size(), 2u);
  for (const auto& run : t["runs"]) {
    EXPECT_EQ(run["state"], "SUCCEEDED");
    EXPECT_GT(run["results"]["twist_angle_deg"]["value"].get<double>(), 0);
  }
  // The coarser run's twist angle differs from the finer one's (the reference) by a little.
  const double err0 = t["runs"][0]["results"]["twist_angle_deg"]["relative_error"].get<double>();
  EXPECT_GT(err0, 0);
  EXPECT_LT(err0, 1e-2);

  // Cancelling a finished study cancels nothing and says so for each job.
  std::vector<std::string> cancel = {"--study", id, "--db", db};
  cancel.insert(cancel.end(), conn.begin(), conn.end());
  std::ostringstream cout_, cerr_;
  EXPECT_EQ(cli::cancel(cancel, cout_, cerr_), cli::kOk) << cerr_.str();
  EXPECT_TRUE(contains(cout_.str(), "had already finished")) << cout_.str();
  fs::remove_all(dir);
}
