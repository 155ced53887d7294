#pragma once
// Checkpoints of a job run in this process (`mdem run KIND`), so that `mdem run --resume ID`
// continues it: the daemon's checkpoint file (mdem/checkpoint_file.h: the engine's state in a
// CRC-checked envelope, replaced atomically) with a record of what the results database held
// when it was written - the frames and snapshots stored, the (stage, step) order of the last of
// each, the thread count, the wall time so far, the spec and the log file. One file per job:
// <db dir>/checkpoints/<job id>.ckpt, written every --checkpoint-every seconds of wall time
// (default 300), at the end of every stage that another follows, and when the run is stopped
// (Ctrl-C, SIGTERM, SIGHUP); removed once the job ends otherwise (succeeded or failed).
#include <chrono>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

#include "flags.h"
#include "mdem/checkpoint_file.h"
#include "mdem/job/job.h"
#include "mdem/v1/job.pb.h"

namespace mdem::cli {

// A job that cannot be resumed; the message names what is wrong and what to do (exit code
// kUsage: nothing was run or changed).
struct ResumeError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// How often a local run checkpoints (`--checkpoint-every S`, `--no-checkpoint`).
struct CheckpointPolicy {
  static constexpr double kDefaultEverySeconds = 300;
  bool enabled = true;
  double every_s = kDefaultEverySeconds;  // wall seconds between checkpoints
};

// What the results database and the run held when a checkpoint was written.
struct LocalCheckpointRecord {
  std::string job_id;
  std::string kind;
  std::string spec_json;          // the job's spec as the database holds it
  int threads = 1;                // the system's: a bit-identical resume runs the same count
  long step = 0;                  // Job::overall_step (over all stages)
  long frames = 0;                // frames stored
  long snapshots = 0;             // snapshots stored
  long last_frame_order = -1;     // event_order(stage, step) of the last frame stored (-1: none)
  long last_snapshot_order = -1;  // of the last snapshot stored
  double wall_s = 0;              // compute time of the job so far
  std::string log;                // the run's log file ("" none)
};

// <db dir>/checkpoints/<id>.ckpt.
std::filesystem::path local_checkpoint_path(const std::string& db, const std::string& id);

// Writes the job's state and the record (creating the directory). Throws CheckpointFileError.
void write_local_checkpoint(const std::filesystem::path& path, const Job& job,
                            const LocalCheckpointRecord& record);

struct LocalCheckpoint {
  CheckpointData data;
  LocalCheckpointRecord record;
};

// Reads the checkpoint of job `id` of kind `kind` whose database spec is `spec_json`: ResumeError
// naming the file and what is wrong when it is missing, truncated, damaged, not a local run's
// checkpoint, of another job, kind or spec, or holds a value out of range (counts, orders,
// threads, wall time).
LocalCheckpoint read_local_checkpoint(const std::filesystem::path& path, const std::string& id,
                                      const std::string& kind, const std::string& spec_json);

// Loads the checkpoint's engine state into `job` (built anew from the spec): ResumeError naming
// the file and the engine's reason (another format version, scene, thread count, a non-finite or
// runaway value) otherwise.
void load_local_checkpoint(const std::filesystem::path& path, const LocalCheckpoint& checkpoint,
                           Job& job);

// --checkpoint-every S (0.01..86400 s) and --no-checkpoint, for `mdem run KIND` and `mdem run
// --resume`; UsageError when both are given.
void add_checkpoint_flags(FlagSpec& spec);
CheckpointPolicy parse_checkpoint_flags(const std::map<std::string, std::string>& given);

// The command that resumes job `id` of database `db` (with --db unless it is the default).
std::string resume_command(const std::string& id, const std::string& db);

// The line a resumed run starts with (on the terminal and in the log): where it resumed.
std::string resumed_line(const std::string& kind, const std::string& id,
                         const LocalCheckpointRecord& record, Job& job);

// A checkpoint to resume a job from (`mdem run --resume`): the file and what it holds.
struct ResumePoint {
  std::filesystem::path path;
  LocalCheckpoint checkpoint;
};

// The checkpoints of one local run: which frames and snapshots are new (a resumed run reports
// again what it reported after its checkpoint, and those already stored are skipped by
// event_order(stage, step), as the daemon does), when a checkpoint is due, and writing it.
class RunCheckpoints {
 public:
  // base: the record's job id, kind, spec, threads and log; resumed: the record resumed from.
  RunCheckpoints(const CheckpointPolicy& policy, std::filesystem::path path,
                 LocalCheckpointRecord base, const LocalCheckpointRecord* resumed);

  bool enabled() const { return policy_.enabled; }
  const std::filesystem::path& path() const { return path_; }
  // Whether the frame (snapshot) of `stage` at `step` is to be stored; counted when it is.
  bool take_frame(int stage, long step);
  bool take_snapshot(int stage, long step);
  // After a chunk of steps: a checkpoint is due when the interval has passed since the last one
  // (or the run's start), or the current stage is done and another follows.
  bool due(const Job& job) const;
  // Writes the checkpoint; every frame and snapshot taken must be stored by then. Throws
  // CheckpointFileError; the interval restarts either way.
  void write(const Job& job);
  // Wall time of the job so far: before this run and in it.
  double wall_s() const;
  // Removes the checkpoint file (the job ended for good).
  void remove() const;

 private:
  using Clock = std::chrono::steady_clock;
  CheckpointPolicy policy_;
  std::filesystem::path path_;
  LocalCheckpointRecord record_;
  long skip_frames_to_ = -1, skip_snapshots_to_ = -1;
  double wall_before_ = 0;
  Clock::time_point start_ = Clock::now(), last_ = start_;
};

}  // namespace mdem::cli
