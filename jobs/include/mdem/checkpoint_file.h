#pragma once
// A job's checkpoint on disk: the engine's state bytes (mdem/state_io.h) in a small envelope -
// magic, format version, the step, the payload length and its CRC-32 - written to a temporary
// file, flushed and renamed over the previous one, so a crash at any moment leaves either the old
// or the new checkpoint whole, and a damaged file is recognised instead of resumed from.
#include <stdexcept>
#include <string>

namespace mdem::server {

struct CheckpointFileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct CheckpointData {
  long step = 0;
  std::string state;  // the engine's bytes
};

// Throws CheckpointFileError naming the file and the system error (e.g. disk full).
void write_checkpoint(const std::string& path, const CheckpointData& data);
// Throws CheckpointFileError naming the file and what is wrong (missing, truncated, not a
// checkpoint, wrong version, CRC mismatch).
CheckpointData read_checkpoint(const std::string& path);

}  // namespace mdem::server
