// The tensile kind in the jobs layer: TensileSpec -> TensileJob (percent -> fractions, the film's
// preset and numbers), its element bound and its summary.
#include <climits>
#include <cmath>

#include "mdem/job/tensile_job.h"
#include "mdem/job_kinds.h"
#include "mdem/spec.h"
#include "mdem/spec_job.h"
#include "mdem/spec_rules.h"

namespace mdem {

namespace {

FilmSize film_size(v1::FilmSize s) {
  switch (s) {
    case v1::FILM_MEDIUM:
      return FilmSize::Medium;
    case v1::FILM_LARGE:
      return FilmSize::Large;
    default:
      return FilmSize::Small;
  }
}

}  // namespace

TensileJobSpec tensile_job_spec(const v1::JobSpec& spec) {
  const v1::TensileSpec& t = spec.tensile();
  TensileJobSpec job;
  // The size's Table 5-1 film, with the spec's numbers (finalize filled them from the size).
  job.film = TensileFilmSpec::of_size(film_size(t.size()));
  job.film.side = t.side_nm();
  job.film.thickness = t.thickness_nm();
  job.film.tubes = t.tubes();
  job.film.segments_per_tube = t.segments_per_tube();
  job.film.max_out_of_plane_deg = t.max_tilt_deg();
  job.film.seed = spec.seed();
  job.film.nanoparticles = t.nanoparticles();
  job.nanoparticles = t.nanoparticles();
  job.np_deposit =
      t.np_deposit() == v1::BEFORE_RELAX ? NpDeposit::BeforeRelax : NpDeposit::AfterRelax;
  job.seed = spec.seed();
  job.prerelax.max_time = t.prerelax_max_ps();
  job.relax_ps = t.relax_ps();
  job.dashpot_ratio = t.vdw_damping_ratio();
  job.local_damping = t.local_damping();
  job.laws.dashpot_shear = t.vdw_dashpot_shear();
  job.mode = t.mode() == v1::CYCLIC ? TensileMode::Cyclic : TensileMode::Monotonic;
  // Strains are percent in the spec, fractions in the engine; rates 1/ps in both.
  job.monotonic.strain_rate = t.strain_rate_per_ps();
  job.monotonic.ramp_time = t.ramp_ps();
  job.monotonic.target_strain = t.target_strain_percent() / 100.0;
  job.cyclic.amplitude = t.amplitude_percent() / 100.0;
  job.cyclic.mean_rate = t.strain_rate_per_ps();
  job.cyclic.period = 0;  // from the mean rate: P = 2 amplitude / rate
  job.cyclic.cycles = t.cycles();
  job.grip_width = t.grip_width_nm();
  job.zero_velocities_at_test = t.zero_velocities();
  job.relax_report_ps.assign(t.report_times_ps().begin(), t.report_times_ps().end());
  job.test_report_strains.clear();
  for (double p : t.report_strains_percent()) job.test_report_strains.push_back(p / 100.0);
  return job;
}

JobKind tensile_job_kind() {
  JobKind k;
  k.name = "tensile";
  k.kind_case = v1::JobSpec::kTensile;
  k.build = [](const v1::JobSpec& spec, const IntegratorSettings& s) -> std::unique_ptr<Job> {
    return std::make_unique<TensileJob>(tensile_job_spec(spec), s);
  };
  k.local_damping = [](const v1::JobSpec& spec) { return spec.tensile().local_damping(); };
  // Every segment of the generated tubes and every NP: the count is exact.
  k.element_bound = [](const v1::JobSpec& spec) {
    const double n = spec::tensile_element_count(spec.tensile());
    if (!(n < 1e15)) return LONG_MAX;  // also NaN
    return static_cast<long>(std::ceil(n));
  };
  // The film itself is generated at once, but the pre-relaxation is a simulation of its own (a
  // stage, up to its cap), and a large film with NPs takes a second and hundreds of MB to build:
  // the daemon leaves it to the worker, as compression's packing.
  k.builds_quickly = false;
  // The keys TensileJob::summary() emits (engine/src/job/tensile_job.cpp). Strains, fractions
  // and shrinkage are fractions (0.02 = 2 %), as the engine reports them. Keys a run does not
  // reach (no frame in the 1-2 % window, no yield, a cyclic test's per-cycle cycle_k_* values)
  // are left out of the summary or follow the declared ones under their own names.
  using T = SummaryField::Type;
  k.summary = {
      {"segments", T::Count, "", "segments", 1, 6, true},
      {"nanoparticles", T::Count, "", "NPs", 1, 6, true},
      {"tubes", T::Count, "", "tubes", 1, 6, false},
      {"pieces", T::Count, "", "pieces", 1, 6, false},
      {"density_g_cm3", T::Real, "g/cm³", "density", 1, 4, false},
      {"porosity", T::Real, "%", "porosity", 1, 4, false, false, 100},
      {"np_deposit", T::Label, "", "NPs deposited", 2, 6, false},
      {"np_candidates", T::Count, "", "NP candidates", 2, 6, false},
      {"prerelax_reason", T::Label, "", "pre-relaxation:", 3, 6, false},
      {"prerelax_ps", T::Real, "ps", "after", 3, 6, false},
      {"prerelax_steps", T::Count, "", "steps", 3, 6, false},
      {"prerelax_dt_ps", T::Real, "ps", "dt", 3, 4, false},
      {"np_prerelax_reason", T::Label, "", "after the NPs:", 4, 6, false},
      {"np_prerelax_ps", T::Real, "ps", "after", 4, 6, false},
      {"step_origin", T::Label, "", "step of the relaxation and test:", 5, 6, false},
      {"step_dt_ps", T::Real, "ps", "dt", 5, 4, false},
      {"step_critical_measured_ps", T::Real, "ps", "measured critical step", 5, 4, false},
      {"step_over_measured", T::Real, "", "dt/measured", 5, 3, false},
      {"step_bound_ps", T::Real, "ps", "automatic bound", 5, 4, false},
      {"step_over_bound", T::Real, "", "dt/bound", 5, 3, false},
      {"relax_ps", T::Real, "ps", "relaxation", 6, 6, false},
      {"relax_stabilisation_ps", T::Real, "ps", "stabilised after", 6, 6, false, true},
      {"relax_bending_share_end", T::Real, "%", "bending share", 6, 3, false, false, 100},
      {"relax_aligned_registry_free_start", T::Count, "", "aligned pairs (registry-free) from", 7,
       6, false},
      {"relax_aligned_registry_free_end", T::Count, "", "to", 7, 6, false},
      {"relax_aligned_thesis_start", T::Count, "", "thesis count from", 7, 6, false},
      {"relax_aligned_thesis_end", T::Count, "", "to", 7, 6, false},
      {"relax_pores_gt200nm2_start", T::Count, "", "pores > 200 nm² from", 7, 6, false},
      {"relax_pores_gt200nm2_end", T::Count, "", "to", 7, 6, false},
      {"youngs_modulus_GPa", T::Real, "GPa", "Young's modulus", 8, 6, true, true},
      {"modulus_intercept_GPa", T::Real, "GPa", "intercept", 8, 6, false},
      {"yield_strain", T::Real, "%", "yield strain", 8, 4, false, true, 100},
      {"peak_stress_GPa", T::Real, "GPa", "peak stress", 8, 6, true, true},
      {"final_strain", T::Real, "%", "final strain", 8, 6, false, false, 100},
      {"grip_bridging_pieces", T::Count, "", "pieces held by both grips", 8, 6, false, true},
      {"grip_bridging_affine_modulus_GPa", T::Real, "GPa", "their affine modulus", 8, 4, false},
      {"tubes_in_tension_at_2pct", T::Real, "%", "tubes in tension at 2 %", 9, 3, false, true, 100},
      {"parents_in_tension_at_2pct", T::Real, "%", "parent tubes", 9, 3, false, false, 100},
      {"mid_width_shrinkage_end", T::Real, "%", "width shrinkage at the end", 9, 3, false, true,
       100},
      {"aligned_registry_free_test_start", T::Count, "", "test: aligned pairs (registry-free) from",
       10, 6, false},
      {"aligned_registry_free_test_end", T::Count, "", "to", 10, 6, false},
      {"aligned_thesis_test_start", T::Count, "", "thesis count from", 10, 6, false},
      {"aligned_thesis_test_end", T::Count, "", "to", 10, 6, false},
      {"pores_gt200nm2_test_start", T::Count, "", "pores > 200 nm² from", 10, 6, false},
      {"pores_gt200nm2_test_last_report", T::Count, "", "to", 10, 6, false},
      {"toughness_GJ_m3", T::Real, "GJ/m³", "toughness", 11, 6, false, true},
      {"failure_strain", T::Real, "%", "failure strain", 11, 4, false, true, 100},
      {"cycles_complete", T::Count, "", "cycles complete", 12, 6, false},
      // Printed by the run's accuracy line; kept in the JSON.
      {"energy_balance_error", T::Real, "", "energy balance error", 0, 6, false},
      {"dt_ps", T::Real, "ps", "dt", 0, 6, false},
  };
  // A cyclic test's figures, one line per cycle (cycle_k_*, k from 1, as many as a test can
  // have), then the run's own line.
  constexpr int kCycleLine = 13;
  const int max_cycles = static_cast<int>(spec::ranges::kCycles.hi);
  for (int c = 1; c <= max_cycles; ++c) {
    const std::string key = "cycle_" + std::to_string(c) + "_";
    k.summary.push_back({key + "loop_area_J_cm3", T::Real, "J/cm³",
                         "cycle " + std::to_string(c) + ": loop area", kCycleLine + c, 4, false});
    k.summary.push_back({key + "modulus_GPa", T::Real, "GPa", "modulus", kCycleLine + c, 4, false});
    k.summary.push_back({key + "phase_lead", T::Real, "% of the period", "phase lead",
                         kCycleLine + c, 3, false, false, 100});
  }
  k.summary.push_back(
      {"simulated_ps", T::Real, "ps", "simulated", kCycleLine + max_cycles + 1, 6, false});
  // The stress-strain curve: the engine's strain column is a fraction, drawn in percent.
  k.plot = {{"stress_GPa"}, "strain", 100.0, "strain (%)"};
  return k;
}

}  // namespace mdem
