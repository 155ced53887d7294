// A tensile job's exports and picture: a tiny film (16 tubes of 40 segments, 8 Si NPs deposited
// after relaxing) run through `mdem run tensile`, exported as extended XYZ and read back by ASE
// (NPs as Si atoms of radius 2.5 nm, tube segments as C of radius 0.678 nm) and as binary VTK read
// by export_readers.h (kind and radius point data), and drawn by `mdem plot` as its stress-strain
// curve (stress in GPa against strain in %).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "../client/src/results_store.h"
#include "export_readers.h"
#include "mdem/cli.h"
#include "support.h"

namespace {

using mdem::Snapshot;
using nlohmann::json;

constexpr std::int32_t kSegment = 0, kNp = 1;
constexpr double kNpRadius = 2.5;     // nm, r_NP (tensile.md §1.3: 3870-atom Si NPs)
constexpr double kCntRadius = 0.678;  // nm, the (10,10) tube (model.md)
constexpr int kSegments = 16 * 40, kNps = 8;

class ExportTensileTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new mdem::testing::TempDir("mdem-export-tensile");
    db_ = dir_->file("results.db");
    const mdem::testing::CliResult r = mdem::testing::run_job("tensile", {"--side",
                                                                          "60",
                                                                          "--tubes",
                                                                          "16",
                                                                          "--segments",
                                                                          "40",
                                                                          "--nps",
                                                                          "8",
                                                                          "--prerelax",
                                                                          "5",
                                                                          "--relax",
                                                                          "10",
                                                                          "--grip-width",
                                                                          "10",
                                                                          "--strain",
                                                                          "1",
                                                                          "--rate",
                                                                          "1e-3",
                                                                          "--ramp",
                                                                          "10",
                                                                          "--threads",
                                                                          "1",
                                                                          "--seed",
                                                                          "3",
                                                                          "--snapshot-every",
                                                                          "10",
                                                                          "--no-log",
                                                                          "--db",
                                                                          db_,
                                                                          "--json"});
    EXPECT_EQ(r.code, mdem::cli::kOk) << r.err;
    const json j = json::parse(r.out, nullptr, false);
    if (j.is_object() && j.contains("job_id")) id_ = j["job_id"];
    std::ofstream(dir_->file("reader.py")) << mdem::testing::kExportReader;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string file(const std::string& name) { return dir_->file(name); }
  static void export_to(const char* format, const std::string& out) {
    std::ostringstream o, e;
    ASSERT_EQ(mdem::cli::export_job({id_, "--format", format, "--out", out, "--db", db_}, o, e),
              mdem::cli::kOk)
        << e.str();
  }
  static std::vector<Snapshot> snapshots() { return mdem::cli::ResultsStore(db_).snapshots(id_); }
  static int count_kind(const Snapshot& s, std::int32_t kind) {
    int n = 0;
    for (std::size_t i = 0; i < s.size(); ++i) n += s.kind[i] == kind;
    return n;
  }

  static mdem::testing::TempDir* dir_;
  static std::string db_, id_;
};

mdem::testing::TempDir* ExportTensileTest::dir_ = nullptr;
std::string ExportTensileTest::db_, ExportTensileTest::id_;

TEST_F(ExportTensileTest, AseReadsNanoparticlesAsSiliconWithTheirRadius) {
  std::string python;
  for (const char* p : {"python3", "/usr/bin/python3"})
    if (mdem::testing::run_shell(std::string(p) + " -c 'import ase.io' 2>/dev/null").code == 0) {
      python = p;
      break;
    }
  if (python.empty()) GTEST_SKIP() << "python3-ase is not installed (apt-get install python3-ase)";
  ASSERT_FALSE(id_.empty());
  std::ofstream(file("ase_reader.py")) << R"py(
import json, sys
import ase.io
frames = ase.io.read(sys.argv[1], index=':', format='extxyz')
print(json.dumps([{'symbols': a.get_chemical_symbols(), 'radius': a.arrays['radius'].tolist(),
                   'positions': a.positions.tolist()} for a in frames]))
)py";
  export_to("xyz", file("film.xyz"));
  const json frames = mdem::testing::run_reader(python, file("ase_reader.py"), {file("film.xyz")});
  const std::vector<Snapshot> snaps = snapshots();
  ASSERT_GE(snaps.size(), 2u);
  ASSERT_EQ(frames.size(), snaps.size());
  for (std::size_t f = 0; f < snaps.size(); ++f) {
    const Snapshot& s = snaps[f];
    int si = 0, c = 0;
    for (std::size_t p = 0; p < s.size(); ++p) {
      const std::string sym = frames[f]["symbols"][p];
      const double r = frames[f]["radius"][p];
      if (sym == "Si") {
        ++si;
        EXPECT_EQ(s.kind[p], kNp);
        EXPECT_DOUBLE_EQ(r, kNpRadius) << "frame " << f << " atom " << p;
      } else {
        ++c;
        EXPECT_EQ(sym, "C");
        EXPECT_EQ(s.kind[p], kSegment);
        EXPECT_NEAR(r, kCntRadius, 1e-12) << "frame " << f << " atom " << p;
      }
      for (int k = 0; k < 3; ++k)
        EXPECT_DOUBLE_EQ(frames[f]["positions"][p][k].get<double>(), s.x[p][k]);
    }
    EXPECT_EQ(c, kSegments) << "frame " << f;
    EXPECT_EQ(si, count_kind(s, kNp)) << "frame " << f;
  }
  // Deposited after the relaxation: the last snapshot, in the test, holds all 8.
  EXPECT_EQ(count_kind(snaps.back(), kNp), kNps);
}

TEST_F(ExportTensileTest, VtkHoldsTubesAndNanoparticlesWithKindAndRadius) {
  ASSERT_FALSE(id_.empty());
  export_to("vtk", file("vtk/film.pvd"));
  const json read =
      mdem::testing::run_reader("python3", file("reader.py"), {"pvd", file("vtk/film.pvd")});
  const std::vector<Snapshot> snaps = snapshots();
  const Snapshot& last = snaps.back();
  // The last snapshot's element file: its points are the elements in order.
  json pieces = read["pieces"];
  const json* elements = nullptr;
  for (const json& p : pieces)
    if (p["n_points"] == last.size()) elements = &p;
  ASSERT_NE(elements, nullptr) << "no piece of " << last.size() << " points";
  int nps = 0;
  for (std::size_t i = 0; i < last.size(); ++i) {
    const int kind = (*elements)["point_data"]["kind"][i];
    const double r = (*elements)["point_data"]["radius"][i];
    EXPECT_EQ(kind, last.kind[i]);
    EXPECT_NEAR(r, kind == kNp ? kNpRadius : kCntRadius, 1e-12) << "point " << i;
    if (kind == kNp) ++nps;
  }
  EXPECT_EQ(nps, kNps);
}

TEST_F(ExportTensileTest, DefaultPlotIsTheStressStrainCurveInPercent) {
  ASSERT_FALSE(id_.empty());
  const std::string svg = file("ss.svg");
  std::ostringstream o, e;
  ASSERT_EQ(mdem::cli::plot({id_, "--out", svg, "--db", db_}, o, e), mdem::cli::kOk) << e.str();
  EXPECT_NE(o.str().find("1 column(s)"), std::string::npos) << o.str();
  std::ifstream is(svg);
  const std::string text((std::istreambuf_iterator<char>(is)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("strain (%)"), std::string::npos);
  EXPECT_NE(text.find("stress (GPa)"), std::string::npos);
  EXPECT_EQ(text.find("energy (eV)"), std::string::npos);
  // The strain axis reaches the test's 1 % (a tick labelled 1), not the fraction 0.01.
  EXPECT_NE(text.find("> 1</text>"), std::string::npos);
  // --columns still draws anything else against time.
  std::ostringstream o2, e2;
  ASSERT_EQ(mdem::cli::plot(
                {id_, "--out", file("e.svg"), "--columns", "kinetic_translational_eV", "--db", db_},
                o2, e2),
            mdem::cli::kOk)
      << e2.str();
}

}  // namespace
