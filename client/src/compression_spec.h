#pragma once
// The compression job's own command-line flags (mdem.v1.CompressionSpec), for `mdem run
// compression` and `mdem submit compression`; the flags every kind shares are in spec_flags.h.
#include "spec_flags.h"

namespace mdem::cli {

// Flag -> compression.* field (--grain-radius sets two).
const FlagFields& compression_flag_fields();

// Sets the compression fields the flags give on top of `spec` (which may come from --spec FILE).
// UsageError naming the flag for text that is not a finite number or not one of the names a
// flag allows; ranges are left to spec::validate, which names the field.
void apply_compression_flags(const FlagValues& f, v1::JobSpec& spec);

// The compression kind of spec_kinds().
SpecKind compression_kind();

}  // namespace mdem::cli
