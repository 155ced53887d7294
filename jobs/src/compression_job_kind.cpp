// The compression kind in the jobs layer: CompressionSpec -> CompressionJob, its element bound
// and its summary.
#include <climits>
#include <cmath>

#include "mdem/core/units.h"
#include "mdem/job/compression_job.h"
#include "mdem/job_kinds.h"
#include "mdem/spec.h"
#include "mdem/spec_job.h"

namespace mdem {

CompressionJobSpec compression_job_spec(const v1::JobSpec& spec) {
  const v1::CompressionSpec& c = spec.compression();
  CompressionJobSpec job;
  PackingSpec& p = job.particle;
  p.shape = PackingShape::Shell;
  p.r_outer = c.outer_radius_nm();
  p.r_inner = c.inner_radius_nm();
  p.grain_r_min = c.grain_radius_min_nm();
  p.grain_r_max = c.grain_radius_max_nm();
  p.target_porosity = c.porosity();
  p.material.youngs = units::GPa(c.youngs_gpa());
  p.material.poisson = c.poisson();
  p.material.density =
      c.density_g_cm3() * units::kGramPerCm3InAmuPerNm3 * units::kAmu;  // g/cm³ -> internal
  p.seed = spec.seed();
  job.bond.material = p.material;
  switch (c.bond()) {
    case v1::PLASTIC:
      job.bond.behaviour = BondBehaviour::Plastic;
      break;
    case v1::BRITTLE:
      job.bond.behaviour = BondBehaviour::Brittle;
      break;
    default:
      job.bond.behaviour = BondBehaviour::Elastic;
  }
  // Unused by elastic bonds (a CUSTOM material's elastic bond may have none).
  job.bond.strength = c.has_strength_gpa() ? units::GPa(c.strength_gpa()) : 0.0;
  job.loading.speed = c.platen_speed_nm_per_ps();
  job.loading.peak_displacement = c.peak_displacement_nm();
  job.loading.unload = c.unload();
  job.viscous_ratio = c.viscous_ratio();
  return job;
}

JobKind compression_job_kind() {
  JobKind k;
  k.name = "compression";
  k.kind_case = v1::JobSpec::kCompression;
  k.build = [](const v1::JobSpec& spec, const IntegratorSettings& s) -> std::unique_ptr<Job> {
    return std::make_unique<CompressionJob>(compression_job_spec(spec), s);
  };
  k.local_damping = [](const v1::JobSpec& spec) { return spec.compression().local_damping(); };
  // The grain estimate (its random count stays within 1 % + 10 of it) and the two platens.
  k.element_bound = [](const v1::JobSpec& spec) {
    const double n = spec::compression_grain_estimate(spec.compression());
    if (!(n < 1e15)) return LONG_MAX;  // also NaN
    return static_cast<long>(std::ceil(1.01 * n + 10)) + 2;
  };
  k.builds_quickly = false;  // packing the grains is a simulation of its own
  // Results (the last flag): peak force, loading stiffness, residual flattening, bonds broken.
  k.summary = {
      {"grains", SummaryField::Type::Count, "", "grains", 1, 6, true},
      {"bonds", SummaryField::Type::Count, "", "bonds", 1, 6, false},
      {"rattlers", SummaryField::Type::Count, "", "rattlers", 1, 6, false},
      {"porosity", SummaryField::Type::Real, "", "porosity", 1, 6, false},
      {"porosity_error", SummaryField::Type::Real, "", "porosity error", 1, 6, false},
      {"packing_steps", SummaryField::Type::Count, "", "packing steps", 2, 6, false},
      {"packing_unbalanced_ratio", SummaryField::Type::Real, "", "unbalanced ratio", 2, 6, false},
      {"packing_wall_shift_nm", SummaryField::Type::Real, "nm", "wall shift", 2, 6, false},
      {"peak_force_nN", SummaryField::Type::Real, "nN", "peak force", 3, 6, true, true},
      {"peak_force_displacement_nm", SummaryField::Type::Real, "nm", "at h", 3, 6, false},
      {"loading_stiffness_nN_per_nm", SummaryField::Type::Real, "nN/nm", "loading stiffness", 3, 6,
       false, true},
      {"final_force_nN", SummaryField::Type::Real, "nN", "final force", 4, 6, false},
      {"final_displacement_nm", SummaryField::Type::Real, "nm", "at h", 4, 6, false},
      {"residual_height_loss_nm", SummaryField::Type::Real, "nm", "residual height loss", 4, 6,
       false, true},
      {"bonds_intact", SummaryField::Type::Count, "", "bonds intact", 5, 6, false},
      {"bonds_yielded", SummaryField::Type::Count, "", "yielded", 5, 6, false},
      {"bonds_broken", SummaryField::Type::Count, "", "broken", 5, 6, false, true},
      {"fragments", SummaryField::Type::Count, "", "fragments", 5, 6, false},
      {"slip_max_nm", SummaryField::Type::Real, "nm", "grain slip max", 6, 6, false},
      {"slip_mean_nm", SummaryField::Type::Real, "nm", "mean", 6, 6, false},
      // The run's accuracy line ("energy balance error ..., dt ... fs = ... x critical step") says
      // these already: kept in the JSON, not printed twice.
      {"energy_balance_error", SummaryField::Type::Real, "", "energy balance error", 0, 6, false},
      {"dt_ps", SummaryField::Type::Real, "ps", "dt", 0, 6, false},
      {"critical_dt_ps", SummaryField::Type::Real, "ps", "critical dt", 0, 6, false},
      {"simulated_ps", SummaryField::Type::Real, "ps", "simulated", 7, 6, false},
  };
  return k;
}

}  // namespace mdem
