// The bundle job (bundle_job.h).
#include "mdem/job/bundle_job.h"

#include <stdexcept>
#include <string>

namespace mdem {
namespace {

const BundleJobSpec& validated(const BundleJobSpec& s) {
  if (s.steps < 1)
    throw std::invalid_argument("bundle steps must be >= 1, got " + std::to_string(s.steps));
  return s;
}

}  // namespace

BundleJob::BundleJob(const BundleJobSpec& spec, IntegratorSettings settings)
    : spec_(validated(spec)), sys_(make_bundle_system(spec.bundle, settings)) {
  SystemStage::Settings st;  // no protocol, no observers: the system left to itself
  st.stop = StopCondition::after_steps(spec_.steps);
  add_stage(std::make_unique<SystemStage>("bundle", *this, std::move(st)));
}

double BundleJob::duration() const { return static_cast<double>(spec_.steps) * sys_.dt(); }

std::vector<EnergyTerm> BundleJob::energy_terms() {
  std::vector<EnergyTerm> t;
  for (int k = 0; k < kEnergyTermCount; ++k) t.push_back(static_cast<EnergyTerm>(k));
  return t;
}

std::vector<std::string> BundleJob::columns() const { return energy_columns(energy_terms()); }

std::vector<double> BundleJob::observe() { return energy_values(sys_, energy_terms()); }

Summary BundleJob::summary() {
  return {{"tubes", static_cast<long>(spec_.bundle.tubes)},
          {"segments_per_tube", static_cast<long>(spec_.bundle.segments)},
          {"elements", static_cast<long>(sys_.elements().size())},
          {"simulated_ps", sys_.time()},
          {"initial_total_eV", sys_.energy().initial_total},
          {"energy_balance_error", sys_.energy_balance_error()}};
}

}  // namespace mdem
