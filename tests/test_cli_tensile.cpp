// `mdem run tensile` and `mdem submit tensile` from flags: the help lists every flag with its
// range and default; text, non-finite, out-of-range and huge values each name the flag (range
// errors also the spec field and the allowed range) before anything is built or stored; flags
// override a --spec file, which must be a tensile spec.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../client/src/spec_flags.h"
#include "mdem/cli.h"
#include "mdem/spec.h"
#include "support.h"

namespace {

namespace fs = std::filesystem;

using mdem::testing::contains;
using mdem::testing::with;
using Result = mdem::testing::CliResult;

Result run(std::vector<std::string> args) {
  return mdem::testing::run_job("tensile", std::move(args));
}

struct TempDir : mdem::testing::TempDir {
  TempDir() : mdem::testing::TempDir("mdem-cli-tensile") {}
};

TEST(CliTensile, HelpListsTheFlagsWithRangesAndDefaults) {
  const Result r = run({"--help"});
  EXPECT_EQ(r.code, 0) << r.err;
  for (const char* part : {"--size S",
                           "small (default: 300 x 300 x 11 nm, 200 tubes of 200 segments)",
                           "--side NM",
                           "(0, 2000] nm (default 300 for small)",
                           "--tubes N",
                           "1..100000 tubes",
                           "--nps N",
                           "0..10000000 NPs",
                           "--np-deposit D",
                           "--prerelax PS",
                           "--relax PS",
                           "0 = ready-to-relax, [0, 1e+06] ps (default 4500)",
                           "--mode M",
                           "--strain PCT",
                           "(0, 300] % (default 20)",
                           "--rate X",
                           "(default 1e-04)",
                           "default 5.7e-05",
                           "--ramp PS",
                           "--cycles N",
                           "--amplitude PCT",
                           "--grip-width NM",
                           "--zero-velocities",
                           "--report-strains",
                           "--report-times",
                           "--seed N",
                           "--dt X|auto"})
    EXPECT_TRUE(contains(r.out, part)) << part << "\n" << r.out;
  EXPECT_FALSE(contains(r.out, "--torque")) << "twist's flags belong to `mdem run twist`";
}

TEST(CliTensile, FlagsSetTheSpecOverAFile) {
  TempDir d;
  std::ofstream(d.file("film.yaml")) << "tensile: {size: FILM_MEDIUM, nanoparticles: 100}\n";
  mdem::cli::FlagValues f = {
      {"--spec", d.file("film.yaml")}, {"--nps", "2000"},         {"--mode", "cyclic"},
      {"--report-times", "0,10"},      {"--zero-velocities", ""}, {"--np-deposit", "before-relax"},
      {"--dashpot-shear", ""}};
  const mdem::v1::JobSpec s = mdem::cli::spec_from_flags(*mdem::cli::find_spec_kind("tensile"), f);
  const mdem::v1::TensileSpec& t = s.tensile();
  EXPECT_DOUBLE_EQ(t.side_nm(), 500.0);  // the file's medium film
  EXPECT_EQ(t.nanoparticles(), 2000);    // the flag over the file
  EXPECT_EQ(t.mode(), mdem::v1::CYCLIC);
  EXPECT_DOUBLE_EQ(t.strain_rate_per_ps(), 5.7e-5);  // the cyclic default
  EXPECT_EQ(t.report_times_ps_size(), 2);
  EXPECT_TRUE(t.zero_velocities());
  EXPECT_EQ(t.np_deposit(), mdem::v1::BEFORE_RELAX);
  EXPECT_TRUE(t.vdw_dashpot_shear());
}

TEST(CliTensile, BadValuesAreRefusedNamingFlagFieldAndRange) {
  TempDir d;
  const std::string db = d.file("bad.db");
  struct Case {
    std::string flag, value, expect;
  };
  const std::vector<Case> cases = {
      {"--size", "huge", "--size"},
      {"--size", "FILM_SMALL", "--size"},
      {"--side", "0", "tensile.side_nm"},
      {"--side", "1e9", "tensile.side_nm"},
      {"--side", "nan", "--side"},
      {"--side", "wide", "--side"},
      {"--thickness", "-11", "tensile.thickness_nm"},
      {"--thickness", "inf", "--thickness"},
      {"--tubes", "0", "tensile.tubes"},
      {"--tubes", "1.5", "--tubes"},
      {"--tubes", "99999999999", "--tubes"},
      {"--segments", "100001", "tensile.segments_per_tube"},
      {"--tilt", "91", "tensile.max_tilt_deg"},
      {"--nps", "-1", "tensile.nanoparticles"},
      {"--nps", "20000", "tensile.nanoparticles"},  // more than fit the small film
      {"--np-deposit", "later", "--np-deposit"},
      {"--prerelax", "0", "tensile.prerelax_max_ps"},
      {"--relax", "-1", "tensile.relax_ps"},
      {"--relax", "-inf", "--relax"},
      {"--damping-ratio", "2", "tensile.vdw_damping_ratio"},
      {"--local-damping", "1", "tensile.local_damping"},
      {"--mode", "pull", "--mode"},
      {"--strain", "0", "tensile.target_strain_percent"},
      {"--strain", "1000", "tensile.target_strain_percent"},
      {"--strain", "NaN", "--strain"},
      {"--rate", "0", "tensile.strain_rate_per_ps"},
      {"--rate", "1", "tensile.strain_rate_per_ps"},
      {"--rate", "1e-12", "tensile.strain_rate_per_ps"},  // 2e11 ps to 20 %
      {"--ramp", "0", "tensile.ramp_ps"},
      {"--cycles", "0", "tensile.cycles"},
      {"--amplitude", "60", "tensile.amplitude_percent"},
      {"--grip-width", "0", "tensile.grip_width_nm"},
      {"--grip-width", "200", "tensile.grip_width_nm"},  // the grips of a 300 nm film meet
      {"--report-strains", "0,30", "tensile.report_strains_percent[1]"},
      {"--report-strains", "1,", "--report-strains"},
      {"--report-times", "a", "--report-times"},
      {"--report-times", "5000", "tensile.report_times_ps[0]"},
  };
  for (const Case& c : cases) {
    const Result r = run({"--db", db, "--no-log", c.flag, c.value});
    EXPECT_EQ(r.code, mdem::cli::kUsage) << c.flag << " " << c.value << "\n" << r.err;
    EXPECT_TRUE(contains(r.err, c.expect)) << c.flag << " " << c.value << "\n" << r.err;
    if (c.expect.rfind("--", 0) != 0) {
      EXPECT_TRUE(contains(r.err, "(" + c.flag + ")")) << r.err;
      EXPECT_TRUE(contains(r.err, "allowed")) << r.err;
    }
  }
  // Missing values, unknown flags, a switch with a value, a flag twice, another kind's flag.
  for (const std::vector<std::string>& args : {std::vector<std::string>{"--strain"},
                                               {"--frobnicate", "1"},
                                               {"--zero-velocities=1"},
                                               {"--nps", "1", "--nps", "2"},
                                               {"--torque", "5"}}) {
    const Result r = run(with(args, {"--db", db, "--no-log"}));
    EXPECT_EQ(r.code, mdem::cli::kUsage) << args.front() << "\n" << r.err;
    EXPECT_TRUE(contains(r.err, "mdem run tensile")) << r.err;
  }
  // A film of more elements than allowed, before anything is generated.
  const Result huge = run({"--db", db, "--no-log", "--tubes", "100000", "--segments", "1000"});
  EXPECT_EQ(huge.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(huge.err, "1e+08 elements")) << huge.err;
  EXPECT_FALSE(fs::exists(db));  // nothing was stored
}

TEST(CliTensile, SpecFilesOfAnotherKindOrWithBadValuesAreRefused) {
  TempDir d;
  std::ofstream(d.file("twist.yaml")) << "twist: {layers: 2}\n";
  Result r = run({"--spec", d.file("twist.yaml"), "--db", d.file("x.db"), "--no-log"});
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(r.err, "another job kind (allowed here: tensile)")) << r.err;
  std::ofstream(d.file("bad.json")) << R"({"tensile": {"ramp_ps": "NaN", "mode": 7}})";
  r = run({"--spec", d.file("bad.json"), "--db", d.file("x.db"), "--no-log"});
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(r.err, "tensile.ramp_ps (--ramp): nan is not a finite number")) << r.err;
  EXPECT_TRUE(contains(r.err, "tensile.mode (--mode): 7 is not a tensile mode")) << r.err;
}

}  // namespace
