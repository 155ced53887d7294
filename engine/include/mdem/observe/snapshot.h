#pragma once
// What a job records over time: a snapshot of every element (for OVITO/ParaView), and frames of
// named scalar series (energies and a protocol's observables), independent of any storage.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "mdem/core/elements.h"

namespace mdem {

// The state of all elements at one time, with per-element scalars for colouring.
struct Snapshot {
  long step = 0;
  double time_ps = 0;
  std::vector<Vec3> x;  // nm
  std::vector<Quat> q;  // body -> world; a CNT segment's axis is body x
  std::vector<double> radius;
  std::vector<std::int32_t> kind;  // ElementKind as an integer
  std::vector<std::int32_t> tube;  // -1 when not a CNT segment
  std::vector<std::int32_t> index;
  // Named per-element values, each of size() entries (e.g. "force_nN").
  std::vector<std::pair<std::string, std::vector<double>>> scalars;

  std::size_t size() const { return x.size(); }
};

// Captures positions, orientations and ids, plus "force_nN" (|internal force|, nN) and
// "torque_nNnm" (|internal torque|, nN·nm) of the last force evaluation.
Snapshot capture_snapshot(const Elements& el, long step, double time_ps);

// One row of a job's time series: values in the order of the job's column names.
struct SeriesFrame {
  long step = 0;
  double time_ps = 0;
  std::vector<double> values;
};

}  // namespace mdem
