#pragma once
// The bundle job (`mdem run bundle`): the bundle scene (bundle_scene.h), vibrating and spinning
// without loads or damping, run for a number of steps. The engine's energy-conservation check as
// an ordinary job: progress, cancellation and checkpoints like every other.
#include "mdem/job/job.h"
#include "mdem/scene/bundle_scene.h"

namespace mdem {

struct BundleJobSpec {
  BundleSpec bundle;
  long steps = 20000;  // >= 1
};

class BundleJob final : public Job {
 public:
  // Throws std::invalid_argument for an impossible bundle (make_bundle_system) or steps < 1.
  BundleJob(const BundleJobSpec& spec, IntegratorSettings settings);
  BundleJob(const BundleJob&) = delete;
  BundleJob& operator=(const BundleJob&) = delete;

  std::string_view kind() const override { return "bundle"; }
  System& system() override { return sys_; }
  // steps × dt (0 until the system is initialized and dt known).
  double duration() const override;
  // Every stored energy term, then the kinetic, work, dissipated, total and residual columns.
  std::vector<std::string> columns() const override;
  std::vector<double> observe() override;
  // tubes, segments_per_tube, elements, simulated_ps, initial_total_eV, energy_balance_error.
  Summary summary() override;
  const BundleJobSpec& spec() const { return spec_; }

 private:
  static std::vector<EnergyTerm> energy_terms();
  BundleJobSpec spec_;
  System sys_;
};

}  // namespace mdem
