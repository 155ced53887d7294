// `mdem export` of real jobs of every kind that stores snapshots (twist, compression; bundle
// stores none), read back by the programs users read them with: ASE (the reference reader of
// extended XYZ) and the independent reader of export_readers.h for the binary VTK (zlib blocks
// decoded by Python's zlib) and the CSV. Everything read is compared with the stored snapshots and
// frames, and the platens, surfaces rather than particles, with the platen geometry.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "../client/src/results_store.h"
#include "export_readers.h"
#include "mdem/cli.h"
#include "support.h"

namespace {

namespace fs = std::filesystem;
using mdem::Snapshot;
using mdem::Vec3;
using mdem::cli::ResultsStore;
using mdem::testing::CliResult;
using nlohmann::json;

constexpr std::int32_t kGrain = 2, kWall = 3;

// ASE's view of an extended-XYZ file: per frame the atom count, symbols, positions, the extra
// per-atom arrays and the Step/Time of the comment line.
constexpr const char* kAseReader = R"py(
import json, sys
import ase.io
frames = ase.io.read(sys.argv[1], index=':', format='extxyz')
print(json.dumps([{'n': len(a), 'symbols': a.get_chemical_symbols(),
                   'positions': a.positions.tolist(),
                   'arrays': {k: v.tolist() for k, v in a.arrays.items()
                              if k not in ('numbers', 'positions')},
                   'step': int(a.info['Step']), 'time': float(a.info['Time'])} for a in frames]))
)py";

CliResult shell(const std::string& command) { return mdem::testing::run_shell(command + " 2>&1"); }

// Relative agreement to 1e-12 (%.17g text and float64 binary are in fact exact).
void expect_close(double read, double stored, const std::string& what) {
  EXPECT_LE(std::abs(read - stored), 1e-12 * std::max(std::abs(read), std::abs(stored)))
      << what << ": read " << read << ", stored " << stored;
}

void expect_vec(const json& read, const Vec3& v, const std::string& what) {
  ASSERT_EQ(read.size(), 3u) << what;
  for (int k = 0; k < 3; ++k) expect_close(read[k], v[k], what);
}

std::vector<std::size_t> particles(const Snapshot& s) {
  std::vector<std::size_t> ids;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s.kind[i] != kWall) ids.push_back(i);
  return ids;
}

class ExportJobsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new mdem::testing::TempDir("mdem-export-jobs");
    db_ = dir_->file("results.db");
    twist_ = run("twist", {"--layers", "2", "--length", "8", "--torque", "1", "--hold", "1",
                           "--threads", "1", "--snapshot-every", "1"});
    // About 20 grains crushed by 1 nm between two platens.
    compression_ =
        run("compression", {"--outer-radius", "4", "--grain-radius", "1,1.5", "--peak", "1",
                            "--speed", "0.05", "--threads", "1", "--snapshot-every", "5"});
    std::ofstream(dir_->file("reader.py")) << mdem::testing::kExportReader;
    std::ofstream(dir_->file("ase_reader.py")) << kAseReader;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  static std::string run(const std::string& kind, std::vector<std::string> args) {
    args.insert(args.end(), {"--db", db_, "--json"});
    const CliResult r = mdem::testing::run_job(kind, args);
    EXPECT_EQ(r.code, mdem::cli::kOk) << r.err;
    const json j = json::parse(r.out, nullptr, false);
    return j.is_object() && j.contains("job_id") ? j["job_id"].get<std::string>() : "";
  }

  static std::string file(const std::string& name) { return dir_->file(name); }

  static void export_to(const std::string& id, const char* format, const std::string& out) {
    std::ostringstream o, e;
    ASSERT_EQ(mdem::cli::export_job({id, "--format", format, "--out", out, "--db", db_}, o, e),
              mdem::cli::kOk)
        << e.str();
  }

  static json read_back(const std::string& python, const std::string& script,
                        const std::vector<std::string>& args) {
    return mdem::testing::run_reader(python, file(script), args);
  }

  // `mdem export ID --format vtk --out pvd`, read back.
  static json export_vtk(const std::string& id, const std::string& pvd) {
    export_to(id, "vtk", pvd);
    return read_back("python3", "reader.py", {"pvd", pvd});
  }

  static std::vector<Snapshot> snapshots(const std::string& id) {
    return ResultsStore(db_).snapshots(id);
  }

  static mdem::testing::TempDir* dir_;
  static std::string db_, twist_, compression_;
};

mdem::testing::TempDir* ExportJobsTest::dir_ = nullptr;
std::string ExportJobsTest::db_, ExportJobsTest::twist_, ExportJobsTest::compression_;

// A python3 that imports ase ($PATH's first, then Debian's), or "" when none does.
std::string python_with_ase() {
  for (const char* python : {"python3", "/usr/bin/python3"})
    if (shell(std::string(python) + " -c 'import ase.io'").code == 0) return python;
  return "";
}

}  // namespace

TEST_F(ExportJobsTest, AseReadsTheExtendedXyzOfEveryJobKind) {
  const std::string python = python_with_ase();
  if (python.empty())
    GTEST_SKIP() << "python3-ase is not installed (scripts/setup.sh installs it: apt-get install "
                    "python3-ase): ASE cannot read the exported extended XYZ here";
  struct Case {
    std::string id;
    std::set<std::string> extra;  // per-element columns beyond the common ones
  };
  for (const Case& c : {Case{twist_, {}}, Case{compression_, {"slip_nm"}}}) {
    ASSERT_FALSE(c.id.empty());
    const std::string path = file(c.id + ".xyz");
    export_to(c.id, "xyz", path);
    const json frames = read_back(python, "ase_reader.py", {path});
    const std::vector<Snapshot> snaps = snapshots(c.id);
    ASSERT_FALSE(snaps.empty());
    ASSERT_EQ(frames.size(), snaps.size()) << c.id;
    for (std::size_t f = 0; f < snaps.size(); ++f) {
      const Snapshot& s = snaps[f];
      const json& fr = frames[f];
      const std::vector<std::size_t> ids = particles(s);
      const std::string at = c.id + " frame " + std::to_string(f);
      ASSERT_EQ(fr["n"], ids.size()) << at;  // walls are not atoms
      EXPECT_EQ(fr["step"], s.step) << at;
      expect_close(fr["time"], s.time_ps, at + " Time");
      const json& a = fr["arrays"];
      for (const char* name :
           {"orientation", "axis", "radius", "tube", "index", "force_nN", "torque_nNnm"})
        EXPECT_TRUE(a.contains(name)) << at << ": ASE has no array " << name;
      for (const std::string& name : c.extra) EXPECT_TRUE(a.contains(name)) << at << " " << name;
      for (std::size_t p = 0; p < ids.size(); ++p) {
        const std::size_t i = ids[p];
        const std::string el = at + " element " + std::to_string(i);
        EXPECT_EQ(fr["symbols"][p], s.kind[i] == kGrain ? "Au" : "C") << el;
        expect_vec(fr["positions"][p], s.x[i], el + " position");
        expect_close(a["radius"][p], s.radius[i], el + " radius");
        EXPECT_EQ(a["tube"][p], s.tube[i]) << el;
        EXPECT_EQ(a["index"][p], s.index[i]) << el;
        expect_vec(a["axis"][p], s.q[i] * Vec3::UnitX(), el + " axis");
        for (const auto& [name, values] : s.scalars)
          expect_close(a[name][p], values[i], el + " " + name);
      }
    }
  }
}

TEST_F(ExportJobsTest, BinaryVtkHoldsTheGrainsAndThePlatensAsDiscs) {
  ASSERT_FALSE(compression_.empty());
  const json read = export_vtk(compression_, file("vtk/crush.pvd"));
  const std::vector<Snapshot> snaps = snapshots(compression_);
  // Per snapshot the elements (part 0), the bonds (2) and the platens (1).
  ASSERT_EQ(read["datasets"].size(), 3 * snaps.size());
  for (std::size_t k = 0; k < snaps.size(); ++k) {
    const Snapshot& s = snaps[k];
    char padded[24];  // room for any size_t, so the compiler sees no truncation
    std::snprintf(padded, sizeof padded, "%04zu", k);
    const json& sets = read["datasets"];
    EXPECT_EQ(sets[3 * k]["file"], std::string("crush_") + padded + ".vtp");
    EXPECT_EQ(sets[3 * k + 1]["file"], std::string("crush_bonds_") + padded + ".vtp");
    EXPECT_EQ(sets[3 * k + 2]["file"], std::string("crush_walls_") + padded + ".vtp");
    EXPECT_EQ(sets[3 * k]["part"], 0);
    EXPECT_EQ(sets[3 * k + 1]["part"], 2);
    EXPECT_EQ(sets[3 * k + 2]["part"], 1);
    const json& grains = read["pieces"][3 * k];
    const json& platens = read["pieces"][3 * k + 2];
    const std::vector<std::size_t> ids = particles(s);
    ASSERT_EQ(ids.size() + 2, s.size()) << "two platens";
    ASSERT_EQ(grains["n_points"], ids.size());
    for (std::size_t p = 0; p < ids.size(); ++p) {
      const std::string at = "snapshot " + std::to_string(k) + " point " + std::to_string(p);
      expect_vec(grains["points"][p], s.x[ids[p]], at);
      expect_close(grains["point_data"]["radius"][p], s.radius[ids[p]], at + " radius");
      EXPECT_EQ(grains["point_data"]["kind"][p], kGrain) << at;
      expect_close(grains["point_data"]["slip_nm"][p], s.scalars.back().second[ids[p]], at);
      ASSERT_EQ(s.v.size(), s.size());
      expect_vec(grains["point_data"]["velocity"][p], s.v[ids[p]], at + " velocity");
    }
    // Each platen a 64-gon of its radius, in its plane, around its point, with its normal.
    ASSERT_EQ(platens["n_polys"], 2);
    std::size_t w = 0;
    for (std::size_t i = 0; i < s.size(); ++i) {
      if (s.kind[i] != kWall) continue;
      const Vec3 normal = s.q[i] * Vec3::UnitZ();
      expect_vec(platens["cell_data"]["normal"][w], normal, "platen normal");
      EXPECT_EQ(platens["cell_data"]["element"][w], i);
      const json& poly = platens["polys"][w];
      ASSERT_EQ(poly.size(), 64u);
      Vec3 centre = Vec3::Zero();
      for (const json& id : poly) {
        const json& pt = platens["points"][id.get<std::size_t>()];
        const Vec3 x(pt[0], pt[1], pt[2]);
        EXPECT_NEAR((x - s.x[i]).norm(), s.radius[i], 1e-9 * s.radius[i]);
        EXPECT_NEAR(normal.dot(x - s.x[i]), 0.0, 1e-9 * s.radius[i]);
        centre += x / 64.0;
      }
      EXPECT_LT((centre - s.x[i]).norm(), 1e-9 * s.radius[i]);
      ++w;
    }
    EXPECT_EQ(w, 2u);
  }
}

TEST_F(ExportJobsTest, BinaryVtkOfATwistHoldsItsTubesAsPolylines) {
  ASSERT_FALSE(twist_.empty());
  const json read = export_vtk(twist_, file("rope.pvd"));
  const std::vector<Snapshot> snaps = snapshots(twist_);
  ASSERT_EQ(read["datasets"].size(), snaps.size());  // no platens, no walls files
  for (std::size_t k = 0; k < snaps.size(); ++k) {
    const Snapshot& s = snaps[k];
    const json& p = read["pieces"][k];
    ASSERT_EQ(p["n_points"], s.size());
    EXPECT_EQ(p["n_lines"], 7);  // 7 tubes of a 2-layer rope
    for (const json& line : p["lines"]) {
      ASSERT_EQ(line.size(), 6u);  // 8 nm = 6 segments
      for (std::size_t m = 0; m < line.size(); ++m) {
        const std::size_t i = line[m].get<std::size_t>();
        EXPECT_EQ(s.index[i], static_cast<std::int32_t>(m));
        EXPECT_EQ(s.tube[i], s.tube[line[0].get<std::size_t>()]);
      }
    }
    for (std::size_t i = 0; i < s.size(); ++i) expect_vec(p["points"][i], s.x[i], "point");
  }
}

TEST_F(ExportJobsTest, EveryCsvHeaderHasUniqueNamesAndTimeOnce) {
  for (const std::string& id : {twist_, compression_}) {
    ASSERT_FALSE(id.empty());
    const std::string path = file(id + ".csv");
    export_to(id, "csv", path);
    const json read = read_back("python3", "reader.py", {"csv", path});
    const std::vector<std::string> header = read["header"];
    const std::set<std::string> unique(header.begin(), header.end());
    EXPECT_EQ(unique.size(), header.size()) << id << ": " << json(header).dump();
    EXPECT_EQ(header[1], "time_ps");
    const auto frames = ResultsStore(db_).frames(id);
    ASSERT_EQ(read["rows"].size(), frames.size());
    for (std::size_t k = 0; k < frames.size(); ++k) {
      ASSERT_EQ(read["rows"][k].size(), header.size());
      expect_close(read["rows"][k][1], frames[k].time_ps, id + " time_ps");
    }
  }
  // The compression series has its own time_ps column: written once, and nothing else lost.
  const auto columns = ResultsStore(db_).columns(compression_);
  const json read = read_back("python3", "reader.py", {"csv", file(compression_ + ".csv")});
  EXPECT_EQ(read["header"].size(), 2 + columns.size() - 1);
}

// The bond network of a brittle (CdS) particle crushed far enough to break bonds: one line per
// bond between the grains it joins, its state the job's own counts of intact, yielded and broken
// bonds in the final frame.
TEST_F(ExportJobsTest, BinaryVtkHoldsTheBondNetworkWithItsStates) {
  const std::string id =
      run("compression",
          {"--outer-radius", "4", "--grain-radius", "1,1.5", "--peak", "2.5", "--speed", "0.1",
           "--material", "cds", "--threads", "1", "--snapshot-every", "10", "--no-unload"});
  ASSERT_FALSE(id.empty());
  const json read = export_vtk(id, file("cds/crush.pvd"));
  const std::vector<Snapshot> snaps = snapshots(id);
  ASSERT_EQ(read["datasets"].size(), 3 * snaps.size());
  const Snapshot& last = snaps.back();
  const json& grains = read["pieces"][3 * (snaps.size() - 1)];
  const json& bonds = read["pieces"][3 * (snaps.size() - 1) + 1];
  ASSERT_EQ(bonds["n_lines"], last.bonds.size());
  ASSERT_GT(last.bonds.size(), 10u);
  EXPECT_EQ(bonds["points"], grains["points"]);  // the element file's points, in its order
  std::map<int, long> count;
  for (std::size_t b = 0; b < last.bonds.size(); ++b) {
    const json& line = bonds["lines"][b];
    ASSERT_EQ(line.size(), 2u);
    // Grains come first in a compression snapshot, so point p is element p.
    expect_vec(bonds["points"][line[0].get<std::size_t>()], last.x[last.bonds[b].i], "bond end i");
    expect_vec(bonds["points"][line[1].get<std::size_t>()], last.x[last.bonds[b].j], "bond end j");
    ++count[bonds["cell_data"]["state"][b].get<int>()];
  }
  const auto columns = ResultsStore(db_).columns(id);
  const auto frames = ResultsStore(db_).frames(id);
  ASSERT_EQ(frames.back().step, last.step);
  auto column = [&](const std::string& name) {
    const auto it = std::find(columns.begin(), columns.end(), name);
    EXPECT_NE(it, columns.end()) << name;
    return frames.back().values[static_cast<std::size_t>(it - columns.begin())];
  };
  EXPECT_EQ(count[2], column("bonds_broken"));
  EXPECT_GT(count[2], 0) << "the test should break bonds";
  EXPECT_EQ(count[0] + count[1], column("bonds_intact"));
  EXPECT_EQ(count[1], column("bonds_yielded"));
}

// The force-displacement curve: the x label says displacement, the legend force, with units.
TEST_F(ExportJobsTest, ForceDisplacementPlotSaysDisplacement) {
  const std::string svg = file("fd.svg");
  std::ostringstream o, e;
  ASSERT_EQ(mdem::cli::plot({compression_, "--columns", "force_nN", "--x", "displacement_nm",
                             "--out", svg, "--db", db_},
                            o, e),
            mdem::cli::kOk)
      << e.str();
  std::ifstream is(svg);
  const std::string text((std::istreambuf_iterator<char>(is)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("displacement (nm)"), std::string::npos);
  EXPECT_NE(text.find("force (nN)"), std::string::npos);
  EXPECT_EQ(text.find("length (nm)"), std::string::npos);
}
