#include "compression_spec.h"

#include <cmath>
#include <sstream>

#include "mdem/job/compression_job.h"

namespace mdem::cli {

const FlagFields& compression_flag_fields() {
  static const FlagFields m = {
      {"--outer-radius", "compression.outer_radius_nm"},
      {"--inner-radius", "compression.inner_radius_nm"},
      {"--grain-radius", "compression.grain_radius_min_nm"},
      {"--grain-radius", "compression.grain_radius_max_nm"},
      {"--porosity", "compression.porosity"},
      {"--material", "compression.material"},
      {"--youngs", "compression.youngs_gpa"},
      {"--poisson", "compression.poisson"},
      {"--density", "compression.density_g_cm3"},
      {"--bond", "compression.bond"},
      {"--strength", "compression.strength_gpa"},
      {"--speed", "compression.platen_speed_nm_per_ps"},
      {"--peak", "compression.peak_displacement_nm"},
      {"--no-unload", "compression.unload"},
      {"--viscous-ratio", "compression.viscous_ratio"},
      {"--local-damping", "compression.local_damping"},
  };
  return m;
}

void apply_compression_flags(const FlagValues& f, v1::JobSpec& spec) {
  v1::CompressionSpec& c = *spec.mutable_compression();
  auto has = [&](const char* k) { return f.count(k) > 0; };
  auto num = [&](const char* k) { return spec_number(k, f.at(k)); };
  if (has("--outer-radius")) c.set_outer_radius_nm(num("--outer-radius"));
  if (has("--inner-radius")) c.set_inner_radius_nm(num("--inner-radius"));
  if (has("--grain-radius")) {
    const std::string& text = f.at("--grain-radius");
    const std::vector<std::string> p = split(text, ',');
    if (p.empty() || p.size() > 2 || text.back() == ',')
      throw UsageError("--grain-radius: '" + text +
                       "' is not MIN,MAX or one radius R for all grains (e.g. 3,6)");
    c.set_grain_radius_min_nm(spec_number("--grain-radius", p.front()));
    c.set_grain_radius_max_nm(spec_number("--grain-radius", p.back()));
  }
  if (has("--porosity")) c.set_porosity(num("--porosity"));
  if (has("--material"))
    c.set_material(choice<v1::GrainMaterialKind>(
        "--material", f.at("--material"),
        {{"gold", v1::GOLD}, {"cds", v1::CADMIUM_SULFIDE}, {"custom", v1::CUSTOM}}));
  if (has("--youngs")) c.set_youngs_gpa(num("--youngs"));
  if (has("--poisson")) c.set_poisson(num("--poisson"));
  if (has("--density")) c.set_density_g_cm3(num("--density"));
  if (has("--bond"))
    c.set_bond(choice<v1::GrainBondKind>(
        "--bond", f.at("--bond"),
        {{"elastic", v1::ELASTIC}, {"plastic", v1::PLASTIC}, {"brittle", v1::BRITTLE}}));
  if (has("--strength")) c.set_strength_gpa(num("--strength"));
  if (has("--speed")) c.set_platen_speed_nm_per_ps(num("--speed"));
  if (has("--peak")) c.set_peak_displacement_nm(num("--peak"));
  if (has("--no-unload")) c.set_unload(false);
  if (has("--viscous-ratio")) c.set_viscous_ratio(num("--viscous-ratio"));
  if (has("--local-damping")) c.set_local_damping(num("--local-damping"));
}

namespace {

// Ranges and defaults from the spec rules (mdem/spec_rules.h).
std::string compression_flags_help() {
  namespace r = spec::ranges;
  namespace d = spec::defaults;
  const std::string max_grains = std::to_string(static_cast<long>(spec::kMaxCompressionGrains));
  return "Particle:\n" +
         flag_help("--outer-radius NM", "outer radius R1", r::kOuterRadiusNm,
                   default_of(d::kOuterRadiusNm)) +
         "  --inner-radius NM    inner radius R2 of a shell, 0 <= R2 < R1 (default " +
         default_of(d::kInnerRadiusNm) +
         ": a full sphere)\n"
         "  --grain-radius MIN,MAX  grain radii, uniform in [MIN, MAX], each in\n"
         "                       " +
         spec::interval_text(r::kGrainRadiusNm) + ", and 2 x MAX <= R1 - R2 (default " +
         default_of(d::kGrainRadiusMinNm) + "," + default_of(d::kGrainRadiusMaxNm) +
         "; one value R: all grains R)\n" +
         flag_help("--porosity X", "target porosity", r::kPorosity, default_of(d::kPorosity)) +
         "                       at most " + max_grains +
         " grains, (1 - porosity) x shell volume / mean grain volume\n"
         "  --material M         gold (default: E 79 GPa, nu 0.46, 19.3 g/cm3), cds (cadmium\n"
         "                       sulfide: E 28 GPa, nu 0.46, 4.82 g/cm3) or custom (give "
         "--youngs,\n"
         "                       --poisson and --density)\n" +
         flag_help("--youngs GPA", "Young's modulus", r::kYoungsGpa, "the material's") +
         flag_help("--poisson X", "Poisson's ratio", r::kPoisson, "the material's") +
         flag_help("--density G_CM3", "density", r::kDensity, "the material's") +
         "  --bond B             elastic, plastic (yield at --strength, shear at half of it) or\n"
         "                       brittle (break at --strength, shear at half of it); default the\n"
         "                       material's: plastic for gold, brittle for cds, elastic for "
         "custom\n" +
         flag_help("--strength GPA", "bond yield (plastic) or failure (brittle) stress",
                   r::kStrengthGpa, "") +
         "                       (default 8 for gold, 4 for cds; required for custom plastic or\n"
         "                       brittle bonds)\n"
         "Loading:\n" +
         flag_help("--speed X", "speed of each platen", r::kPlatenSpeed,
                   default_of(d::kPlatenSpeed)) +
         "                       (the approach rate is twice it)\n"
         "  --peak NM            peak displacement h, the platens' total approach, (0, 2 x R1) nm\n"
         "                       (default " +
         default_of(d::kPeakPerOuterRadius) +
         " x R1, 20 % of the diameter)\n"
         "  --no-unload          stop at the peak (default: return the platens to the start)\n" +
         flag_help("--viscous-ratio X", "normal dashpot ratio on bonds and contacts, 0 = none",
                   r::kViscousRatio, default_of(d::kViscousRatio)) +
         flag_help("--local-damping X", "PFC local damping", r::kLocalDamping,
                   default_of(d::kCompressionLocalDamping));
}

constexpr const char* kCompressionAbout =
    "Crushes a nanocrystalline particle between two flat platens (thesis Ch. 6): grains with\n"
    "radii uniform in --grain-radius fill a sphere or shell to --porosity at random (seeded\n"
    "by --seed), are packed, bonded to every touching neighbour, and compressed by platens\n"
    "that approach at --speed each to a total approach --peak, then return. Reports the\n"
    "force-displacement curve, bonds yielded and broken, fragments and grain slip.\n";

std::string describe_compression(Job& job, const v1::JobSpec& spec) {
  auto* comp = dynamic_cast<CompressionJob*>(&job);
  if (!comp) return {};
  const v1::CompressionSpec& c = spec.compression();
  std::ostringstream o;
  // The particle is packed by the job's first stage: its figures are known once it ran.
  if (comp->built())
    o << comp->packing().grains.size() << " grains, " << comp->bonds().bonds().size()
      << " bonds, porosity " << comp->packing().porosity << "; ";
  o << "platens at " << c.platen_speed_nm_per_ps() << " nm/ps to h = " << c.peak_displacement_nm()
    << " nm" << (c.unload() ? " and back" : "") << ", " << job.duration() << " ps";
  return o.str();
}

std::string building_compression(const v1::JobSpec& spec) {
  const v1::CompressionSpec& c = spec.compression();
  std::ostringstream o;
  o << "packing about " << std::lround(spec::compression_grain_estimate(c)) << " grains in a "
    << (c.inner_radius_nm() > 0 ? "shell of radii " : "sphere of radius ");
  if (c.inner_radius_nm() > 0) o << c.inner_radius_nm() << "/";
  o << c.outer_radius_nm() << " nm";
  return o.str();
}

}  // namespace

SpecKind compression_kind() {
  return {"compression",
          v1::JobSpec::kCompression,
          compression_flag_fields,
          {"--no-unload"},
          apply_compression_flags,
          kCompressionAbout,
          compression_flags_help(),
          describe_compression,
          building_compression};
}

}  // namespace mdem::cli
