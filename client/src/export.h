#pragma once
// Writers of a job's results for other programs: extended XYZ (OVITO), VTK XML PolyData with a
// .pvd collection (ParaView), and CSV of the time series. Numbers are written with %.17g, so a
// reader gets every double back exactly.
#include <cstdint>
#include <ostream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "mdem/observe/snapshot.h"
#include "results_store.h"

namespace mdem::cli {

// An output file that cannot be written; the message names it (exit code kJobFailed).
struct ExportError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Species written for an element kind: "C" CNT segment (0), "Si" nanoparticle (1), "G" grain
// (2), "X" anything else.
const char* species_of(std::int32_t kind);

// One extended-XYZ frame: the element count, the Properties/Time/Step line, one line per element.
void write_xyz_frame(std::ostream& os, const Snapshot& s);
// One snapshot as a VTK XML PolyData (.vtp) document, ASCII.
void write_vtp(std::ostream& os, const Snapshot& s);
// A ParaView collection (.pvd) of (time_ps, file name) data sets.
void write_pvd(std::ostream& os, const std::vector<std::pair<double, std::string>>& datasets);
// The series as CSV: step,time_ps,<columns...>, one row per frame.
void write_csv(std::ostream& os, const std::vector<std::string>& columns,
               const std::vector<SeriesFrame>& frames);

// Whole-job exports, reading the store one snapshot at a time. Each returns the files written.
// xyz: one file with every snapshot as a frame. vtk: `pvd_path` (must end in .pvd) and
// <base>_<k>.vtp next to it. csv: one file. Throw ExportError (or StoreError).
std::vector<std::string> export_xyz(const ResultsStore& store, const JobRecord& job,
                                    const std::string& path);
std::vector<std::string> export_vtk(const ResultsStore& store, const JobRecord& job,
                                    const std::string& pvd_path);
std::vector<std::string> export_csv(const ResultsStore& store, const JobRecord& job,
                                    const std::string& path);

}  // namespace mdem::cli
