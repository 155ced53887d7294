// `mdem run compression` and `mdem submit compression` (flags only: the daemon's side is
// test_server_compression.cpp): the help, every flag refusing wrong, missing, huge and
// non-finite values with exit code 2 naming the flag (and the field and its range), a tiny job end
// to end through the mdem binary with its JSON report and results that ls, show and export read,
// and the shipped compression examples.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "../client/src/results_store.h"
#include "mdem/cli.h"
#include "mdem/spec.h"
#include "support.h"

namespace {

namespace fs = std::filesystem;

using mdem::testing::contains;
using mdem::testing::slurp;
using mdem::testing::with;
using Result = mdem::testing::CliResult;

// In-process `mdem run compression ARGS`.
Result run(std::vector<std::string> args) {
  return mdem::testing::run_job("compression", std::move(args));
}

// A fresh temp directory for one test.
struct TempDir : mdem::testing::TempDir {
  TempDir() : mdem::testing::TempDir("mdem-cli-compression") {}
};

// The mdem binary with `args` (words without spaces), as a user runs it, without the user's
// settings.
Result mdem_binary(const TempDir& dir, const std::vector<std::string>& args) {
  std::string cmd =
      "env -u MDEM_DB -u MDEM_SERVER -u MDEM_CONFIG HOME=" + dir.file("") + " " + MDEM_CLI_PATH;
  for (const std::string& a : args) cmd += " '" + a + "'";
  cmd += " 2>" + dir.file("stderr.txt") + " </dev/null";
  Result r = mdem::testing::run_shell(cmd);
  r.err = slurp(dir.file("stderr.txt"));
  return r;
}

// About 19 grains of 1-1.5 nm in a sphere of 4 nm, crushed by 1 nm and unloaded in 20 ps.
const std::vector<std::string> kTiny = {"--outer-radius", "4", "--grain-radius",   "1,1.5",
                                        "--peak",         "1", "--speed",          "0.05",
                                        "--threads",      "1", "--snapshot-every", "5"};

TEST(CliCompression, HelpListsTheFlagsWithRangesAndDefaults) {
  TempDir d;
  const Result r = mdem_binary(d, {"run", "compression", "--help"});
  EXPECT_EQ(r.code, 0) << r.err;
  for (const char* part : {"Usage: mdem run compression",
                           "--spec FILE",
                           "--outer-radius",
                           "--inner-radius",
                           "--grain-radius MIN,MAX",
                           "--porosity",
                           "--material M",
                           "gold",
                           "cds",
                           "custom",
                           "--youngs",
                           "--poisson",
                           "--density",
                           "--bond B",
                           "elastic",
                           "plastic",
                           "brittle",
                           "--strength",
                           "--speed",
                           "--peak",
                           "--no-unload",
                           "--viscous-ratio",
                           "--local-damping",
                           "default 0.7",
                           "--threads",
                           "--dt",
                           "--energy-every",
                           "--snapshot-every",
                           "--seed",
                           "--db PATH",
                           "--json",
                           "mdem submit compression",
                           "Exit codes"})
    EXPECT_TRUE(contains(r.out, part)) << part << "\n" << r.out;
  EXPECT_FALSE(contains(r.out, "--torque")) << "twist's flags belong to `mdem run twist`";
  // `mdem run --help` names the kind; `mdem submit compression --help` lists the same flags.
  const std::string kinds = mdem_binary(d, {"run", "--help"}).out;
  EXPECT_TRUE(contains(kinds, "\n  compression  Crushes a nanocrystalline particle")) << kinds;
  const Result s = mdem_binary(d, {"submit", "compression", "--help"});
  EXPECT_EQ(s.code, 0);
  for (const char* part : {"Usage: mdem submit compression", "--outer-radius", "--no-unload",
                           "--request-id", "--watch", "--server HOST:PORT"})
    EXPECT_TRUE(contains(s.out, part)) << part << "\n" << s.out;
  // Without a kind, the help of submit lists every kind's flags.
  const Result all = mdem_binary(d, {"submit", "--help"});
  for (const char* part : {"twist, compression", "--torque", "--outer-radius"})
    EXPECT_TRUE(contains(all.out, part)) << part;
}

// Every flag: text, non-finite and out-of-range values each name the flag (range errors also the
// spec field and the allowed range); nothing runs and nothing is stored.
TEST(CliCompression, BadValuesAreRefusedNamingFlagFieldAndRange) {
  TempDir d;
  const std::string db = d.file("bad.db");
  struct Case {
    std::string flag, value, expect;
  };
  const std::vector<Case> cases = {
      {"--outer-radius", "1", "compression.outer_radius_nm"},
      {"--outer-radius", "1e9", "compression.outer_radius_nm"},
      {"--outer-radius", "big", "--outer-radius"},
      {"--outer-radius", "nan", "--outer-radius"},
      {"--inner-radius", "-1", "compression.inner_radius_nm"},
      {"--inner-radius", "4", "compression.inner_radius_nm"},  // not below the outer radius
      {"--inner-radius", "inf", "--inner-radius"},
      {"--grain-radius", "0.1,1", "compression.grain_radius_min_nm"},
      {"--grain-radius", "1.5,1", "compression.grain_radius_min_nm"},
      {"--grain-radius", "1,3", "compression.grain_radius_max_nm"},  // too big for R = 4
      {"--grain-radius", "1,2,3", "--grain-radius"},
      {"--grain-radius", "1,", "--grain-radius"},
      {"--grain-radius", "a,b", "--grain-radius"},
      {"--porosity", "0.2", "compression.porosity"},
      {"--porosity", "0.95", "compression.porosity"},
      {"--porosity", "-inf", "--porosity"},
      {"--material", "silver", "--material"},
      {"--material", "GOLD", "--material"},
      {"--youngs", "0", "compression.youngs_gpa"},
      {"--youngs", "1e5", "compression.youngs_gpa"},
      {"--poisson", "0.5", "compression.poisson"},
      {"--density", "-1", "compression.density_g_cm3"},
      {"--bond", "soft", "--bond"},
      {"--strength", "0", "compression.strength_gpa"},
      {"--strength", "1000", "compression.strength_gpa"},
      {"--speed", "0", "compression.platen_speed_nm_per_ps"},
      {"--speed", "2", "compression.platen_speed_nm_per_ps"},
      {"--speed", "NaN", "--speed"},
      {"--peak", "8", "compression.peak_displacement_nm"},  // the particle's diameter
      {"--peak", "-1", "compression.peak_displacement_nm"},
      {"--viscous-ratio", "1.5", "compression.viscous_ratio"},
      {"--local-damping", "1", "compression.local_damping"},
      {"--threads", "-1", "run.threads"},
      {"--threads", "x", "--threads"},
      {"--dt", "0", "run.dt_ps"},
      {"--energy-every", "0", "outputs.energy_every_ps"},
      {"--seed", "-3", "--seed"},
  };
  for (const Case& c : cases) {
    const Result r = run(with(kTiny, {"--db", db, c.flag, c.value}));
    EXPECT_EQ(r.code, mdem::cli::kUsage) << c.flag << " " << c.value << "\n" << r.err;
    EXPECT_TRUE(contains(r.err, c.expect)) << c.flag << " " << c.value << "\n" << r.err;
    if (c.expect.rfind("--", 0) != 0) {
      EXPECT_TRUE(contains(r.err, "(" + c.flag + ")")) << r.err;
      EXPECT_TRUE(contains(r.err, "allowed")) << r.err;
    }
  }
  // Missing values, unknown flags, a switch with a value, a flag twice.
  for (const std::vector<std::string>& args : {std::vector<std::string>{"--peak"},
                                               {"--frobnicate", "1"},
                                               {"--no-unload=1"},
                                               {"--peak", "1", "--peak", "2"},
                                               {"extra"},
                                               {"--unload"},
                                               {"--torque", "5"}}) {
    const Result r = run(with(args, {"--db", db}));
    EXPECT_EQ(r.code, mdem::cli::kUsage) << args.front() << "\n" << r.err;
    EXPECT_TRUE(contains(r.err, "mdem run compression")) << r.err;
  }
  // A custom material without its properties names each missing field and its flag.
  const Result custom = run(with(kTiny, {"--db", db, "--material", "custom", "--bond", "plastic"}));
  EXPECT_EQ(custom.code, mdem::cli::kUsage);
  for (const char* part : {"compression.youngs_gpa (--youngs)", "compression.poisson (--poisson)",
                           "compression.density_g_cm3 (--density)",
                           "compression.strength_gpa (--strength)", "required for material CUSTOM"})
    EXPECT_TRUE(contains(custom.err, part)) << part << "\n" << custom.err;
  // A particle of more grains than allowed, before anything is packed.
  const Result huge = run({"--db", db, "--outer-radius", "1000", "--grain-radius", "0.5,1"});
  EXPECT_EQ(huge.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(huge.err, "at most 2000000 grains")) << huge.err;
  EXPECT_FALSE(fs::exists(db));  // nothing was stored
}

TEST(CliCompression, SpecFilesOfAnotherKindOrWithBadValuesAreRefused) {
  TempDir d;
  std::ofstream(d.file("twist.yaml")) << "twist: {layers: 2}\n";
  Result r = run({"--spec", d.file("twist.yaml"), "--db", d.file("x.db")});
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(r.err, "another job kind (allowed here: compression)")) << r.err;
  std::ofstream(d.file("bad.json")) << R"({"compression": {"porosity": "NaN", "bond": 7}})";
  r = run({"--spec", d.file("bad.json"), "--db", d.file("x.db")});
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(r.err, "compression.porosity (--porosity): nan is not a finite number"))
      << r.err;
  EXPECT_TRUE(contains(r.err, "compression.bond (--bond): 7 is not a bond kind")) << r.err;
  std::ofstream(d.file("unknown.yaml")) << "compression:\n  outer_radius: 10\n";
  r = run({"--spec", d.file("unknown.yaml"), "--db", d.file("x.db")});
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(r.err, "outer_radius")) << r.err;
  EXPECT_FALSE(fs::exists(d.file("x.db")));
}

// A tiny job through the binary: the JSON report with the summary keys, the record and its
// frames in the database, ls/show/export on it; a spec file under the flags.
TEST(CliCompression, TinyJobEndToEndThroughTheBinary) {
  TempDir d;
  const std::string db = d.file("results.db");
  std::ofstream(d.file("tiny.yaml")) << "name: tiny crush\nseed: 5\ncompression:\n"
                                        "  outer_radius_nm: 4\n  grain_radius_min_nm: 1\n"
                                        "  grain_radius_max_nm: 1.5\n  peak_displacement_nm: 3\n"
                                        "  material: GOLD\n";
  std::vector<std::string> args = {"run", "compression", "--spec", d.file("tiny.yaml")};
  for (const std::string& a : with(kTiny, {"--db", db, "--json"})) args.push_back(a);
  const Result r = mdem_binary(d, args);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["kind"], "compression");
  EXPECT_EQ(j["state"], "SUCCEEDED");
  const auto& s = j["summary"];
  for (const char* k :
       {"grains", "bonds", "rattlers", "porosity", "peak_force_nN", "peak_force_displacement_nm",
        "loading_stiffness_nN_per_nm", "final_force_nN", "final_displacement_nm", "bonds_yielded",
        "bonds_broken", "fragments", "slip_max_nm", "slip_mean_nm"})
    EXPECT_TRUE(s.contains(k)) << k << " in " << s.dump();
  EXPECT_GE(s["grains"].get<long>(), 10);
  EXPECT_LE(s["grains"].get<long>(), 30);
  EXPECT_GT(s["bonds"].get<long>(), 0);
  EXPECT_GT(s["peak_force_nN"].get<double>(), 0);
  // The flag's peak (1 nm) wins over the file's (3 nm): the platens came 1 nm closer, then back.
  EXPECT_NEAR(s["peak_force_displacement_nm"].get<double>(), 1.0, 0.05);
  EXPECT_NEAR(s["final_displacement_nm"].get<double>(), 0.0, 1e-6);
  EXPECT_LT(j["accuracy"]["energy_balance_error"].get<double>(), 0.05);
  EXPECT_NEAR(j["accuracy"]["dt_over_critical"].get<double>(), 0.6, 1e-12);
  EXPECT_GT(j["performance"]["steps"].get<long>(), 20);
  EXPECT_LT(j["performance"]["wall_s"].get<double>(), 20.0);

  const std::string id = j["job_id"];
  mdem::cli::ResultsStore store(db);
  const auto rec = store.find(id);
  ASSERT_TRUE(rec.has_value());
  EXPECT_EQ(rec->kind, "compression");
  EXPECT_EQ(rec->state, "SUCCEEDED");
  const auto spec = nlohmann::json::parse(rec->spec_json);
  EXPECT_EQ(spec["name"], "tiny crush");
  EXPECT_EQ(spec["seed"], "5");
  EXPECT_DOUBLE_EQ(spec["compression"]["peak_displacement_nm"].get<double>(), 1.0);
  EXPECT_EQ(spec["compression"]["bond"], "PLASTIC");
  EXPECT_DOUBLE_EQ(spec["compression"]["local_damping"].get<double>(), 0.7);
  // 20 ps at 1 ps frames: step 0, 20 more, and maybe the last step.
  const auto frames = store.frames(id);
  EXPECT_GE(frames.size(), 21u);
  EXPECT_LE(frames.size(), 22u);
  EXPECT_GE(store.snapshot_count(id), 4u);
  const auto cols = store.columns(id);
  for (const char* c : {"bond_tension_eV", "total_eV"})
    EXPECT_NE(std::find(cols.begin(), cols.end(), c), cols.end()) << c;

  Result ls = mdem_binary(d, {"ls", "--db", db});
  EXPECT_EQ(ls.code, 0) << ls.err;
  EXPECT_TRUE(contains(ls.out, id) && contains(ls.out, "compression")) << ls.out;
  Result show = mdem_binary(d, {"show", id, "--db", db, "--json"});
  ASSERT_EQ(show.code, 0) << show.err;
  EXPECT_EQ(nlohmann::json::parse(show.out)["kind"], "compression");
  const std::string csv = d.file("out.csv");
  Result ex = mdem_binary(d, {"export", id, "--format", "csv", "--out", csv, "--db", db});
  ASSERT_EQ(ex.code, 0) << ex.err;
  const std::string text = slurp(csv);
  EXPECT_TRUE(contains(text.substr(0, text.find('\n')), "time")) << text.substr(0, 200);
  EXPECT_GE(std::count(text.begin(), text.end(), '\n'), 22);
  ex = mdem_binary(d, {"export", id, "--format", "xyz", "--out", d.file("out.xyz"), "--db", db});
  EXPECT_EQ(ex.code, 0) << ex.err;
}

TEST(CliCompression, TextOutputDescribesTheParticle) {
  TempDir d;
  std::vector<std::string> args = {"run", "compression"};
  for (const std::string& a : with(kTiny, {"--db", d.file("r.db"), "--snapshot-every", "0"}))
    args.push_back(a);
  const Result r = mdem_binary(d, args);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(contains(r.err, "packing about 19 grains in a sphere of radius 4 nm")) << r.err;
  EXPECT_TRUE(contains(r.err, "grains,") && contains(r.err, "bonds, porosity")) << r.err;
  EXPECT_TRUE(contains(r.out, "compression j-") && contains(r.out, "SUCCEEDED")) << r.out;
  EXPECT_TRUE(contains(r.out, "peak force")) << r.out;
}

TEST(CliCompression, ShippedExamplesAreValidCompressionSpecs) {
  for (const char* f : {"compression-au-shell.yaml", "compression-cds.yaml"}) {
    SCOPED_TRACE(f);
    const fs::path p = fs::path(MDEM_SOURCE_DIR) / "examples" / f;
    mdem::v1::JobSpec spec;
    ASSERT_NO_THROW(spec = mdem::spec::finalize(mdem::spec::load_file(p.string())));
    ASSERT_TRUE(spec.has_compression());
    const double grains = mdem::spec::compression_grain_estimate(spec.compression());
    EXPECT_GT(grains, 4000);
    EXPECT_LT(grains, 4500);
  }
  const mdem::v1::CompressionSpec au =
      mdem::spec::finalize(
          mdem::spec::load_file(MDEM_SOURCE_DIR "/examples/compression-au-shell.yaml"))
          .compression();
  EXPECT_DOUBLE_EQ(au.outer_radius_nm(), 95);
  EXPECT_DOUBLE_EQ(au.inner_radius_nm(), 52);
  EXPECT_EQ(au.bond(), mdem::v1::PLASTIC);
  EXPECT_DOUBLE_EQ(au.strength_gpa(), 8);
  const mdem::v1::CompressionSpec cds =
      mdem::spec::finalize(mdem::spec::load_file(MDEM_SOURCE_DIR "/examples/compression-cds.yaml"))
          .compression();
  EXPECT_EQ(cds.material(), mdem::v1::CADMIUM_SULFIDE);
  EXPECT_EQ(cds.bond(), mdem::v1::BRITTLE);
  EXPECT_DOUBLE_EQ(cds.strength_gpa(), 4);
  EXPECT_DOUBLE_EQ(cds.peak_displacement_nm(), 60);
}

}  // namespace
