// `mdem probe`: the JSON it prints against model.md's check values, and its refusal of bad input.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "mdem/cli.h"
#include "mdem/core/cnt.h"

namespace {

using nlohmann::json;

struct ProbeRun {
  int code = -1;
  std::string out, err;
};

ProbeRun probe(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  ProbeRun r;
  r.code = mdem::cli::probe(args, out, err);
  r.out = out.str();
  r.err = err.str();
  return r;
}

json probe_json(const std::vector<std::string>& args) {
  const ProbeRun r = probe(args);
  EXPECT_EQ(r.code, mdem::cli::kOk) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  return json::parse(r.out);
}

// Full precision, so a quaternion stays unit to 1e-16.
std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::array<double, 3> vec(const json& j) {
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

void expect_rel(double actual, double expected, double rel) {
  EXPECT_NEAR(actual, expected, rel * std::abs(expected)) << "expected " << expected;
}

// Newton's third law on the forces; nN = eV/nm × 0.1602177 and nN·nm = eV / 6.241509.
void expect_consistent(const json& j) {
  const auto f1 = vec(j["element1"]["force_eV_per_nm"]);
  const auto f2 = vec(j["element2"]["force_eV_per_nm"]);
  const auto f1n = vec(j["element1"]["force_nN"]);
  const auto t1 = vec(j["element1"]["torque_eV"]);
  const auto t1n = vec(j["element1"]["torque_nN_nm"]);
  double scale = 0;
  for (int k = 0; k < 3; ++k) scale = std::max(scale, std::abs(f1[k]));
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(f1[k], -f2[k], 1e-12 * (1 + scale));
    EXPECT_NEAR(f1n[k], f1[k] * 0.1602177, 1e-7 * std::abs(f1[k]) + 1e-15);
    EXPECT_NEAR(t1n[k], t1[k] / 6.241509, 1e-7 * std::abs(t1[k]) + 1e-15);
  }
}

TEST(CliProbe, VdwParallelPairMinimumOfModelMd) {
  const json j = probe_json({"--x2", "0,1.734357,0"});
  EXPECT_EQ(j["model"], "vdw");
  expect_rel(j["energy_eV"].get<double>(), -1.1677221, 1e-6);
  expect_consistent(j);
  // At the pair minimum the radial force vanishes (to the 7 digits of the check position).
  EXPECT_LT(std::abs(j["element1"]["force_eV_per_nm"][1].get<double>()), 1e-4);
  EXPECT_NEAR(j["vdw"]["R_nm"].get<double>(), 1.734357, 1e-12);
  EXPECT_NEAR(j["vdw"]["gamma_deg"].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(j["vdw"]["theta_deg"].get<double>(), 90.0, 1e-9);
  EXPECT_NEAR(j["vdw"]["delta"].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(j["vdw"]["D"].get<double>(), 1.734357 / 0.678 - 2.0, 1e-12);
}

TEST(CliProbe, VdwSecondCheckValueAndFormsOfFlags) {
  // --flag=value, the defaults of x1 and axis1 given explicitly, and an axis of any length.
  const json j =
      probe_json({"--model=vdw", "--x1", "0,0,0", "--axis1=2,0,0", "--x2", " 0, 2.0, 0 "});
  expect_rel(j["energy_eV"].get<double>(), -0.2348774, 1e-6);
  expect_consistent(j);
}

TEST(CliProbe, VdwCrossedPairOfModelMd) {
  const json j = probe_json({"--x2", "0,1.734357,0", "--axis2", "0,0,1"});
  expect_rel(j["energy_eV"].get<double>(), -1.2742876, 1e-6);
  expect_consistent(j);
  EXPECT_NEAR(j["vdw"]["gamma_deg"].get<double>(), 90.0, 1e-9);
  const auto axis2 = vec(j["element2"]["axis"]);
  EXPECT_NEAR(axis2[2], 1.0, 1e-12);
  // The same orientation as a quaternion: 90° about y turns x onto −z (the model flips b2).
  const double h = std::sqrt(0.5);
  const json jq = probe_json({"--x2", "0,1.734357,0", "--q2", num(h) + ",0," + num(h) + ",0"});
  expect_rel(jq["energy_eV"].get<double>(), -1.2742876, 1e-6);
}

TEST(CliProbe, VdwGeneralConfigurationBothTorqueModes) {
  // Translation of the pair leaves everything unchanged; both modes share the energy.
  const std::vector<std::string> a = {"--x2",    "0.4,1.6,0.5", "--axis1",
                                      "1,0.2,0", "--axis2",     "1,-0.3,0.4"};
  const json exact = probe_json(a);
  expect_consistent(exact);
  std::vector<std::string> b = a;
  b.insert(b.end(), {"--model", "vdw-pfc"});
  const json pfc = probe_json(b);
  EXPECT_EQ(pfc["model"], "vdw-pfc");
  EXPECT_EQ(pfc["vdw"]["torque"], "pfc");
  expect_consistent(pfc);
  expect_rel(pfc["energy_eV"].get<double>(), exact["energy_eV"].get<double>(), 1e-12);
  std::vector<std::string> c = a;
  c[1] = "10.4,11.6,12.5";
  c.insert(c.end(), {"--x1", "10,10,12"});
  const json shifted = probe_json(c);
  expect_rel(shifted["energy_eV"].get<double>(), exact["energy_eV"].get<double>(), 1e-9);
  // Exact mode: total torque about the origin balances, t1 + t2 + x1 × f1 + x2 × f2 = 0.
  const auto f2 = vec(exact["element2"]["force_eV_per_nm"]);
  const auto t1 = vec(exact["element1"]["torque_eV"]);
  const auto t2 = vec(exact["element2"]["torque_eV"]);
  const std::array<double, 3> x2 = {0.4, 1.6, 0.5};
  const std::array<double, 3> m = {x2[1] * f2[2] - x2[2] * f2[1], x2[2] * f2[0] - x2[0] * f2[2],
                                   x2[0] * f2[1] - x2[1] * f2[0]};
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(t1[k] + t2[k] + m[k], 0.0, 1e-9);
}

TEST(CliProbe, VdwBeyondCutoffIsZero) {
  const json j = probe_json({"--x2", "0,6,0"});
  EXPECT_EQ(j["energy_eV"].get<double>(), 0.0);
  EXPECT_FALSE(j["vdw"]["within_cutoff"].get<bool>());
}

TEST(CliProbe, BondStretchOfModelMd) {
  const double T = mdem::cnt::kSegmentLength;
  const json j = probe_json({"--model", "bond", "--x2", num(T + 0.01) + ",0,0"});
  EXPECT_EQ(j["model"], "bond");
  expect_rel(j["energy_eV"].get<double>(), 0.5 * 4740 * 1.427 * 0.01 * 0.01, 1e-6);
  expect_consistent(j);
  // Axial restoring force −kn·A·u_n on element 2.
  expect_rel(j["element2"]["force_eV_per_nm"][0].get<double>(), -4740 * 1.427 * 0.01, 1e-6);
  expect_rel(j["bond"]["u_n_nm"].get<double>(), 0.01, 1e-6);
  EXPECT_NEAR(j["bond"]["u_s_nm"].get<double>(), 0.0, 1e-12);
  EXPECT_NEAR(j["bond"]["twist_deg"].get<double>(), 0.0, 1e-9);
  EXPECT_NEAR(j["bond"]["bending_deg"].get<double>(), 0.0, 1e-9);
}

TEST(CliProbe, BondRestStateAndTwist) {
  const double T = mdem::cnt::kSegmentLength;
  const json rest = probe_json({"--model", "bond", "--x2", num(T) + ",0,0"});
  EXPECT_NEAR(rest["energy_eV"].get<double>(), 0.0, 1e-9);
  // Element 2 twisted by 1° about the bond axis: ½ ks·J·θ².
  const double a = 1.0 * M_PI / 180.0;
  const std::string q = num(std::cos(a / 2)) + "," + num(std::sin(a / 2)) + ",0,0";
  const json tw = probe_json({"--model", "bond", "--x2", num(T) + ",0,0", "--q2", q});
  EXPECT_NEAR(std::abs(tw["bond"]["twist_deg"].get<double>()), 1.0, 1e-5);
  expect_rel(tw["energy_eV"].get<double>(), 0.5 * 2110 * 0.696 * a * a, 1e-4);
}

// Every malformed command line: exit 2 and a message naming the offending flag.
TEST(CliProbe, BadInputIsRefusedNamingTheFlag) {
  struct Case {
    std::vector<std::string> args;
    std::string flag;
  };
  const std::vector<Case> cases = {
      {{"--x2", "0,2,0", "--bogus", "1"}, "--bogus"},
      {{"--x2", "0,2,0", "-v"}, "-v"},
      {{"--x2", "0,2,0", "stray"}, "stray"},
      {{"--x2"}, "--x2"},
      {{"--x2", "--model", "vdw"}, "--x2"},
      {{"--x2="}, "--x2"},
      {{"--x2", "0,2,0", "--model"}, "--model"},
      {{"--x2", "0,2"}, "--x2"},
      {{"--x2", "0,2,0,1"}, "--x2"},
      {{"--x2", "0,abc,0"}, "--x2"},
      {{"--x2", "0,2x,0"}, "--x2"},
      {{"--x2", "0,,0"}, "--x2"},
      {{"--x2", "0,nan,0"}, "--x2"},
      {{"--x2", "0,inf,0"}, "--x2"},
      {{"--x2", "0,-Infinity,0"}, "--x2"},
      {{"--x2", "0,1e400,0"}, "--x2"},
      {{"--x2", "0,2e6,0"}, "--x2"},
      {{"--x2", "0,2,0", "--x1", "-1e7,0,0"}, "--x1"},
      {{"--x2", "0,2,0", "--x1", "0,0"}, "--x1"},
      {{"--x2", "0,2,0", "--axis1", "0,0,0"}, "--axis1"},
      {{"--x2", "0,2,0", "--axis2", "0,0,0"}, "--axis2"},
      {{"--x2", "0,2,0", "--axis2", "1,nan,0"}, "--axis2"},
      {{"--x2", "0,2,0", "--axis2", "1,0"}, "--axis2"},
      {{"--x2", "0,2,0", "--q1", "1,0,0,0.01"}, "--q1"},
      {{"--x2", "0,2,0", "--q2", "2,0,0,0"}, "--q2"},
      {{"--x2", "0,2,0", "--q2", "0,0,0,0"}, "--q2"},
      {{"--x2", "0,2,0", "--q2", "1,0,0"}, "--q2"},
      {{"--x2", "0,2,0", "--q2", "1,0,0,inf"}, "--q2"},
      {{"--x2", "0,2,0", "--q1", "1,0,0,0", "--axis1", "1,0,0"}, "--axis1"},
      {{"--x2", "0,2,0", "--model", "lj"}, "--model"},
      {{"--x2", "0,2,0", "--x2", "0,3,0"}, "--x2"},
      {{}, "--x2"},
      {{"--model", "bond"}, "--x2"},
      {{"--x2", "0,0,0"}, "--x2"},  // coincident centres: no vdW contact
  };
  for (const Case& c : cases) {
    std::string cmd = "mdem probe";
    for (const auto& a : c.args) cmd += " '" + a + "'";
    SCOPED_TRACE(cmd);
    const ProbeRun r = probe(c.args);
    EXPECT_EQ(r.code, mdem::cli::kUsage);
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_NE(r.err.find(c.flag), std::string::npos) << r.err;
  }
  // The messages say what is allowed.
  EXPECT_NE(probe({"--x2", "0,2,0", "--model", "lj"}).err.find("vdw, vdw-pfc, bond"),
            std::string::npos);
  EXPECT_NE(probe({"--x2", "0,2"}).err.find("3 comma-separated numbers"), std::string::npos);
  EXPECT_NE(probe({"--x2", "0,2e6,0"}).err.find("1e+06"), std::string::npos);
}

TEST(CliProbe, QuaternionWithinToleranceIsNormalised) {
  const json j = probe_json({"--x2", "0,1.734357,0", "--q2", "1.0000005,0,0,0"});
  EXPECT_NEAR(j["element2"]["q_wxyz"][0].get<double>(), 1.0, 1e-15);
  expect_rel(j["energy_eV"].get<double>(), -1.1677221, 1e-6);
  // Negative coordinates are values, not flags.
  const json n = probe_json({"--x2", "-0.2,-1.734357,0"});
  EXPECT_LT(n["energy_eV"].get<double>(), 0.0);
}

TEST(CliProbe, HelpGoesToStdoutWithExitZero) {
  const ProbeRun r = probe({"--help"});
  EXPECT_EQ(r.code, mdem::cli::kOk);
  EXPECT_NE(r.out.find("--x2"), std::string::npos);
  EXPECT_TRUE(r.err.empty());
}

// The real binary: `mdem probe` prints the JSON on stdout; an unknown subcommand exits 2.
TEST(CliProbe, BinaryPrintsJson) {
  const std::filesystem::path bin = MDEM_CLI_PATH;
  if (!std::filesystem::exists(bin)) GTEST_SKIP() << "no binary at " << bin;
  const std::string cmd = "'" + bin.string() + "' probe --x2 0,1.734357,0 </dev/null";
  FILE* pipe = popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  std::array<char, 4096> buf;
  while (std::size_t n = fread(buf.data(), 1, buf.size(), pipe)) out.append(buf.data(), n);
  const int status = pclose(pipe);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  const json j = json::parse(out);
  expect_rel(j["energy_eV"].get<double>(), -1.1677221, 1e-6);

  const std::string bad = "'" + bin.string() + "' frobnicate >/dev/null 2>&1 </dev/null";
  const int bad_status = std::system(bad.c_str());
  ASSERT_TRUE(WIFEXITED(bad_status));
  EXPECT_EQ(WEXITSTATUS(bad_status), 2);
}

}  // namespace
