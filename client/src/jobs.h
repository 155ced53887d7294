#pragma once
// The job kinds `mdem run` knows, each in its own file.
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "flags.h"
#include "local_checkpoint.h"
#include "mdem/integrate/system.h"
#include "spec_flags.h"

namespace mdem::cli {

// `mdem run <kind>` for a kind built from a job spec (spec_kinds(): twist, compression).
int run_spec_kind(const SpecKind& kind, const std::vector<std::string>& args, std::ostream& out,
                  std::ostream& err);

// What `mdem run <kind>` was asked for, once its flags are parsed.
struct SpecRunOptions {
  v1::JobSpec spec;  // finalized
  std::string db;
  bool json = false;
  std::optional<double> thermo_every_ps;  // default: default_thermo_every
  std::optional<std::string> log;         // default: default_log_path
  bool no_log = false;
  CheckpointPolicy checkpoint;  // --checkpoint-every, --no-checkpoint
};

// Runs one finalized spec in this process as `mdem run <kind>` does (results in the database,
// the thermo table and report, or one JSON object with json); the new job's id goes to *job_id
// (when given) before anything runs. Returns kOk or kJobFailed; throws what the run's setup
// throws (a refused time step, an unwritable database or log).
// With `resume`, the job of its checkpoint continues instead (`mdem run --resume`: its id, the
// results it stored up to the checkpoint, its log appended to).
int run_spec_job(const SpecKind& kind, const SpecRunOptions& options, std::ostream& out,
                 std::ostream& err, std::string* job_id = nullptr,
                 const ResumePoint* resume = nullptr);

// `mdem run --resume ID [flags]`: continues an interrupted or stopped local job (run_resume.cpp).
int run_resume(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// Runs one `mdem run <kind>` body and turns what it throws into an exit code and a message
// prefixed with `command`: a bad flag (UsageError) or an impossible setting (ConfigError,
// std::invalid_argument) is a usage error, anything else a failed job.
int guarded_run(const std::string& command, const std::function<int()>& body, std::ostream& err);

}  // namespace mdem::cli
