// SpecError, defaults, finalize, the rope's derived counts and the particle's grain estimate.
#include "mdem/spec.h"

#include <climits>
#include <cmath>

#include "rules.h"

namespace mdem::spec {

namespace {

namespace d = detail::defaults;

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
}

void default_outputs(mdem::v1::Outputs& out) {
  if (!out.has_energy_every_ps()) out.set_energy_every_ps(d::kEnergyEveryPs);
  if (!out.has_snapshot_every_ps()) out.set_snapshot_every_ps(d::kSnapshotEveryPs);
}

void default_line_defect(mdem::v1::LineDefect& line) {
  if (!line.has_angle_deg()) line.set_angle_deg(d::kAngleDeg);
  if (!line.has_width()) line.set_width(d::kWidth);
  if (!line.has_length_fraction()) line.set_length_fraction(d::kLengthFraction);
}

void default_twist_loading(mdem::v1::TwistSpec& t) {
  if (!t.has_torque_nn_nm()) t.set_torque_nn_nm(d::kTorqueNnNm);
  if (!t.has_torque_rate_nn_nm_per_ps()) t.set_torque_rate_nn_nm_per_ps(d::kTorqueRate);
  if (!t.has_hold_ps()) t.set_hold_ps(d::kHoldPs);
  if (t.boundary() == mdem::v1::TWIST_BOUNDARY_UNSPECIFIED)
    t.set_boundary(mdem::v1::CONSTANT_MOMENT);
  if (t.grip_load() == mdem::v1::GRIP_LOAD_UNSPECIFIED) t.set_grip_load(mdem::v1::RIGID_GRIP);
  if (!t.has_unload()) t.set_unload(d::kUnload);
  if (!t.has_unload_hold_ps()) t.set_unload_hold_ps(d::kUnloadHoldPs);
}

void default_twist(mdem::v1::TwistSpec& t) {
  if (!t.has_layers()) t.set_layers(d::kLayers);
  if (!t.has_length_nm()) t.set_length_nm(d::kLengthNm);
  for (mdem::v1::LineDefect& line : *t.mutable_line_defects()) default_line_defect(line);
  default_twist_loading(t);
  if (!t.has_grip_segments()) t.set_grip_segments(d::kGripSegments);
  if (!t.has_vdw_damping_ratio()) t.set_vdw_damping_ratio(d::kVdwDampingRatio);
  if (!t.has_local_damping()) t.set_local_damping(d::kLocalDamping);
  if (!t.has_temperature_k()) t.set_temperature_k(d::kTemperatureK);
}

void default_compression_material(mdem::v1::CompressionSpec& c) {
  if (c.material() == mdem::v1::GRAIN_MATERIAL_UNSPECIFIED) c.set_material(mdem::v1::GOLD);
  const detail::MaterialPreset* m = detail::material_preset(c.material());
  if (c.bond() == mdem::v1::GRAIN_BOND_UNSPECIFIED &&
      mdem::v1::GrainMaterialKind_IsValid(c.material()))
    c.set_bond(m ? m->bond : mdem::v1::ELASTIC);
  if (!m) return;  // CUSTOM (or an invalid number, which validation reports)
  if (!c.has_youngs_gpa()) c.set_youngs_gpa(m->youngs_gpa);
  if (!c.has_poisson()) c.set_poisson(m->poisson);
  if (!c.has_density_g_cm3()) c.set_density_g_cm3(m->density_g_cm3);
  if (!c.has_strength_gpa()) c.set_strength_gpa(m->strength_gpa);
}

void default_compression(mdem::v1::CompressionSpec& c) {
  if (!c.has_outer_radius_nm()) c.set_outer_radius_nm(d::kOuterRadiusNm);
  if (!c.has_inner_radius_nm()) c.set_inner_radius_nm(d::kInnerRadiusNm);
  if (!c.has_grain_radius_min_nm()) c.set_grain_radius_min_nm(d::kGrainRadiusMinNm);
  if (!c.has_grain_radius_max_nm()) c.set_grain_radius_max_nm(d::kGrainRadiusMaxNm);
  if (!c.has_porosity()) c.set_porosity(d::kPorosity);
  default_compression_material(c);
  if (!c.has_platen_speed_nm_per_ps()) c.set_platen_speed_nm_per_ps(d::kPlatenSpeed);
  if (!c.has_peak_displacement_nm()) {
    // 20 % of the diameter; of the default one when the given radius is invalid (reported).
    const bool outer_ok = detail::contains(detail::ranges::kOuterRadiusNm, c.outer_radius_nm());
    c.set_peak_displacement_nm(d::kPeakPerOuterRadius *
                               (outer_ok ? c.outer_radius_nm() : d::kOuterRadiusNm));
  }
  if (!c.has_unload()) c.set_unload(d::kCompressionUnload);
  if (!c.has_viscous_ratio()) c.set_viscous_ratio(d::kViscousRatio);
  if (!c.has_local_damping()) c.set_local_damping(d::kCompressionLocalDamping);
}

}  // namespace

SpecError::SpecError(std::vector<FieldError> errors)
    : std::invalid_argument(join_errors(errors)), errors_(std::move(errors)) {}

void apply_defaults(mdem::v1::JobSpec& spec) {
  if (!spec.has_name()) spec.set_name("");
  if (!spec.has_seed()) spec.set_seed(d::kSeed);
  default_run(*spec.mutable_run());
  default_outputs(*spec.mutable_outputs());
  if (spec.has_twist()) default_twist(*spec.mutable_twist());
  if (spec.has_compression()) default_compression(*spec.mutable_compression());
}

mdem::v1::JobSpec finalize(mdem::v1::JobSpec spec) {
  apply_defaults(spec);
  std::vector<FieldError> errors = validate(spec);
  if (!errors.empty()) throw SpecError(std::move(errors));
  return spec;
}

int twist_segments(const mdem::v1::TwistSpec& twist) {
  const double length = twist.has_length_nm() ? twist.length_nm() : d::kLengthNm;
  const double segments = std::round(length / detail::kSegmentNm);
  if (!(segments >= 1)) return 1;  // also NaN
  if (segments >= INT_MAX) return INT_MAX;
  return static_cast<int>(segments);
}

int hex_tube_count(int layers) {
  if (layers < 1) return 0;
  if (layers > 100000) return INT_MAX;  // keeps 3N² within long long
  const long long n = layers;
  const long long count = 3 * n * n - 3 * n + 1;
  return count > INT_MAX ? INT_MAX : static_cast<int>(count);
}

double compression_grain_estimate(const mdem::v1::CompressionSpec& c) {
  const double outer = c.has_outer_radius_nm() ? c.outer_radius_nm() : d::kOuterRadiusNm;
  const double inner = c.has_inner_radius_nm() ? c.inner_radius_nm() : d::kInnerRadiusNm;
  const double a = c.has_grain_radius_min_nm() ? c.grain_radius_min_nm() : d::kGrainRadiusMinNm;
  const double b = c.has_grain_radius_max_nm() ? c.grain_radius_max_nm() : d::kGrainRadiusMaxNm;
  const double porosity = c.has_porosity() ? c.porosity() : d::kPorosity;
  const double mean_r3 = (a + b) * (a * a + b * b) / 4.0;
  return (1.0 - porosity) * (outer * outer * outer - inner * inner * inner) / mean_r3;
}

}  // namespace mdem::spec
