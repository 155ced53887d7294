// The tensile kind's rules (mdem.v1.TensileSpec): the Table 5-1 presets, defaults, validation and
// the film's derived counts, registered as one entry of kind_rules().
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "rules.h"

namespace mdem::spec {

namespace {

namespace d = defaults;
namespace r = ranges;
using detail::valid;
using detail::value_or;
using Tensile = mdem::v1::TensileSpec;

FilmPreset preset_of(const Tensile& t) { return film_preset(t.size()); }

double side_of(const Tensile& t) {
  return value_or(t.has_side_nm(), t.side_nm(), preset_of(t).side_nm);
}
double thickness_of(const Tensile& t) {
  return value_or(t.has_thickness_nm(), t.thickness_nm(), d::kThicknessNm);
}
double target_of(const Tensile& t) {
  return value_or(t.has_target_strain_percent(), t.target_strain_percent(),
                  d::kTargetStrainPercent);
}
double relax_of(const Tensile& t) { return value_or(t.has_relax_ps(), t.relax_ps(), d::kRelaxPs); }

// The default report points that lie within `limit`.
template <std::size_t N>
void default_points(google::protobuf::RepeatedField<double>& out, const double (&points)[N],
                    double limit) {
  if (!out.empty()) return;
  for (double p : points)
    if (p <= limit) out.Add(p);
}

double default_rate(const Tensile& t) {
  return t.mode() == mdem::v1::CYCLIC ? d::kCyclicStrainRatePerPs : d::kStrainRatePerPs;
}

void default_tensile(Tensile& t) {
  if (t.size() == mdem::v1::FILM_SIZE_UNSPECIFIED) t.set_size(mdem::v1::FILM_SMALL);
  const FilmPreset p = preset_of(t);
  if (!t.has_side_nm()) t.set_side_nm(p.side_nm);
  if (!t.has_thickness_nm()) t.set_thickness_nm(d::kThicknessNm);
  if (!t.has_tubes()) t.set_tubes(p.tubes);
  if (!t.has_segments_per_tube()) t.set_segments_per_tube(p.segments_per_tube);
  if (!t.has_max_tilt_deg()) t.set_max_tilt_deg(d::kMaxTiltDeg);
  if (!t.has_nanoparticles()) t.set_nanoparticles(d::kNanoparticles);
  if (t.np_deposit() == mdem::v1::NP_DEPOSIT_UNSPECIFIED) t.set_np_deposit(mdem::v1::AFTER_RELAX);
  if (!t.has_prerelax_max_ps()) t.set_prerelax_max_ps(d::kPrerelaxMaxPs);
  if (!t.has_relax_ps()) t.set_relax_ps(d::kRelaxPs);
  if (!t.has_vdw_damping_ratio()) t.set_vdw_damping_ratio(d::kVdwDampingRatio);
  if (!t.has_local_damping()) t.set_local_damping(d::kTensileLocalDamping);
  if (t.mode() == mdem::v1::TENSILE_MODE_UNSPECIFIED) t.set_mode(mdem::v1::MONOTONIC);
  if (!t.has_target_strain_percent()) t.set_target_strain_percent(d::kTargetStrainPercent);
  if (!t.has_strain_rate_per_ps()) t.set_strain_rate_per_ps(default_rate(t));
  if (!t.has_ramp_ps()) t.set_ramp_ps(d::kRampPs);
  if (!t.has_cycles()) t.set_cycles(d::kCycles);
  if (!t.has_amplitude_percent()) t.set_amplitude_percent(d::kAmplitudePercent);
  if (!t.has_grip_width_nm()) t.set_grip_width_nm(d::kGripWidthNm);
  if (!t.has_zero_velocities()) t.set_zero_velocities(d::kZeroVelocities);
  if (!t.has_vdw_dashpot_shear()) t.set_vdw_dashpot_shear(d::kVdwDashpotShear);
  if (t.mode() == mdem::v1::MONOTONIC)
    default_points(*t.mutable_report_strains_percent(), d::kReportStrainsPercent, target_of(t));
  default_points(*t.mutable_report_times_ps(), d::kReportTimesPs, relax_of(t));
}

// ---- validation ----

void check_enums(const Tensile& t, Checks& rep) {
  if (!mdem::v1::FilmSize_IsValid(t.size()))
    rep.add("tensile.size", std::to_string(t.size()) +
                                " is not a film size (allowed: FILM_SMALL, FILM_MEDIUM, "
                                "FILM_LARGE; unset = FILM_SMALL)");
  if (!mdem::v1::NpDeposit_IsValid(t.np_deposit()))
    rep.add("tensile.np_deposit", std::to_string(t.np_deposit()) +
                                      " is not an NP deposition (allowed: AFTER_RELAX, "
                                      "BEFORE_RELAX; unset = AFTER_RELAX)");
  if (!mdem::v1::TensileMode_IsValid(t.mode()))
    rep.add("tensile.mode", std::to_string(t.mode()) +
                                " is not a tensile mode (allowed: MONOTONIC, CYCLIC; unset = "
                                "MONOTONIC)");
}

void check_film(const Tensile& t, Checks& rep) {
  rep.real("tensile.side_nm", t.has_side_nm(), t.side_nm(), r::kSideNm);
  rep.real("tensile.thickness_nm", t.has_thickness_nm(), t.thickness_nm(), r::kThicknessNm);
  rep.integer("tensile.tubes", t.has_tubes(), t.tubes(), r::kTubes);
  rep.integer("tensile.segments_per_tube", t.has_segments_per_tube(), t.segments_per_tube(),
              r::kSegmentsPerTube);
  rep.real("tensile.max_tilt_deg", t.has_max_tilt_deg(), t.max_tilt_deg(), r::kMaxTiltDeg);
  rep.integer("tensile.nanoparticles", t.has_nanoparticles(), t.nanoparticles(), r::kNanoparticles);
}

std::string count_text(double n) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", n);
  return buf;
}

// The element count and the NPs' room, from fields valid on their own.
void check_film_counts(const Tensile& t, Checks& rep) {
  const FilmPreset p = preset_of(t);
  const bool counts_ok =
      valid(t.has_tubes(), t.tubes(), p.tubes, r::kTubes) &&
      valid(t.has_segments_per_tube(), t.segments_per_tube(), p.segments_per_tube,
            r::kSegmentsPerTube) &&
      valid(t.has_nanoparticles(), t.nanoparticles(), d::kNanoparticles, r::kNanoparticles);
  if (counts_ok) {
    const double n = tensile_element_count(t);
    if (n > kMaxTensileElements)
      rep.add("tensile", "the film would hold " + count_text(n) +
                             " elements, tubes x segments_per_tube + nanoparticles (allowed: at "
                             "most " +
                             count_text(kMaxTensileElements) +
                             "; fewer or shorter tubes, or fewer NPs)");
  }
  const bool slab_ok =
      valid(t.has_side_nm(), t.side_nm(), p.side_nm, r::kSideNm) &&
      valid(t.has_thickness_nm(), t.thickness_nm(), d::kThicknessNm, r::kThicknessNm);
  if (!slab_ok || !t.has_nanoparticles() || !contains(r::kNanoparticles, t.nanoparticles())) return;
  const double most = tensile_np_capacity(side_of(t), thickness_of(t));
  if (t.nanoparticles() > most)
    rep.add("tensile.nanoparticles",
            std::to_string(t.nanoparticles()) + " NPs cannot fit a " + number_text(side_of(t)) +
                " x " + number_text(side_of(t)) + " x " + number_text(thickness_of(t)) +
                " nm film (allowed: at most " + std::to_string(static_cast<long>(most)) +
                ", NP centres " + number_text(kNpMinSpacingNm) + " nm apart)");
}

void check_stages(const Tensile& t, Checks& rep) {
  rep.real("tensile.prerelax_max_ps", t.has_prerelax_max_ps(), t.prerelax_max_ps(),
           r::kPrerelaxMaxPs);
  rep.real("tensile.relax_ps", t.has_relax_ps(), t.relax_ps(), r::kRelaxPs);
  rep.real("tensile.vdw_damping_ratio", t.has_vdw_damping_ratio(), t.vdw_damping_ratio(),
           r::kVdwDampingRatio);
  rep.real("tensile.local_damping", t.has_local_damping(), t.local_damping(), r::kLocalDamping);
}

void check_loading(const Tensile& t, Checks& rep) {
  rep.real("tensile.target_strain_percent", t.has_target_strain_percent(),
           t.target_strain_percent(), r::kTargetStrainPercent);
  rep.real("tensile.strain_rate_per_ps", t.has_strain_rate_per_ps(), t.strain_rate_per_ps(),
           r::kStrainRatePerPs);
  rep.real("tensile.ramp_ps", t.has_ramp_ps(), t.ramp_ps(), r::kRampPs);
  rep.integer("tensile.cycles", t.has_cycles(), t.cycles(), r::kCycles);
  rep.real("tensile.amplitude_percent", t.has_amplitude_percent(), t.amplitude_percent(),
           r::kAmplitudePercent);
  const bool each_ok = valid(t.has_target_strain_percent(), t.target_strain_percent(),
                             d::kTargetStrainPercent, r::kTargetStrainPercent) &&
                       valid(t.has_strain_rate_per_ps(), t.strain_rate_per_ps(), default_rate(t),
                             r::kStrainRatePerPs) &&
                       valid(t.has_ramp_ps(), t.ramp_ps(), d::kRampPs, r::kRampPs) &&
                       valid(t.has_cycles(), t.cycles(), d::kCycles, r::kCycles) &&
                       valid(t.has_amplitude_percent(), t.amplitude_percent(), d::kAmplitudePercent,
                             r::kAmplitudePercent);
  constexpr double kMaxLoadingPs = 1e7;
  const double loading = tensile_loading_ps(t);
  if (each_ok && loading > kMaxLoadingPs)
    rep.add("tensile.strain_rate_per_ps",
            "the test would last " + count_text(loading) + " ps at this rate (allowed: at most " +
                count_text(kMaxLoadingPs) +
                " ps; a higher rate, a lower target strain or fewer cycles)");
}

void check_grips(const Tensile& t, Checks& rep) {
  rep.real("tensile.grip_width_nm", t.has_grip_width_nm(), t.grip_width_nm(), r::kGripWidthNm);
  const bool side_ok = valid(t.has_side_nm(), t.side_nm(), preset_of(t).side_nm, r::kSideNm);
  const double w = value_or(t.has_grip_width_nm(), t.grip_width_nm(), d::kGripWidthNm);
  if (side_ok && contains(r::kGripWidthNm, w) && 2.0 * w >= side_of(t))
    rep.add("tensile.grip_width_nm", number_text(w) + " nm grips meet in a " +
                                         number_text(side_of(t)) + " nm film (allowed: < " +
                                         number_text(side_of(t) / 2.0) + " nm, half of side_nm)");
}

// Each point finite and within [0, limit] (the limit's own field valid), at most
// kMaxReportPoints of them.
void check_points(const google::protobuf::RepeatedField<double>& points, const std::string& field,
                  const Range& range, Checks& rep) {
  if (static_cast<std::size_t>(points.size()) > r::kMaxReportPoints) {
    rep.add(field, std::to_string(points.size()) + " points listed (allowed: at most " +
                       std::to_string(r::kMaxReportPoints) + ")");
    return;
  }
  for (int i = 0; i < points.size(); ++i)
    rep.real(field + "[" + std::to_string(i) + "]", true, points[i], range);
}

// Points are checked against their stage's limit when that limit is valid (otherwise it is
// reported on its own: one mistake, one error).
void check_reports(const Tensile& t, Checks& rep) {
  const bool target_ok = valid(t.has_target_strain_percent(), t.target_strain_percent(),
                               d::kTargetStrainPercent, r::kTargetStrainPercent);
  const bool relax_ok = valid(t.has_relax_ps(), t.relax_ps(), d::kRelaxPs, r::kRelaxPs);
  if (t.mode() == mdem::v1::CYCLIC && !t.report_strains_percent().empty())
    rep.add("tensile.report_strains_percent",
            "is for MONOTONIC tests (allowed: empty for CYCLIC, whose report is per cycle)");
  else if (target_ok)
    check_points(t.report_strains_percent(), "tensile.report_strains_percent",
                 closed(0.0, target_of(t), "%", "target_strain_percent"), rep);
  if (relax_ok)
    check_points(t.report_times_ps(), "tensile.report_times_ps",
                 closed(0.0, relax_of(t), "ps", "relax_ps"), rep);
}

void check_tensile(const Tensile& t, Checks& rep) {
  check_enums(t, rep);
  check_film(t, rep);
  check_film_counts(t, rep);
  check_stages(t, rep);
  check_loading(t, rep);
  check_grips(t, rep);
  check_reports(t, rep);
}

}  // namespace

FilmPreset film_preset(mdem::v1::FilmSize size) {
  switch (size) {
    case mdem::v1::FILM_MEDIUM:
      return {500.0, 350, 350};
    case mdem::v1::FILM_LARGE:
      return {1000.0, 500, 700};
    default:
      return {300.0, 200, 200};
  }
}

double tensile_element_count(const mdem::v1::TensileSpec& t) {
  const FilmPreset p = film_preset(t.size());
  const double tubes = t.has_tubes() ? t.tubes() : p.tubes;
  const double segments = t.has_segments_per_tube() ? t.segments_per_tube() : p.segments_per_tube;
  const double nps = t.has_nanoparticles() ? t.nanoparticles() : d::kNanoparticles;
  return tubes * segments + nps;
}

double tensile_np_capacity(double side_nm, double thickness_nm) {
  const double s = kNpMinSpacingNm;
  return 6.0 * (side_nm + s) * (side_nm + s) * (thickness_nm + s) / (std::numbers::pi * s * s * s);
}

double tensile_loading_ps(const mdem::v1::TensileSpec& t) {
  const double rate = value_or(t.has_strain_rate_per_ps(), t.strain_rate_per_ps(), default_rate(t));
  if (t.mode() == mdem::v1::CYCLIC) {
    const double a =
        value_or(t.has_amplitude_percent(), t.amplitude_percent(), d::kAmplitudePercent) / 100.0;
    const double cycles = t.has_cycles() ? t.cycles() : d::kCycles;
    return cycles * 2.0 * a / rate;
  }
  const double ramp = value_or(t.has_ramp_ps(), t.ramp_ps(), d::kRampPs);
  const double target = target_of(t) / 100.0;
  // The ramp reaches 1/2 rate x ramp; a target below it ends on the ramp, within it.
  if (target < 0.5 * rate * ramp) return ramp;
  return 0.5 * ramp + target / rate;
}

KindRules tensile_rules() {
  return {"tensile", v1::JobSpec::kTensile,
          [](v1::JobSpec& spec) { default_tensile(*spec.mutable_tensile()); },
          [](const v1::JobSpec& spec, Checks& checks) { check_tensile(spec.tensile(), checks); }};
}

}  // namespace mdem::spec
