#pragma once
// Snapshots as mdem.v1.SnapshotData, the form the daemon streams and the client reassembles.
#include "mdem/observe/snapshot.h"
#include "mdem/v1/results.pb.h"

namespace mdem {

v1::SnapshotData snapshot_to_proto(const Snapshot& s);
// Throws std::invalid_argument when the arrays disagree in length (a damaged message).
Snapshot snapshot_from_proto(const v1::SnapshotData& d);

}  // namespace mdem
