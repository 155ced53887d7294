#pragma once
// The tensile job's own command-line flags (mdem.v1.TensileSpec), for `mdem run tensile` and
// `mdem submit tensile`; the flags every kind shares are in spec_flags.h.
#include <string>

#include "spec_flags.h"

namespace mdem::cli {

// Flag -> tensile.* field.
const FlagFields& tensile_flag_fields();

// Sets the tensile fields the flags give on top of `spec` (which may come from --spec FILE).
// UsageError naming the flag for text that is not a finite number or integer, or not one of the
// names a flag allows; ranges are left to spec::validate, which names the field.
void apply_tensile_flags(const FlagValues& f, v1::JobSpec& spec);

// "small film 300×300×11 nm, 200 tubes × 200 segments + 2000 NPs": the film of a finalized spec.
std::string tensile_film_text(const v1::TensileSpec& t);

// The tensile kind of spec_kinds().
SpecKind tensile_kind();

}  // namespace mdem::cli
