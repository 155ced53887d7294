#pragma once
// The twist job's spec (mdem.v1.TwistSpec, validated) turned into the engine's terms, and the
// command-line flags that set its fields. Shared by `mdem run twist` and, later, the daemon.
#include <map>
#include <string>

#include "mdem/twist_job.h"
#include "mdem/v1/job.pb.h"

namespace mdem::cli {

struct EngineJob {
  TwistJobSpec twist;
  IntegratorSettings settings;
  JobCadence cadence;
};

// A finalized spec (spec::finalize) in engine units.
EngineJob twist_engine_job(const v1::JobSpec& spec);

// Flag -> dotted spec field, for `mdem run twist` and for naming a flag in an error.
const std::map<std::string, std::string>& twist_flag_fields();

// Sets the fields the flags give on top of `spec` (which may come from --spec FILE). Numbers are
// parsed strictly (UsageError naming the flag for text that is not a finite number or integer);
// ranges are left to spec::validate, which names the field.
void apply_twist_flags(const std::map<std::string, std::string>& flags, v1::JobSpec& spec);

}  // namespace mdem::cli
