#pragma once
// A test hook for faults of the data directory's disk, off unless the environment names a file:
// with MDEMD_FAULT_FILE=PATH set when mdemd starts, every write to the data directory (the event
// log, checkpoints, the storage probe) fails as on a full disk while PATH exists, and works again
// once it is removed. It lets a test show what a full disk does where it cannot mount a small
// filesystem; with the variable unset (always, in production) it costs one branch.
#include <optional>
#include <string>

namespace mdem::server {

// The injected failure's message while the fault is on; nothing otherwise.
std::optional<std::string> injected_write_failure();

}  // namespace mdem::server
