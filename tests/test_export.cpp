// `mdem ls`, `mdem show`, `mdem export` and `mdem plot` on a synthetic job: exported files are read
// back by an independent reader (Python's standard library: xml.etree, csv, plain parsing of the
// extended-XYZ header) and compared with what was stored; pictures are real PNG/SVG files; bad
// command lines exit with code 2 and unknown jobs with code 1.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "../client/src/results_store.h"
#include "export_readers.h"
#include "mdem/cli.h"

namespace {

namespace fs = std::filesystem;
using mdem::Quat;
using mdem::SeriesFrame;
using mdem::Snapshot;
using mdem::Vec3;
using mdem::cli::JobRecord;
using mdem::cli::ResultsStore;
using nlohmann::json;

constexpr const char* kJob = "j-20260102-030405-abcd";
constexpr const char* kOtherJob = "j-20260102-030406-ef01";  // shares the prefix j-20260102-0304

struct Result {
  int code;
  std::string out, err;
};

using Command = int (*)(const std::vector<std::string>&, std::ostream&, std::ostream&);

Result call(Command cmd, const std::vector<std::string>& args) {
  std::ostringstream out, err;
  const int code = cmd(args, out, err);
  return {code, out.str(), err.str()};
}

// Stdout of a shell command (stderr merged) and its exit status.
std::pair<int, std::string> shell(const std::string& command) {
  std::string output;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return {-1, "popen failed"};
  char buf[4096];
  for (std::size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) output.append(buf, n);
  return {pclose(p), output};
}

std::string quote(const std::string& s) { return "'" + s + "'"; }

// Relative agreement to 1e-12 (the files hold 17 significant digits, so in fact exact).
void expect_close(double read, double stored, const std::string& what) {
  EXPECT_LE(std::abs(read - stored), 1e-12 * std::max(std::abs(read), std::abs(stored)))
      << what << ": read " << read << ", stored " << stored;
}

// 3 tubes x 4 segments, a nanoparticle and a grain, in shuffled order (so that a tube's polyline
// must follow the index, not the storage order), at random positions and orientations.
Snapshot make_snapshot(long step, double time_ps, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 2);
  std::vector<std::array<std::int32_t, 3>> ids;  // kind, tube, index
  for (std::int32_t t = 0; t < 3; ++t)
    for (std::int32_t k = 0; k < 4; ++k) ids.push_back({0, t, k});
  ids.push_back({1, -1, -1});
  ids.push_back({2, -1, -1});
  std::shuffle(ids.begin(), ids.end(), std::mt19937(11));  // the same order in every snapshot
  Snapshot s;
  s.step = step;
  s.time_ps = time_ps;
  std::vector<double> force, torque;
  for (const auto& [kind, tube, index] : ids) {
    s.x.emplace_back(g(rng), g(rng) / 3, g(rng) * 1e-7);
    s.q.push_back(Quat(g(rng), g(rng), g(rng), g(rng)).normalized());
    s.radius.push_back(kind == 0 ? 0.678 : 1.5 + g(rng) / 10);
    s.kind.push_back(kind);
    s.tube.push_back(tube);
    s.index.push_back(index);
    force.push_back(std::abs(g(rng)) / 7);
    torque.push_back(std::abs(g(rng)) * 1e-20);
  }
  s.scalars = {{"force_nN", force}, {"torque_nNnm", torque}};
  return s;
}

// Point ids of each tube in index order, tubes ascending: the polylines the .vtp must hold.
std::vector<std::vector<int>> expected_polylines(const Snapshot& s) {
  std::map<int, std::map<int, int>> tubes;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s.tube[i] >= 0) tubes[s.tube[i]][s.index[i]] = static_cast<int>(i);
  std::vector<std::vector<int>> lines;
  for (const auto& [t, members] : tubes) {
    lines.emplace_back();
    for (const auto& [index, point] : members) lines.back().push_back(point);
  }
  return lines;
}

const std::vector<std::string> kColumns = {"kinetic_eV", "potential_eV", "total_eV", "strain",
                                           "stress_GPa"};

class ExportTest : public ::testing::Test {
 protected:
  static JobRecord record(const char* id, const char* kind, const char* spec, const char* state,
                          const char* reason, const char* created) {
    JobRecord r;
    r.id = id;
    r.kind = kind;
    r.spec_json = spec;
    r.state = state;
    r.reason = reason;
    r.created_at = created;
    return r;
  }
  void SetUp() override {
    std::string tmpl = (fs::temp_directory_path() / "mdem-export-test-XXXXXX").string();
    dir_ = mkdtemp(tmpl.data());
    db_ = file("results.db");
    ResultsStore store(db_);
    store.create_job(record(kJob, "twist", R"({"name":"demo rope","tubes":3})", "RUNNING", "",
                            "2026-01-02T03:04:05Z"));
    store.set_columns(kJob, kColumns);
    std::mt19937_64 rng(3);
    std::normal_distribution<double> g(0, 1);
    for (long k = 0; k < 7; ++k)
      frames_.push_back({k * 50,
                         k * 1.3430500000000001,
                         {g(rng), -g(rng) * 1e3, g(rng) / 3, k * 1e-3, g(rng) * 1e-17}});
    store.append_frames(kJob, frames_);
    for (long k = 0; k < 3; ++k) {
      snaps_.push_back(make_snapshot(k * 150, k * 4.0291500000000003, 100 + k));
      store.append_snapshot(kJob, snaps_.back());
    }
    store.finish_job(kJob, "SUCCEEDED", "",
                     R"({"job":"twist","state":"SUCCEEDED","summary":{"morphology":"helical"}})");
    store.create_job(
        record(kOtherJob, "bundle", "{}", "FAILED", "blew up at step 3", "2026-01-02T03:04:06Z"));
    std::ofstream(file("reader.py")) << mdem::testing::kExportReader;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  // Runs the Python reader on a file and returns what it read.
  json read_back(const std::string& mode, const std::string& path) const {
    const auto [status, output] =
        shell("python3 " + quote(file("reader.py")) + " " + mode + " " + quote(path));
    EXPECT_EQ(status, 0) << output;
    json j = json::parse(output, nullptr, false);
    EXPECT_FALSE(j.is_discarded()) << output;
    return j;
  }

  Result export_job(const std::vector<std::string>& args) const {
    std::vector<std::string> a = args;
    a.insert(a.end(), {"--db", db_});
    return call(mdem::cli::export_job, a);
  }
  Result plot(const std::vector<std::string>& args) const {
    std::vector<std::string> a = args;
    a.insert(a.end(), {"--db", db_});
    return call(mdem::cli::plot, a);
  }

  fs::path dir_;
  std::string db_;
  std::vector<SeriesFrame> frames_;
  std::vector<Snapshot> snaps_;
};

void expect_quat_xyzw(const json& read, const Quat& q, const std::string& what) {
  ASSERT_EQ(read.size(), 4u) << what;
  expect_close(read[0], q.x(), what + " x");
  expect_close(read[1], q.y(), what + " y");
  expect_close(read[2], q.z(), what + " z");
  expect_close(read[3], q.w(), what + " w");
}

void expect_vec(const json& read, const Vec3& v, const std::string& what) {
  ASSERT_EQ(read.size(), 3u) << what;
  for (int k = 0; k < 3; ++k) expect_close(read[k], v[k], what);
}

}  // namespace

TEST_F(ExportTest, ExtendedXyzHoldsEverySnapshotAsAFrame) {
  const std::string path = file("out/../rope.xyz");
  fs::create_directory(file("out"));
  const Result r = export_job({kJob, "--format", "xyz", "--out", path});
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  const json frames = read_back("xyz", path);
  ASSERT_EQ(frames.size(), snaps_.size());
  const json props = json::parse(
      R"([["species","S",1],["pos","R",3],["orientation","R",4],["axis","R",3],["radius","R",1],
          ["tube","I",1],["index","I",1],["force_nN","R",1],["torque_nNnm","R",1]])");
  const std::map<std::int32_t, std::string> species = {{0, "C"}, {1, "Si"}, {2, "Au"}};
  for (std::size_t f = 0; f < snaps_.size(); ++f) {
    const Snapshot& s = snaps_[f];
    const json& fr = frames[f];
    EXPECT_EQ(fr["properties"], props);
    EXPECT_EQ(fr["n"], s.size());
    EXPECT_EQ(fr["step"], s.step);
    expect_close(fr["time"], s.time_ps, "Time");
    const json& c = fr["columns"];
    for (std::size_t i = 0; i < s.size(); ++i) {
      const std::string at = "frame " + std::to_string(f) + " element " + std::to_string(i);
      EXPECT_EQ(c["species"][i], species.at(s.kind[i])) << at;
      expect_vec(c["pos"][i], s.x[i], at + " pos");
      expect_quat_xyzw(c["orientation"][i], s.q[i], at + " orientation");
      expect_vec(c["axis"][i], s.q[i] * Vec3::UnitX(), at + " axis");
      expect_close(c["radius"][i], s.radius[i], at + " radius");
      EXPECT_EQ(c["tube"][i], s.tube[i]) << at;
      EXPECT_EQ(c["index"][i], s.index[i]) << at;
      expect_close(c["force_nN"][i], s.scalars[0].second[i], at + " force_nN");
      expect_close(c["torque_nNnm"][i], s.scalars[1].second[i], at + " torque_nNnm");
    }
  }
}

TEST_F(ExportTest, VtkSeriesHasOnePolyDataPerSnapshotWithTubePolylines) {
  const std::string pvd = file("vtk/rope.pvd");  // the directory is created
  const Result r = export_job({kJob, "--format", "vtk", "--out", pvd});
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  const json read = read_back("pvd", pvd);
  ASSERT_EQ(read["datasets"].size(), snaps_.size());
  for (std::size_t k = 0; k < snaps_.size(); ++k) {
    const Snapshot& s = snaps_[k];
    EXPECT_EQ(read["datasets"][k]["file"], "rope_000" + std::to_string(k) + ".vtp");
    EXPECT_TRUE(fs::exists(file("vtk/rope_000" + std::to_string(k) + ".vtp")));
    expect_close(read["datasets"][k]["timestep"], s.time_ps, "timestep");
    const json& p = read["pieces"][k];
    expect_close(p["time"], s.time_ps, "TimeValue");
    ASSERT_EQ(p["n_points"], s.size());
    EXPECT_EQ(p["n_lines"], 3);
    EXPECT_EQ(p["lines"], json(expected_polylines(s)));
    const json& d = p["point_data"];
    for (std::size_t i = 0; i < s.size(); ++i) {
      const std::string at = "snapshot " + std::to_string(k) + " point " + std::to_string(i);
      expect_vec(p["points"][i], s.x[i], at + " position");
      expect_quat_xyzw(d["orientation"][i], s.q[i], at + " orientation");
      expect_vec(d["axis"][i], s.q[i] * Vec3::UnitX(), at + " axis");
      expect_close(d["radius"][i], s.radius[i], at + " radius");
      EXPECT_EQ(d["kind"][i], s.kind[i]) << at;
      EXPECT_EQ(d["tube"][i], s.tube[i]) << at;
      EXPECT_EQ(d["index"][i], s.index[i]) << at;
      expect_close(d["force_nN"][i], s.scalars[0].second[i], at + " force_nN");
      expect_close(d["torque_nNnm"][i], s.scalars[1].second[i], at + " torque_nNnm");
    }
  }
}

TEST_F(ExportTest, CsvHoldsTheSeriesAtFullPrecision) {
  const std::string path = file("series.csv");
  const Result r = export_job({"j-20260102-030405", "--format=csv", "--out", path});  // a prefix
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  const json read = read_back("csv", path);
  json header = json::array({"step", "time_ps"});
  for (const auto& c : kColumns) header.push_back(c);
  EXPECT_EQ(read["header"], header);
  ASSERT_EQ(read["rows"].size(), frames_.size());
  for (std::size_t k = 0; k < frames_.size(); ++k) {
    const json& row = read["rows"][k];
    ASSERT_EQ(row.size(), 2 + kColumns.size());
    EXPECT_EQ(row[0].get<double>(), frames_[k].step);
    expect_close(row[1], frames_[k].time_ps, "time_ps");
    for (std::size_t c = 0; c < kColumns.size(); ++c)
      expect_close(row[2 + c], frames_[k].values[c], kColumns[c]);
  }
}

TEST_F(ExportTest, DefaultOutputIsNamedAfterTheJobInTheCurrentDirectory) {
  const fs::path cwd = fs::current_path();
  fs::current_path(dir_);
  const Result csv = export_job({kJob, "--format", "csv"});
  const Result vtk = export_job({kJob, "--format", "vtk"});
  const Result png = plot({kJob});
  fs::current_path(cwd);
  EXPECT_EQ(csv.code, mdem::cli::kOk) << csv.err;
  EXPECT_EQ(vtk.code, mdem::cli::kOk) << vtk.err;
  EXPECT_EQ(png.code, mdem::cli::kOk) << png.err;
  EXPECT_TRUE(fs::exists(file(std::string(kJob) + ".csv")));
  EXPECT_TRUE(fs::exists(file(std::string(kJob) + ".pvd")));
  EXPECT_TRUE(fs::exists(file(std::string(kJob) + "_0002.vtp")));
  EXPECT_TRUE(fs::exists(file(std::string(kJob) + ".png")));
}

TEST_F(ExportTest, PlotWritesARealPngAndSvg) {
  const std::string png = file("energy.png"), svg = file("stress.svg");
  Result r = plot({kJob, "--out", png});
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  EXPECT_NE(r.out.find("3 column(s), 7 frames"), std::string::npos) << r.out;
  std::ifstream is(png, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(is)), std::istreambuf_iterator<char>());
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_GT(bytes.size(), 1024u);

  r = plot({kJob, "--out", svg, "--columns", "stress_GPa", "--x", "strain"});
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  const json read = read_back("svg", svg);
  EXPECT_EQ(read["root"], "svg");
  EXPECT_GT(read["paths"].get<int>() + read["polylines"].get<int>(), 0);
}

TEST_F(ExportTest, PlotWithoutGnuplotSaysWhatToInstall) {
  const char* old = std::getenv("MDEM_GNUPLOT");
  const std::string saved = old ? old : "";
  setenv("MDEM_GNUPLOT", "/nonexistent/gnuplot", 1);
  const Result r = plot({kJob, "--out", file("x.png")});
  if (old)
    setenv("MDEM_GNUPLOT", saved.c_str(), 1);
  else
    unsetenv("MDEM_GNUPLOT");
  EXPECT_EQ(r.code, mdem::cli::kJobFailed);
  EXPECT_NE(r.err.find("gnuplot-nox"), std::string::npos) << r.err;
}

TEST_F(ExportTest, BadCommandLinesAreUsageErrors) {
  const std::vector<std::pair<Result, std::string>> cases = {
      {export_job({kJob, "--format", "pdb"}), "unknown format 'pdb' (allowed: xyz, vtk, csv)"},
      {export_job({kJob}), "--format: missing"},
      {export_job({kJob, "--format", "vtk", "--out", file("a.vtp")}), "must end in .pvd"},
      {export_job({"--format", "csv"}), "missing the job ID"},
      {export_job({kJob, kOtherJob, "--format", "csv"}), "unexpected argument"},
      {export_job({kJob, "--format", "csv", "--bogus", "1"}), "unknown flag '--bogus'"},
      {plot({kJob, "--columns", "kinetic_eV,nope", "--out", file("p.png")}),
       "unknown column 'nope' (available: kinetic_eV, potential_eV, total_eV, strain, "
       "stress_GPa)"},
      {plot({kJob, "--out", file("p.jpg")}), "(allowed: .png, .svg)"},
      {plot({kJob, "--x", "volume", "--out", file("p.png")}), "--x: unknown column 'volume'"},
      {plot({}), "missing the job ID"},
      {call(mdem::cli::show, {kJob, "--db"}), "--db: missing value"},
      {call(mdem::cli::ls, {"extra"}), "unexpected argument 'extra'"},
  };
  for (const auto& [r, message] : cases) {
    EXPECT_EQ(r.code, mdem::cli::kUsage) << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
  }
}

TEST_F(ExportTest, UnknownAmbiguousAndUnexportableJobsFail) {
  Result r = export_job({"j-nope", "--format", "csv"});
  EXPECT_EQ(r.code, mdem::cli::kJobFailed);
  EXPECT_NE(r.err.find("no job 'j-nope' in " + db_), std::string::npos) << r.err;
  r = plot({"j-20260102-0304"});
  EXPECT_EQ(r.code, mdem::cli::kJobFailed);
  EXPECT_NE(r.err.find(kJob), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(kOtherJob), std::string::npos) << r.err;
  r = export_job({kOtherJob, "--format", "xyz", "--out", file("none.xyz")});
  EXPECT_EQ(r.code, mdem::cli::kJobFailed);
  EXPECT_NE(r.err.find("no snapshots"), std::string::npos) << r.err;
  std::ofstream(file("plain")) << "a regular file\n";
  r = export_job({kJob, "--format", "csv", "--out", file("plain/x.csv")});
  EXPECT_EQ(r.code, mdem::cli::kJobFailed);
  EXPECT_NE(r.err.find(file("plain/x.csv")), std::string::npos) << r.err;
  r = plot({kJob, "--out", file("plain/x.png")});
  EXPECT_EQ(r.code, mdem::cli::kJobFailed);
  EXPECT_NE(r.err.find(file("plain/x.png")), std::string::npos) << r.err;
  // A database that does not exist holds no job, and reading does not create it.
  const std::string missing = file("missing.db");
  r = call(mdem::cli::show, {kJob, "--db", missing});
  EXPECT_EQ(r.code, mdem::cli::kJobFailed);
  EXPECT_NE(r.err.find("no job '" + std::string(kJob) + "' in " + missing), std::string::npos);
  EXPECT_FALSE(fs::exists(missing));
}

TEST_F(ExportTest, LsListsJobsNewestFirstWithHighlights) {
  Result r = call(mdem::cli::ls, {"--db", db_});
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  const std::size_t other = r.out.find(kOtherJob), job = r.out.find(kJob);
  ASSERT_NE(other, std::string::npos) << r.out;
  ASSERT_NE(job, std::string::npos) << r.out;
  EXPECT_LT(other, job);  // newest first
  EXPECT_NE(r.out.find("ID"), std::string::npos);
  EXPECT_NE(r.out.find("demo rope; morphology helical"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("blew up at step 3"), std::string::npos) << r.out;

  r = call(mdem::cli::ls, {"--db", db_, "--json"});
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  const json jobs = json::parse(r.out);
  ASSERT_EQ(jobs.size(), 2u);
  EXPECT_EQ(jobs[0]["job_id"], kOtherJob);
  EXPECT_EQ(jobs[1]["report"]["summary"]["morphology"], "helical");
  EXPECT_FALSE(jobs[1].contains("summary"));  // one report, no summary.summary
  EXPECT_EQ(jobs[1]["spec"]["tubes"], 3);

  r = call(mdem::cli::ls, {"--db", file("empty.db"), "--json"});
  EXPECT_EQ(r.code, mdem::cli::kOk) << r.err;
  EXPECT_EQ(json::parse(r.out), json::array());
}

TEST_F(ExportTest, ShowPrintsTheRecordWithCounts) {
  Result r = call(mdem::cli::show, {"j-20260102-030405", "--db", db_});
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  EXPECT_NE(r.out.find("state:      SUCCEEDED"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("frames:     7 (kinetic_eV, potential_eV"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("snapshots:  3"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"morphology\": \"helical\""), std::string::npos) << r.out;

  r = call(mdem::cli::show, {"--json", kJob, "--db", db_});
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["job_id"], kJob);
  EXPECT_EQ(j["frames"], 7);
  EXPECT_EQ(j["snapshots"], 3);
  EXPECT_EQ(j["columns"], json(kColumns));
  EXPECT_EQ(j["spec"]["name"], "demo rope");
}

TEST_F(ExportTest, TheMdemBinaryDispatchesTheCommands) {
  const std::string mdem = MDEM_CLI_PATH;
  auto [status, output] = shell(quote(mdem) + " show " + kJob + " --db " + quote(db_));
  EXPECT_EQ(status, 0) << output;
  EXPECT_NE(output.find("snapshots:  3"), std::string::npos) << output;
  for (const char* cmd : {"ls", "show", "export", "plot"}) {
    std::tie(status, output) = shell(quote(mdem) + " help " + cmd);
    EXPECT_EQ(status, 0) << output;
    EXPECT_NE(output.find(std::string("Usage: mdem ") + cmd), std::string::npos) << output;
  }
  std::tie(status, output) = shell(quote(mdem) + " show j-nope --db " + quote(db_));
  EXPECT_EQ(WEXITSTATUS(status), 1) << output;
  std::tie(status, output) = shell(quote(mdem) + " export " + kJob + " --format nope");
  EXPECT_EQ(WEXITSTATUS(status), 2) << output;
}

TEST_F(ExportTest, DefaultPlotShowsEnergyChangesInPanelsWithWords) {
  const std::string svg = file("energy.svg");
  const Result r = plot({kJob, "--out", svg});
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  std::ifstream is(svg);
  const std::string text((std::istreambuf_iterator<char>(is)), std::istreambuf_iterator<char>());
  for (const char* words :
       {"energy changes from the start", "change from start (eV)", "kinetic (eV)", "total (eV)",
        "potential (eV)", "kinetic energy", "work, dissipation and balance"})
    EXPECT_NE(text.find(words), std::string::npos) << words;
  EXPECT_EQ(text.find("kinetic_eV"), std::string::npos) << "a column name in the legend";
}

TEST_F(ExportTest, PlotToAPathThatCannotBeWrittenNamesItNotGnuplot) {
  fs::create_directory(file("taken.png"));  // a directory where the picture should go
  Result r = plot({kJob, "--out", file("taken.png")});
  EXPECT_EQ(r.code, mdem::cli::kJobFailed);
  EXPECT_NE(r.err.find("cannot write the picture '" + file("taken.png") + "'"), std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("gnuplot"), std::string::npos) << r.err;
  r = plot({kJob, "--out", "/proc/mdem-test.png"});
  EXPECT_EQ(r.code, mdem::cli::kJobFailed);
  EXPECT_NE(r.err.find("/proc/mdem-test.png"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("gnuplot"), std::string::npos) << r.err;
}
