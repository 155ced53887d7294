#pragma once
// What the kinds' rules files share; the ranges and defaults themselves are in
// mdem/spec_rules.h, the registry in mdem/spec_kinds.h.
#include "mdem/spec_kinds.h"
#include "mdem/spec_rules.h"

namespace mdem::spec::detail {

// A field's value, or its default when unset.
inline double value_or(bool has, double v, double fallback) { return has ? v : fallback; }

// Whether the field's value (its default when unset) is within its range: cross-field rules
// check only fields that are valid on their own, so one mistake gives one error.
inline bool valid(bool has, double v, double fallback, const Range& range) {
  return contains(range, value_or(has, v, fallback));
}

}  // namespace mdem::spec::detail
