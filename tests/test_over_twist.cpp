// The over-twist outcome (issue 17): a tube loaded far above its Greenhill torque by the
// per-element grip load buckles, coils and, with nothing left to store the work of the held
// moments, its grip elements spin up. The run guard's message names that cause instead of the
// time step, and the twist job ends its hold there with outcome separated_by_over_twist, before
// the guard would stop it, its results kept.
//
// The scene: seven (10,10) tubes of 30 segments (a two-layer rope; one tube's Greenhill torque
// 2π·B/L = 57 nN·nm with B = kn·I·T from model.md, L = 39.3 nm), 120 nN·nm on every grip element
// (one end segment of each tube), ramped at 10 nN·nm/ps, held up to 200 ps, local damping 0.1,
// 10 K of seeded noise. The tubes coil; one tube's grip spins up and the job ends at 88.5 ps, while
// the same run driven by hand is stopped by the guard at 106.8 ps.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>

#include "../client/src/console.h"
#include "mdem/cli.h"
#include "mdem/core/cnt.h"
#include "mdem/core/units.h"
#include "mdem/io/state_io.h"
#include "mdem/job/twist_job.h"
#include "support.h"

namespace mdem {
namespace {

constexpr double kTorque = 120;  // nN·nm

TwistJobSpec over_twisted_tube() {
  TwistJobSpec s;
  s.rope.layers = 2;
  s.rope.segments = 30;
  s.loading.torque_max = units::nNnm(kTorque);
  s.loading.rate = units::nNnm(10.0);
  s.loading.hold = 200;
  s.loading.grip_load = GripLoad::PerElement;
  s.temperature_k = 10;
  return s;
}

IntegratorSettings one_thread() {
  IntegratorSettings st;
  st.local_damping = 0.1;
  st.threads = 1;
  return st;
}

TEST(OverTwist, TheLoadIsFarAboveGreenhill) {
  const double B = cnt::kBondKn * cnt::kBondI * cnt::kSegmentLength;
  const double Mc = 2 * std::numbers::pi * B / (29 * cnt::kSegmentLength);
  EXPECT_GT(units::nNnm(kTorque), 2 * Mc);
}

// The job's system driven by hand (no stage, so no outcome check) until the run guard stops it:
// its message and the time, empty and -1 when it ran to the end.
struct GuardStop {
  std::string what;
  double time = -1;
};
GuardStop run_until_the_guard_stops() {
  TwistJob job(over_twisted_tube(), one_thread());
  System& sys = job.system();
  sys.initialize();
  try {
    while (sys.time() < job.duration()) sys.run(100);
  } catch (const NumericalError& e) {
    return {e.what(), sys.time()};
  }
  return {};
}

// Driven by hand past the outcome, the run guard stops the run; its message names the applied
// moment that nothing resists, not the time step.
TEST(OverTwist, GuardSaysTheMomentIsNoLongerResisted) {
  const std::string what = run_until_the_guard_stops().what;
  ASSERT_FALSE(what.empty()) << "the tube did not spin up";
  EXPECT_NE(what.find("an applied moment of 120 nN·nm on element"), std::string::npos) << what;
  EXPECT_NE(what.find("is no longer resisted"), std::string::npos) << what;
  EXPECT_NE(what.find("over-twist separation the thesis reports"), std::string::npos) << what;
  EXPECT_EQ(what.find("lower dt"), std::string::npos) << what;
  EXPECT_EQ(what.find("dt is within the safe limit"), std::string::npos) << what;
}

// Run as a job, the hold ends at the separation with the outcome in the summary, before the
// time at which the guard stopped the hand-driven run, and nothing is thrown.
TEST(OverTwist, HoldEndsWithTheSeparationOutcome) {
  const double guard_time = run_until_the_guard_stops().time;
  ASSERT_GT(guard_time, 0);

  TwistJob job(over_twisted_tube(), one_thread());
  ASSERT_NO_THROW(run_job(job, {1.0, 0}, {}));
  const std::optional<double> t = job.separation().time();
  ASSERT_TRUE(t.has_value());
  EXPECT_LT(*t, guard_time);
  EXPECT_GT(*t, units::nNnm(kTorque) / units::nNnm(10.0) * 0.5);  // not at the start
  EXPECT_NEAR(job.system().time(), *t, 1.0);                      // the stage ended there
  const SpunUpGrip& g = job.separation().grip();
  EXPECT_GE(g.tube, 0);
  EXPECT_LT(g.tube, 7);
  EXPECT_TRUE(g.segment == 0 || g.segment == 29) << g.segment;
  EXPECT_NEAR(units::to_nNnm(g.moment), kTorque, 1e-9);
  EXPECT_GT(g.spin * job.system().dt(), 0.25);

  const Summary s = job.summary();
  auto value = [&](const std::string& k) -> const SummaryValue* {
    for (const auto& [key, v] : s)
      if (key == k) return &v;
    return nullptr;
  };
  ASSERT_NE(value("outcome"), nullptr);
  EXPECT_EQ(std::get<std::string>(*value("outcome")), "separated_by_over_twist");
  ASSERT_NE(value("outcome_time_ps"), nullptr);
  EXPECT_EQ(std::get<double>(*value("outcome_time_ps")), *t);
  ASSERT_NE(value("separated_tube"), nullptr);
  EXPECT_EQ(std::get<long>(*value("separated_tube")), static_cast<long>(g.tube));
  // The results are those of the state at the separation: the energy ledger still closes.
  const auto& E = job.system().energy();
  EXPECT_LT(std::abs(E.balance_residual()), 1e-3 * E.external_work);
}

// The outcome is part of a checkpoint: a separated run's state loads into a fresh job's check,
// and a state no run can reach is refused.
TEST(OverTwist, OutcomeRoundTripsThroughACheckpointAndImpossibleStatesAreRefused) {
  TwistJob job(over_twisted_tube(), one_thread());
  run_job(job, {1.0, 0}, {});
  ASSERT_TRUE(job.separation().time().has_value());
  StateWriter w;
  job.separation().save_state(w);
  TwistJob fresh(over_twisted_tube(), one_thread());
  OverTwistSeparation loaded(std::make_shared<TwistProtocol>(fresh.protocol()));
  StateReader r(w.bytes());
  loaded.load_state(r);
  EXPECT_EQ(loaded.time(), job.separation().time());
  EXPECT_EQ(loaded.grip().element, job.separation().grip().element);
  EXPECT_EQ(loaded.grip().spin, job.separation().grip().spin);

  auto state = [](int in_a_row, double time) {
    StateWriter b;
    b.begin("over_twist");
    b.put(in_a_row);
    b.put(true);
    b.put(time);
    b.put(std::size_t{0});
    b.put(0);
    b.put(0);
    b.put(1.0);
    b.put(1.0);
    return b.take();
  };
  for (const auto& [n, t] : {std::pair{7, 1.0}, std::pair{-1, 1.0}, std::pair{1, std::nan("")}}) {
    OverTwistSeparation c(std::make_shared<TwistProtocol>(fresh.protocol()));
    const std::string bytes = state(n, t);
    StateReader bad(bytes);
    EXPECT_THROW(c.load_state(bad), CheckpointError) << n << " checks in a row, time " << t;
  }
}

// `mdem run twist` reports the outcome in its JSON and prints it; the job succeeded.
TEST(OverTwist, CliReportsAndPrintsTheOutcome) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("mdem-over-twist-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const testing::CliResult r = testing::run_job(
      "twist", {"--layers", "2", "--length", "40.7", "--torque", "120", "--rate", "10", "--hold",
                "200", "--temperature", "10", "--grip-load", "per-element", "--threads", "1",
                "--json", "--db", (dir / "r.db").string()});
  std::filesystem::remove_all(dir);
  ASSERT_EQ(r.code, cli::kOk) << r.err;
  const auto j = nlohmann::ordered_json::parse(r.out);
  EXPECT_EQ(j["state"], "SUCCEEDED");
  const auto& sum = j["summary"];
  EXPECT_EQ(sum["outcome"], "separated_by_over_twist");
  EXPECT_GE(sum["separated_tube"].get<int>(), 0);
  EXPECT_LT(sum["outcome_time_ps"].get<double>(), 212.0);  // before the end of the hold
  EXPECT_EQ(sum["outcome_time_ps"], sum["simulated_ps"]);
  std::ostringstream out, err;
  cli::print_report(out, err, j, std::nullopt);
  EXPECT_NE(out.str().find("outcome separated_by_over_twist, separated tube " +
                           std::to_string(sum["separated_tube"].get<int>()) + ", "),
            std::string::npos)
      << out.str();
}

// Below the separation nothing is reported: a held tube completes its hold.
TEST(OverTwist, HeldTubeCompletes) {
  TwistJobSpec s = over_twisted_tube();
  s.loading.torque_max = units::nNnm(20.0);  // below Greenhill's 57 nN·nm
  s.loading.hold = 20;
  TwistJob job(s, one_thread());
  run_job(job, {1.0, 0}, {});
  EXPECT_FALSE(job.separation().time().has_value());
  EXPECT_NEAR(job.system().time(), job.duration(), job.system().dt());
  const Summary sum = job.summary();
  EXPECT_EQ(sum[0].first, "outcome");
  EXPECT_EQ(std::get<std::string>(sum[0].second), "completed");
  EXPECT_EQ(sum[1].first, "outcome_time_ps");
  EXPECT_EQ(std::get<double>(sum[1].second), job.system().time());
  EXPECT_EQ(sum[2].first, "separated_tube");
  EXPECT_EQ(std::get<long>(sum[2].second), -1L);
}

}  // namespace
}  // namespace mdem
