// `mdem run bundle`: a small job end to end, and every flag refusing wrong, missing, huge and
// non-finite values with exit code 2 and a message naming the flag.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <sstream>

#include "mdem/cli.h"

namespace {

struct Result {
  int code;
  std::string out, err;
};

Result run(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  const int code = mdem::cli::run(args, out, err);
  return {code, out.str(), err.str()};
}

}  // namespace

TEST(CliRun, SmallBundleSucceedsWithABalancedEnergyReport) {
  const Result r = run({"bundle", "--segments", "6", "--steps", "400", "--threads", "1", "--json"});
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["kind"], "bundle");  // the key every report uses
  EXPECT_EQ(j["state"], "SUCCEEDED");
  EXPECT_EQ(j["summary"]["elements"], 42);
  EXPECT_EQ(j["performance"]["steps"], 400);
  EXPECT_GT(j["performance"]["element_steps_per_s"].get<double>(), 0);
  // Undamped, unloaded: no external work, nothing dissipated, and the balance closes to Verlet's
  // few-per-cent offset at the default step.
  EXPECT_EQ(j["summary"]["energies"]["external_work_eV"].get<double>(), 0.0);
  EXPECT_EQ(j["summary"]["energies"]["dissipated_eV"].get<double>(), 0.0);
  EXPECT_LT(j["accuracy"]["energy_balance_error"].get<double>(), 0.05);
  EXPECT_NEAR(j["accuracy"]["dt_over_critical"].get<double>(), 0.6, 1e-12);
}

TEST(CliRun, BadValuesAreRefusedNamingTheFlag) {
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {{"bundle", "--steps", "nan"}, "--steps"},
      {{"bundle", "--steps", "0"}, "--steps"},
      {{"bundle", "--steps", "99999999999999999999"}, "--steps"},
      {{"bundle", "--steps", "1.5"}, "--steps"},
      {{"bundle", "--dt", "nan"}, "--dt"},
      {{"bundle", "--dt", "inf"}, "--dt"},
      {{"bundle", "--dt", "-0.01"}, "--dt"},
      {{"bundle", "--dt", "1e300"}, "--dt"},
      {{"bundle", "--dt", "0.5"}, "above the safe limit"},  // within range, above the limit
      {{"bundle", "--speed", "inf"}, "--speed"},
      {{"bundle", "--speed", "-1"}, "--speed"},
      {{"bundle", "--spin", "NaN"}, "--spin"},
      {{"bundle", "--bundle-spin", "1e9"}, "--bundle-spin"},
      {{"bundle", "--tubes", "3"}, "--tubes"},
      {{"bundle", "--segments", "1"}, "--segments"},
      {{"bundle", "--segments", "abc"}, "--segments"},
      {{"bundle", "--threads", "-2"}, "--threads"},
      {{"bundle", "--seed", "-1"}, "--seed"},
      {{"bundle", "--steps"}, "--steps"},
      {{"bundle", "--steps", "5", "--steps", "6"}, "--steps"},
      {{"bundle", "--frobnicate", "1"}, "--frobnicate"},
      {{"bundle", "--json=yes"}, "--json"},
      {{"bundle", "stray"}, "stray"},
      {{"twirl"}, "twirl"},
  };
  for (const auto& [args, needle] : cases) {
    const Result r = run(args);
    EXPECT_EQ(r.code, mdem::cli::kUsage) << args.back() << ": " << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }
  EXPECT_EQ(run({}).code, mdem::cli::kUsage);
  EXPECT_EQ(run({"--help"}).code, mdem::cli::kOk);
}
