#pragma once
// What a job records over time: a snapshot of every element (for OVITO/ParaView), and frames of
// named scalar series (energies and a protocol's observables), independent of any storage.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "mdem/core/elements.h"

namespace mdem {

// What a bond of a snapshot is in: intact (elastic), yielded (has flowed plastically at least
// once, still holding) or broken for good.
enum class BondState : std::int32_t { Intact = 0, Yielded = 1, Broken = 2 };

// A bond between elements i and j (indices into the snapshot's arrays).
struct SnapshotBond {
  std::int32_t i = 0, j = 0;
  BondState state = BondState::Intact;
};

// The state of all elements at one time, with per-element scalars for colouring.
struct Snapshot {
  long step = 0;
  double time_ps = 0;
  std::vector<Vec3> x;  // nm
  std::vector<Quat> q;  // body -> world; a CNT segment's axis is body x
  std::vector<Vec3> v;  // nm/ps; empty when not recorded (snapshots of an older mdem)
  std::vector<double> radius;
  std::vector<std::int32_t> kind;  // ElementKind as an integer
  std::vector<std::int32_t> tube;  // -1 when not a CNT segment
  std::vector<std::int32_t> index;
  // Named per-element values, each of size() entries (e.g. "force_nN").
  std::vector<std::pair<std::string, std::vector<double>>> scalars;
  // The bond network of a job that has one whose bonds yield or break (a compression job's grain
  // bonds); empty otherwise (a CNT's bonds follow its tube and index).
  std::vector<SnapshotBond> bonds;

  std::size_t size() const { return x.size(); }
};

// Captures positions, orientations, velocities and ids, plus "force_nN" (|internal force|, nN) and
// "torque_nNnm" (|internal torque|, nN·nm) of the last force evaluation.
Snapshot capture_snapshot(const Elements& el, long step, double time_ps);

// One row of a job's time series: values in the order of the job's column names.
struct SeriesFrame {
  long step = 0;
  double time_ps = 0;
  std::vector<double> values;
};

}  // namespace mdem
