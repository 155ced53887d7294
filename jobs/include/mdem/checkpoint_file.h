#pragma once
// A job's checkpoint on disk, as mdemd and `mdem run` write it: the engine's state bytes
// (mdem/io/state_io.h) in a small envelope - magic, format version, the step, the payload length
// and its CRC-32 - written to a temporary file, flushed and renamed over the previous one, so a
// crash at any moment leaves either the old or the new checkpoint whole, and a damaged file is
// recognised instead of resumed from.
//
// Format 1: magic "MDEMCKPT", u32 version, u64 step, u64 state length, u32 CRC-32 of the state,
// then the state. Format 2 (written when the caller keeps a record beside the state, as a local
// run does: what it had stored when the checkpoint was taken) adds u64 record length and u32
// CRC-32 of the record after those fields, and the record after the state. All little-endian.
// A checkpoint without a record is written as format 1, so the daemon's files are unchanged.
#include <stdexcept>
#include <string>

namespace mdem {

struct CheckpointFileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct CheckpointData {
  long step = 0;
  std::string state;   // the engine's bytes
  std::string record;  // the caller's bookkeeping ("" none)
};

// Throws CheckpointFileError naming the file and the system error (e.g. disk full).
void write_checkpoint(const std::string& path, const CheckpointData& data);
// Throws CheckpointFileError naming the file and what is wrong (missing, truncated, not a
// checkpoint, wrong version, CRC mismatch).
CheckpointData read_checkpoint(const std::string& path);

}  // namespace mdem
