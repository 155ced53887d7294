#pragma once
// The command-line flags that set the twist job's spec fields (mdem.v1.TwistSpec), shared by
// `mdem run twist` and `mdem submit twist`. The spec in engine terms is mdem/spec_job.h.
#include <map>
#include <string>

#include "flags.h"
#include "mdem/spec.h"
#include "mdem/v1/job.pb.h"

namespace mdem::cli {

// Flag -> dotted spec field, for `mdem run twist` and for naming a flag in an error.
const std::map<std::string, std::string>& twist_flag_fields();

// Sets the fields the flags give on top of `spec` (which may come from --spec FILE). Numbers are
// parsed strictly (UsageError naming the flag for text that is not a finite number or integer);
// ranges are left to spec::validate, which names the field.
void apply_twist_flags(const std::map<std::string, std::string>& flags, v1::JobSpec& spec);

// The flags that make a twist spec: those of twist_flag_fields() (--unload a switch) and --spec.
// A command adds its own to these.
FlagSpec twist_flag_spec();

// The finalized twist spec of parsed flags: --spec FILE (if given), the flags over it, then
// spec::finalize. Throws UsageError (a bad flag, a file of another kind) or spec::SpecError.
v1::JobSpec twist_spec_from_flags(const std::map<std::string, std::string>& given);

// A spec error as usage lines: each field, the flag that sets it, and what is allowed.
std::string describe_spec_error(const spec::SpecError& e);

// Help of the flags of twist_flag_spec() (sections Spec, Rope, Loading, Run).
extern const char* const kTwistSpecFlagsHelp;

}  // namespace mdem::cli
