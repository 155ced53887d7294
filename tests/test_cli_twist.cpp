// `mdem run twist`: a small job end to end (JSON report, results in the database), and every
// input path refusing wrong, missing, huge and non-finite values with exit code 2 and a message
// naming the field and the flag.
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

using mdem::testing::with;
using Result = mdem::testing::CliResult;

// In-process `mdem run twist ARGS`.
Result run(std::vector<std::string> args) {
  return mdem::testing::run_job("twist", std::move(args));
}

// One directory for the program's databases (removed after a passing run, see ScratchDirs).
fs::path temp_dir() {
  static const fs::path d =
      mdem::testing::ScratchDirs::make("mdem-cli-twist-" + std::to_string(getpid()));
  return d;
}

const std::vector<std::string> kSmall = {"--layers",  "2", "--length",         "8",
                                         "--torque",  "1", "--hold",           "1",
                                         "--threads", "1", "--snapshot-every", "1"};

TEST(CliTwist, SmallJobReportsJsonAndStoresItsResults) {
  const std::string db = (temp_dir() / "ok.db").string();
  const Result r = run(with(kSmall, {"--db", db, "--json", "--name", "smoke"}));
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["state"], "SUCCEEDED");
  for (const char* k : {"twist_angle_deg", "topological_charge", "rope_radius_nm", "morphology",
                        "shift_angle_deg", "length_nm"})
    EXPECT_TRUE(j["summary"].contains(k)) << k;
  EXPECT_EQ(j["summary"]["tubes"], 7);
  EXPECT_EQ(j["summary"]["elements"], 7 * 6);  // 8 nm = 6 segments
  EXPECT_LT(j["accuracy"]["energy_balance_error"].get<double>(), 0.05);
  EXPECT_NEAR(j["accuracy"]["dt_over_critical"].get<double>(), 0.6, 1e-12);
  EXPECT_GT(j["performance"]["steps"].get<long>(), 50);
  EXPECT_GT(j["performance"]["element_steps_per_s"].get<double>(), 0);
  EXPECT_GT(j["performance"]["wall_s"].get<double>(), 0);
  // The job's data: the element arrays alone hold more than 200 bytes per element (positions,
  // velocities, orientations, spins, forces, torques as doubles); bonds, lists and per-thread
  // buffers add a few times that, never 50 kB per element.
  const double data = j["performance"]["job_data_bytes"].get<double>();
  EXPECT_GT(data, 200.0 * 42);
  EXPECT_LT(data, 50e3 * 42);

  mdem::cli::ResultsStore store(db);
  const auto rec = store.find(j["job_id"].get<std::string>());
  ASSERT_TRUE(rec.has_value());
  EXPECT_EQ(rec->state, "SUCCEEDED");
  EXPECT_EQ(rec->kind, "twist");
  const auto spec = nlohmann::json::parse(rec->spec_json);
  EXPECT_EQ(spec["name"], "smoke");
  EXPECT_EQ(spec["twist"]["layers"], 2);
  EXPECT_DOUBLE_EQ(spec["twist"]["torque_nn_nm"].get<double>(), 1.0);
  // Ramp 1 ps + hold 1 ps at 1 ps frames: frames at 0, ~1, ~2 ps and at the last step;
  // snapshots at the same steps.
  const auto frames = store.frames(rec->id);
  ASSERT_GE(frames.size(), 3u);
  ASSERT_LE(frames.size(), 4u);
  EXPECT_EQ(frames.front().step, 0);
  EXPECT_NEAR(frames.back().time_ps, 2.0, 0.05);
  EXPECT_EQ(store.snapshot_count(rec->id), frames.size());
  const auto cols = store.columns(rec->id);
  EXPECT_NE(std::find(cols.begin(), cols.end(), "topological_charge"), cols.end());
  EXPECT_NE(std::find(cols.begin(), cols.end(), "bond_torsion_eV"), cols.end());
  // `mdem show` of the local run says how long it ran and its data's size.
  const auto show = mdem::testing::run_shell(std::string(MDEM_CLI_PATH) + " show " + rec->id +
                                             " --db " + db + " 2>&1");
  ASSERT_EQ(show.code, 0) << show.out;
  const auto elapsed = show.out.find("elapsed:"), memory = show.out.find("memory:");
  ASSERT_NE(elapsed, std::string::npos) << show.out;
  ASSERT_NE(memory, std::string::npos) << show.out;
  EXPECT_EQ(show.out.find(" 00:00:0", elapsed), show.out.find_first_of('0', elapsed) - 1);
  EXPECT_EQ(show.out.find("job data 0.", memory), show.out.find_first_not_of(' ', memory + 7));
}

TEST(CliTwist, SpecFileAndFlagsCombineWithFlagsWinning) {
  const fs::path d = temp_dir();
  std::ofstream(d / "spec.yaml") << "name: from-yaml\ntwist:\n  layers: 2\n  length_nm: 8\n"
                                    "  torque_nn_nm: 50\n  hold_ps: 1\n"
                                    "  boundary: TWIST_RELAXATION\noutputs:\n"
                                    "  snapshot_every_ps: 0\n";
  const Result r = run({"--spec", (d / "spec.yaml").string(), "--torque", "1", "--threads", "1",
                        "--db", (d / "y.db").string(), "--json"});
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  mdem::cli::ResultsStore store((d / "y.db").string());
  const auto rec = store.find(j["job_id"].get<std::string>());
  const auto spec = nlohmann::json::parse(rec->spec_json);
  EXPECT_EQ(spec["name"], "from-yaml");
  EXPECT_EQ(spec["twist"]["boundary"], "TWIST_RELAXATION");
  EXPECT_DOUBLE_EQ(spec["twist"]["torque_nn_nm"].get<double>(), 1.0);
  EXPECT_EQ(store.snapshot_count(rec->id), 0u);
}

// Every value flag: text, non-finite, and out-of-range values each name the flag (and, for range
// errors, the spec field and its allowed range); nothing runs and no job is stored.
TEST(CliTwist, BadValuesAreRefusedNamingFieldAndRange) {
  const std::string db = (temp_dir() / "bad.db").string();
  struct Case {
    std::string flag, value, expect;
  };
  const std::vector<Case> cases = {
      {"--layers", "1", "twist.layers"},
      {"--layers", "11", "twist.layers"},
      {"--layers", "x", "--layers"},
      {"--layers", "1e9", "--layers"},
      {"--length", "4", "twist.length_nm"},
      {"--length", "1e300", "twist.length_nm"},
      {"--length", "nan", "--length"},
      {"--length", "inf", "--length"},
      {"--spacing", "1.2", "twist.spacing_nm"},
      {"--spacing", "-inf", "--spacing"},
      {"--missing", "7", "twist.missing_tubes"},
      {"--missing", "1,1", "twist.missing_tubes"},
      {"--missing", "a", "--missing"},
      {"--torque", "0", "twist.torque_nn_nm"},
      {"--torque", "501", "twist.torque_nn_nm"},
      {"--torque", "NaN", "--torque"},
      {"--rate", "-1", "twist.torque_rate"},
      {"--rate", "1e6", "twist.torque_rate"},
      {"--hold", "-1", "twist.hold_ps"},
      {"--hold", "1e7", "twist.hold_ps"},
      {"--unload-hold", "-5", "twist.unload_hold_ps"},
      {"--grip-segments", "0", "twist.grip_segments"},
      {"--grip-segments", "99", "twist.grip_segments"},
      {"--damping-ratio", "2", "twist.vdw_damping_ratio"},
      {"--local-damping", "1", "twist.local_damping"},
      {"--temperature", "-1", "twist.temperature_k"},
      {"--temperature", "1e5", "twist.temperature_k"},
      {"--temperature", "inf", "--temperature"},
      {"--dt", "0", "run.dt_ps"},
      {"--dt", "5", "run.dt_ps"},
      {"--safety", "0", "run.safety"},
      {"--threads", "-1", "run.threads"},
      {"--energy-every", "0", "outputs.energy_every_ps"},
      {"--snapshot-every", "-1", "outputs.snapshot_every_ps"},
      {"--bc", "fixed", "--bc"},
      {"--grip-load", "both", "--grip-load"},
      {"--grip-hold", "spins", "--grip-hold"},
      {"--grip-hold", "positions-and-spins", "twist.grip_hold"},  // needs --bc twist-relaxation
      {"--line-defects", "0:9", "twist.line_defects[0].width"},
      {"--line-defects", "1:2:3:4", "--line-defects"},
      {"--line-defects", "400", "twist.line_defects[0].angle_deg"},
  };
  for (const Case& c : cases) {
    const Result r = run(with(kSmall, {"--db", db, c.flag, c.value}));
    EXPECT_EQ(r.code, mdem::cli::kUsage) << c.flag << " " << c.value << "\n" << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.flag << " " << c.value << "\n" << r.err;
    if (c.expect.rfind("--", 0) != 0) {  // a range error names the flag too, and the range
      EXPECT_NE(r.err.find("(" + c.flag + ")"), std::string::npos) << r.err;
      EXPECT_NE(r.err.find("allowed"), std::string::npos) << r.err;
    }
  }
  EXPECT_FALSE(fs::exists(db));  // nothing was queued or stored
}

// A step inside the spec's range but above this rope's safe limit is refused by the engine with
// the limit in the message, before any job is stored.
TEST(CliTwist, StepAboveTheSafeLimitIsRefusedBeforeAnythingIsStored) {
  const std::string db = (temp_dir() / "dt.db").string();
  const Result r = run(with(kSmall, {"--db", db, "--dt", "0.5"}));
  EXPECT_EQ(r.code, mdem::cli::kUsage) << r.err;
  EXPECT_NE(r.err.find("safe limit"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(db));
}

TEST(CliTwist, MissingValuesUnknownFlagsAndBadSpecFiles) {
  const fs::path d = temp_dir();
  EXPECT_EQ(run({"--torque"}).code, mdem::cli::kUsage);
  EXPECT_EQ(run({"--frobnicate", "1"}).code, mdem::cli::kUsage);
  EXPECT_EQ(run({"extra"}).code, mdem::cli::kUsage);
  Result r = run({"--spec", (d / "nope.json").string()});
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_NE(r.err.find("nope.json"), std::string::npos) << r.err;
  std::ofstream(d / "bad.json") << R"({"twist": {"layers": 3, "torque_nn_nm": "NaN"}})";
  r = run({"--spec", (d / "bad.json").string()});
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_NE(r.err.find("twist.torque_nn_nm"), std::string::npos) << r.err;
  std::ofstream(d / "unknown.json") << R"({"twist": {"layers": 3, "twirl": 1}})";
  r = run({"--spec", (d / "unknown.json").string()});
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_NE(r.err.find("twirl"), std::string::npos) << r.err;
  std::ofstream(d / "broken.yaml") << "twist: [layers: 3\n";
  r = run({"--spec", (d / "broken.yaml").string()});
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_NE(r.err.find("line"), std::string::npos) << r.err;
}

TEST(CliTwist, UnwritableDatabaseFailsTheJobWithItsPath) {
  const fs::path d = temp_dir();
  std::ofstream(d / "file") << "x";
  const std::string db = (d / "file" / "sub" / "r.db").string();
  const Result r = run(with(kSmall, {"--db", db}));
  EXPECT_EQ(r.code, mdem::cli::kJobFailed);
  EXPECT_NE(r.err.find("file"), std::string::npos) << r.err;
}

}  // namespace

// Every example spec shipped in examples/ (of any kind) stays valid: loaded and validated, not
// run.
TEST(CliTwist, ShippedExampleSpecsAreValid) {
  int specs = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(MDEM_SOURCE_DIR) / "examples")) {
    const std::string ext = entry.path().extension().string();
    if (ext != ".yaml" && ext != ".yml" && ext != ".json") continue;
    ++specs;
    EXPECT_NO_THROW(mdem::spec::finalize(mdem::spec::load_file(entry.path().string())))
        << entry.path();
  }
  EXPECT_GE(specs, 4);  // twist_table4-1, twist_defects, compression-au-shell, compression-cds
}
