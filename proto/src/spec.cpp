// SpecError, defaults, finalize, the rope's derived counts and the particle's grain estimate.
#include "mdem/spec.h"

#include "mdem/spec_kinds.h"

namespace mdem::spec {

namespace {

namespace d = defaults;

std::string join_errors(const std::vector<FieldError>& errors) {
  std::string text;
  for (const FieldError& e : errors) {
    if (!text.empty()) text += '\n';
    text += e.field + ": " + e.message;
  }
  return text;
}

void default_run(mdem::v1::RunSettings& run) {
  if (!run.has_safety()) run.set_safety(d::kSafety);
  if (!run.has_threads()) run.set_threads(d::kThreads);
  if (!run.has_respa_k()) run.set_respa_k(d::kRespaK);
}

void default_outputs(mdem::v1::Outputs& out) {
  if (!out.has_energy_every_ps()) out.set_energy_every_ps(d::kEnergyEveryPs);
  if (!out.has_snapshot_every_ps()) out.set_snapshot_every_ps(d::kSnapshotEveryPs);
}

}  // namespace

SpecError::SpecError(std::vector<FieldError> errors)
    : std::invalid_argument(join_errors(errors)), errors_(std::move(errors)) {}

void apply_defaults(mdem::v1::JobSpec& spec, const KindRulesRegistry& kinds) {
  if (!spec.has_name()) spec.set_name("");
  if (!spec.has_seed()) spec.set_seed(d::kSeed);
  default_run(*spec.mutable_run());
  default_outputs(*spec.mutable_outputs());
  if (const KindRules* kind = kinds.of(spec)) kind->apply_defaults(spec);
}

void apply_defaults(mdem::v1::JobSpec& spec) { apply_defaults(spec, kind_rules()); }

mdem::v1::JobSpec finalize(mdem::v1::JobSpec spec, const KindRulesRegistry& kinds) {
  apply_defaults(spec, kinds);
  std::vector<FieldError> errors = validate(spec, kinds);
  if (!errors.empty()) throw SpecError(std::move(errors));
  return spec;
}

mdem::v1::JobSpec finalize(mdem::v1::JobSpec spec) {
  return finalize(std::move(spec), kind_rules());
}

}  // namespace mdem::spec
