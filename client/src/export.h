#pragma once
// Writers of a job's results for other programs: extended XYZ (ASE, OVITO), binary VTK XML
// PolyData with a .pvd collection (ParaView), and CSV of the time series. Text numbers are
// written with %.17g and binary ones as float64, so a reader gets every double back exactly.
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

// The chemical symbol written for an element kind, one ASE and OVITO accept: "C" CNT segment
// (0), "Si" nanoparticle (1), `grain` for a grain (2), "X" (ASE's dummy element) otherwise.
const char* species_of(std::int32_t kind, const char* grain);
// The symbol of a job's grains: "Au" for gold (a compression job's default material, and any job
// of another kind), "X" for cadmium sulfide or a custom material (no one element).
const char* grain_species(const JobRecord& job);

// One extended-XYZ frame: the particle count, the Properties/Time/Step line, one line per element
// that is not a wall (walls are surfaces: see write_walls_vtp).
void write_xyz_frame(std::ostream& os, const Snapshot& s, const char* grain);
// One snapshot's elements but walls as a VTK XML PolyData (.vtp) document: binary, the arrays
// appended raw and zlib-compressed; one vertex per element, one polyline per tube.
void write_vtp(std::ostream& os, const Snapshot& s);
// Whether the snapshot holds walls (platens), and the walls as a .vtp of one disc polygon each
// (the platen's radius, in its plane), with their normals as cell data.
bool has_walls(const Snapshot& s);
void write_walls_vtp(std::ostream& os, const Snapshot& s);
// The snapshot's bond network (compression's grain bonds) as a .vtp: the element file's points,
// one line per bond, its state (0 intact, 1 yielded, 2 broken) as cell data.
void write_bonds_vtp(std::ostream& os, const Snapshot& s);
// A data set of a ParaView collection: part 0 the elements, 1 the platens, 2 the bonds.
struct PvdDataSet {
  double time_ps = 0;
  int part = 0;
  std::string name;  // the part's name ("elements", "platens")
  std::string file;
};
void write_pvd(std::ostream& os, const std::vector<PvdDataSet>& datasets);
// The series as CSV: step,time_ps,<columns...>, one row per frame. Header names are unique: a
// column that repeats the frame's time (named time_ps, equal in every frame) is left out, any
// other clash gets a suffix _2, _3, ...
void write_csv(std::ostream& os, const std::vector<std::string>& columns,
               const std::vector<SeriesFrame>& frames);

// Whole-job exports, reading the store one snapshot at a time. Each returns the files written.
// xyz: one file with every snapshot as a frame. vtk: `pvd_path` (must end in .pvd) and, next to
// it, <base>_<k>.vtp, <base>_bonds_<k>.vtp when the snapshot has bonds and <base>_walls_<k>.vtp
// when it has platens, k zero-padded to at least 4 digits. csv: one file. Throw ExportError (or
// StoreError).
std::vector<std::string> export_xyz(const ResultsStore& store, const JobRecord& job,
                                    const std::string& path);
std::vector<std::string> export_vtk(const ResultsStore& store, const JobRecord& job,
                                    const std::string& pvd_path);
std::vector<std::string> export_csv(const ResultsStore& store, const JobRecord& job,
                                    const std::string& path);

}  // namespace mdem::cli
