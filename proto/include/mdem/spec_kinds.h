#pragma once
// The proto layer's registry of job kinds: for each kind its name (JobSpec's oneof field), its
// defaults and its validation rules. apply_defaults, validate and finalize handle the common
// fields (name, seed, run, outputs) and hand the kind's own message to its entry; a new kind is
// its own rules file and one line in builtin_kind_rules() (proto/src/spec_kinds.cpp).
#include <functional>
#include <string>
#include <vector>

#include "mdem/kind_registry.h"
#include "mdem/spec.h"
#include "mdem/spec_rules.h"

namespace mdem::spec {

// Collects a spec's errors, each under its dotted field path; real() and integer() check one
// optional scalar against its Range.
class Checks {
 public:
  void add(std::string field, std::string message);
  void real(const std::string& field, bool has, double v, const Range& range);
  void integer(const std::string& field, bool has, long long v, const Range& range);
  std::vector<FieldError> take() { return std::move(errors_); }

 private:
  std::vector<FieldError> errors_;
};

struct KindRules {
  std::string name;  // "twist": JobSpec's oneof field, the CLI's word, the report's "kind"
  v1::JobSpec::KindCase kind_case;
  // Fills the kind's unset fields with their defaults (the spec holds this kind).
  std::function<void(v1::JobSpec&)> apply_defaults;
  // Adds every problem of the kind's fields (the spec holds this kind).
  std::function<void(const v1::JobSpec&, Checks&)> validate;
};

using KindRulesRegistry = KindRegistry<KindRules>;

// The kinds this build knows: twist, compression, tensile.
const KindRulesRegistry& kind_rules();
KindRules twist_rules();
KindRules compression_rules();
KindRules tensile_rules();

// apply_defaults, validate and finalize over another registry (a test's own kinds).
void apply_defaults(v1::JobSpec& spec, const KindRulesRegistry& kinds);
std::vector<FieldError> validate(const v1::JobSpec& spec, const KindRulesRegistry& kinds);
v1::JobSpec finalize(v1::JobSpec spec, const KindRulesRegistry& kinds);

}  // namespace mdem::spec
