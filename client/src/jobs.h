#pragma once
// The job kinds `mdem run` knows, each in its own file.
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "flags.h"
#include "mdem/integrate/system.h"
#include "spec_flags.h"

namespace mdem::cli {

// `mdem run <kind>` for a kind built from a job spec (spec_kinds(): twist, compression).
int run_spec_kind(const SpecKind& kind, const std::vector<std::string>& args, std::ostream& out,
                  std::ostream& err);

// Runs one `mdem run <kind>` body and turns what it throws into an exit code and a message
// prefixed with `command`: a bad flag (UsageError) or an impossible setting (ConfigError,
// std::invalid_argument) is a usage error, anything else a failed job.
int guarded_run(const std::string& command, const std::function<int()>& body, std::ostream& err);

}  // namespace mdem::cli
