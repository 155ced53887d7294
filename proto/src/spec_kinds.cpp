// The registry of the job kinds this build knows: one line per kind.
#include "mdem/spec_kinds.h"

namespace mdem::spec {

const KindRulesRegistry& kind_rules() {
  static const KindRulesRegistry kinds = {twist_rules(), compression_rules(), tensile_rules()};
  return kinds;
}

}  // namespace mdem::spec
