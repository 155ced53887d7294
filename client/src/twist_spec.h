#pragma once
// The twist job's own command-line flags (mdem.v1.TwistSpec), for `mdem run twist` and `mdem
// submit twist`; the flags every kind shares are in spec_flags.h.
#include "spec_flags.h"

namespace mdem::cli {

// Flag -> twist.* field.
const FlagFields& twist_flag_fields();

// Sets the twist fields the flags give on top of `spec` (which may come from --spec FILE).
// Numbers are parsed strictly (UsageError naming the flag for text that is not a finite number
// or integer); ranges are left to spec::validate, which names the field.
void apply_twist_flags(const FlagValues& f, v1::JobSpec& spec);

// The twist kind of spec_kinds().
SpecKind twist_kind();

}  // namespace mdem::cli
