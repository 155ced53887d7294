#pragma once
// The thermo table `mdem run` prints while a job runs (LAMMPS's "thermo" output): a header of
// named columns with units, then one row every `every_ps` of simulated time, taken from the
// job's time-series frames (so a row shows exactly what the results database stores).
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "mdem/observe/snapshot.h"

namespace mdem::cli {

// One column of the table: a name, its unit ("" for counts and ratios) and where its value comes
// from.
struct ThermoColumn {
  std::string name, unit;
  std::vector<int> sources;  // frame value indices summed for this column; empty: see below
  enum class Kind { Step, Time, Frame, BalanceError } kind = Kind::Frame;
  // The header cell: "name[unit]", or "name" without a unit.
  std::string header() const;
};

// The columns of a job with frame columns `frame_columns` (Job::columns(), units in the names):
// Step, Time[ps], each stored energy term the job has ("<term>[eV]"), kinetic[eV] (translational +
// rotational), balance_error (the system's relative energy-balance error), then the kind's key
// observables (twist: applied torque, twist angle, rope radius, Q; compression: displacement,
// force, bonds broken, fragments; another kind: every column that is not an energy).
std::vector<ThermoColumn> thermo_columns(const std::string& kind,
                                         const std::vector<std::string>& frame_columns);

// "twist_angle_deg" -> {"twist_angle", "deg"}; "applied_torque_nNnm" -> {"applied_torque",
// "nN·nm"}; "clusters" -> {"clusters", ""}.
std::pair<std::string, std::string> split_unit(const std::string& column);

class ThermoTable {
 public:
  // every_ps > 0: the row interval in simulated ps; frame_ps: the frames' interval (a frame
  // within half of it before a multiple of every_ps counts as at that multiple: frames fall on
  // whole steps).
  ThermoTable(std::vector<ThermoColumn> columns, double every_ps, double frame_ps);
  double every_ps() const { return every_ps_; }
  // The header line (no newline).
  std::string header() const;
  // Whether the frame is due a row: the first frame, and each frame whose time reaches the next
  // multiple of every_ps.
  bool due(const SeriesFrame& f) const;
  // The row of a frame (no newline); balance_error: the system's at that frame. Marks it printed.
  std::string row(const SeriesFrame& f, double balance_error);
  // The step of the last row printed (-1: none).
  long last_step() const { return last_step_; }

 private:
  std::vector<ThermoColumn> columns_;
  std::vector<int> widths_;
  double every_ps_, frame_ps_;
  long last_bin_ = -1;
  long last_step_ = -1;
};

// The default row interval: about 15 rows over `duration_ps`, rounded up to a whole multiple of
// the frame interval `frame_ps` (rows come from frames), at least one frame interval.
double default_thermo_every(double duration_ps, double frame_ps);

}  // namespace mdem::cli
