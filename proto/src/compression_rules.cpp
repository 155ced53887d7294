// The compression kind's rules (mdem.v1.CompressionSpec): material presets, defaults, validation
// and the grain estimate, registered as one entry of kind_rules().
#include <cmath>
#include <cstdio>
#include <string>

#include "rules.h"

namespace mdem::spec {

namespace {

namespace d = defaults;
namespace r = ranges;
using detail::valid;
using detail::value_or;
using Report = Checks;

// The preset grain materials of a compression job, in user units; nullptr for CUSTOM or a
// number that names no material.
struct MaterialPreset {
  double youngs_gpa;
  double poisson;
  double density_g_cm3;
  double strength_gpa;  // sigma_y of Au's plastic bonds, sigma_f of CdS's brittle ones
  mdem::v1::GrainBondKind bond;
};

const MaterialPreset* material_preset(mdem::v1::GrainMaterialKind kind) {
  // scenes.md compression: Au E = 79 GPa, nu = 0.46, 19.3 g/cm3, plastic sigma_y 2-8 GPa;
  // CdS E = 28 GPa, nu = 0.46, 4.82 g/cm3, brittle sigma_f = 4 GPa.
  static constexpr MaterialPreset kGold{79.0, 0.46, 19.3, 8.0, mdem::v1::PLASTIC};
  static constexpr MaterialPreset kCadmiumSulfide{28.0, 0.46, 4.82, 4.0, mdem::v1::BRITTLE};
  switch (kind) {
    case mdem::v1::GOLD:
    case mdem::v1::GRAIN_MATERIAL_UNSPECIFIED:
      return &kGold;
    case mdem::v1::CADMIUM_SULFIDE:
      return &kCadmiumSulfide;
    default:
      return nullptr;
  }
}

void default_compression_material(mdem::v1::CompressionSpec& c) {
  if (c.material() == mdem::v1::GRAIN_MATERIAL_UNSPECIFIED) c.set_material(mdem::v1::GOLD);
  const MaterialPreset* m = material_preset(c.material());
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
    const bool outer_ok = contains(r::kOuterRadiusNm, c.outer_radius_nm());
    c.set_peak_displacement_nm(d::kPeakPerOuterRadius *
                               (outer_ok ? c.outer_radius_nm() : d::kOuterRadiusNm));
  }
  if (!c.has_unload()) c.set_unload(d::kCompressionUnload);
  if (!c.has_viscous_ratio()) c.set_viscous_ratio(d::kViscousRatio);
  if (!c.has_local_damping()) c.set_local_damping(d::kCompressionLocalDamping);
}

// ---- validation ----

using Compression = mdem::v1::CompressionSpec;

double outer_of(const Compression& c) {
  return value_or(c.has_outer_radius_nm(), c.outer_radius_nm(), d::kOuterRadiusNm);
}
double inner_of(const Compression& c) {
  return value_or(c.has_inner_radius_nm(), c.inner_radius_nm(), d::kInnerRadiusNm);
}
double rmin_of(const Compression& c) {
  return value_or(c.has_grain_radius_min_nm(), c.grain_radius_min_nm(), d::kGrainRadiusMinNm);
}
double rmax_of(const Compression& c) {
  return value_or(c.has_grain_radius_max_nm(), c.grain_radius_max_nm(), d::kGrainRadiusMaxNm);
}
bool outer_ok(const Compression& c) {
  return valid(c.has_outer_radius_nm(), c.outer_radius_nm(), d::kOuterRadiusNm, r::kOuterRadiusNm);
}
bool inner_ok(const Compression& c) {
  return valid(c.has_inner_radius_nm(), c.inner_radius_nm(), d::kInnerRadiusNm, r::kInnerRadiusNm);
}
bool radii_ok(const Compression& c) {
  return valid(c.has_grain_radius_min_nm(), c.grain_radius_min_nm(), d::kGrainRadiusMinNm,
               r::kGrainRadiusNm) &&
         valid(c.has_grain_radius_max_nm(), c.grain_radius_max_nm(), d::kGrainRadiusMaxNm,
               r::kGrainRadiusNm);
}

// Inner radius below the outer; a grain fits across the shell's wall; min <= max.
void check_particle_shape(const Compression& c, Report& rep) {
  const double outer = outer_of(c), inner = inner_of(c), rmin = rmin_of(c), rmax = rmax_of(c);
  if (outer_ok(c) && inner_ok(c) && inner >= outer)
    rep.add("compression.inner_radius_nm",
            number_text(inner) + " is not below the outer radius (allowed: >= 0 and < " +
                number_text(outer) + " nm, outer_radius_nm; 0 = a full sphere)");
  if (!radii_ok(c)) return;
  if (rmin > rmax)
    rep.add("compression.grain_radius_min_nm",
            number_text(rmin) + " is above grain_radius_max_nm (allowed: <= " + number_text(rmax) +
                " nm, grain_radius_max_nm)");
  if (outer_ok(c) && inner_ok(c) && inner < outer && 2.0 * rmax > outer - inner)
    rep.add("compression.grain_radius_max_nm",
            number_text(rmax) + " nm grains do not fit in the shell's wall of " +
                number_text(outer - inner) +
                " nm (allowed: <= " + number_text((outer - inner) / 2.0) +
                " nm, half of outer_radius_nm - inner_radius_nm)");
}

// The grain count from volume, porosity and grain size, before anything is built.
void check_grain_count(const Compression& c, Report& rep) {
  const bool porosity_ok = valid(c.has_porosity(), c.porosity(), d::kPorosity, r::kPorosity);
  if (!outer_ok(c) || !inner_ok(c) || !radii_ok(c) || !porosity_ok) return;
  if (inner_of(c) >= outer_of(c) || rmin_of(c) > rmax_of(c)) return;
  // The packing draws grains while their volume stays within half a grain of the target: the
  // largest grain must fit in that way, or the particle may hold none.
  const double outer = outer_of(c), inner = inner_of(c), rmax = rmax_of(c);
  const double porosity = value_or(c.has_porosity(), c.porosity(), d::kPorosity);
  if ((1.0 - porosity) * (outer * outer * outer - inner * inner * inner) < 0.5 * rmax * rmax * rmax)
    return rep.add("compression",
                   "the particle would hold no grain: (1 - porosity) x shell "
                   "volume is below half the volume of a grain of "
                   "grain_radius_max_nm (allowed: a larger particle, a lower "
                   "porosity or smaller grains)");
  const double n = compression_grain_estimate(c);
  if (n <= kMaxCompressionGrains) return;
  char count[32];
  std::snprintf(count, sizeof count, "%.3g", n);
  rep.add("compression", std::string("the particle would hold about ") + count +
                             " grains, (1 - porosity) x shell volume / mean grain volume "
                             "(allowed: at most " +
                             std::to_string(static_cast<long>(kMaxCompressionGrains)) +
                             " grains; make the particle smaller or the grains larger)");
}

void check_material(const Compression& c, Report& rep) {
  if (!mdem::v1::GrainMaterialKind_IsValid(c.material()))
    rep.add("compression.material",
            std::to_string(c.material()) +
                " is not a grain material (allowed: GOLD, CADMIUM_SULFIDE, CUSTOM; unset = GOLD)");
  const bool custom = c.material() == mdem::v1::CUSTOM;
  struct Field {
    const char* name;
    bool has;
    double v;
    const Range& range;
  };
  for (const Field& f :
       {Field{"youngs_gpa", c.has_youngs_gpa(), c.youngs_gpa(), r::kYoungsGpa},
        Field{"poisson", c.has_poisson(), c.poisson(), r::kPoisson},
        Field{"density_g_cm3", c.has_density_g_cm3(), c.density_g_cm3(), r::kDensity}}) {
    const std::string field = std::string("compression.") + f.name;
    if (custom && !f.has) rep.add(field, "is required for material CUSTOM " + allowed(f.range));
    rep.real(field, f.has, f.v, f.range);
  }
}

void check_bond(const Compression& c, Report& rep) {
  if (!mdem::v1::GrainBondKind_IsValid(c.bond()))
    rep.add("compression.bond", std::to_string(c.bond()) +
                                    " is not a bond kind (allowed: ELASTIC, PLASTIC, BRITTLE; "
                                    "unset = the material's)");
  // The bond an unset kind stands for: the material's, ELASTIC for CUSTOM.
  mdem::v1::GrainBondKind bond = c.bond();
  if (bond == mdem::v1::GRAIN_BOND_UNSPECIFIED) {
    const MaterialPreset* m = material_preset(c.material());
    bond = m ? m->bond : mdem::v1::ELASTIC;
  }
  const bool needs_strength = bond == mdem::v1::PLASTIC || bond == mdem::v1::BRITTLE;
  if (needs_strength && c.material() == mdem::v1::CUSTOM && !c.has_strength_gpa())
    rep.add("compression.strength_gpa", std::string("is required for material CUSTOM with ") +
                                            mdem::v1::GrainBondKind_Name(bond) + " bonds " +
                                            allowed(r::kStrengthGpa));
  rep.real("compression.strength_gpa", c.has_strength_gpa(), c.strength_gpa(), r::kStrengthGpa);
}

void check_compression_loading(const Compression& c, Report& rep) {
  rep.real("compression.platen_speed_nm_per_ps", c.has_platen_speed_nm_per_ps(),
           c.platen_speed_nm_per_ps(), r::kPlatenSpeed);
  // Less than the particle's diameter, so that the platens never meet; with an invalid outer
  // radius (reported on its own) only the fixed range is checked.
  const Range peak = outer_ok(c)
                         ? Range{0.0, 2.0 * outer_of(c), true, true, "nm", "twice outer_radius_nm"}
                         : r::kPeakDisplacementNm;
  rep.real("compression.peak_displacement_nm", c.has_peak_displacement_nm(),
           c.peak_displacement_nm(), peak);
  rep.real("compression.viscous_ratio", c.has_viscous_ratio(), c.viscous_ratio(), r::kViscousRatio);
}

void check_compression(const Compression& c, Report& rep) {
  rep.real("compression.outer_radius_nm", c.has_outer_radius_nm(), c.outer_radius_nm(),
           r::kOuterRadiusNm);
  rep.real("compression.inner_radius_nm", c.has_inner_radius_nm(), c.inner_radius_nm(),
           r::kInnerRadiusNm);
  rep.real("compression.grain_radius_min_nm", c.has_grain_radius_min_nm(), c.grain_radius_min_nm(),
           r::kGrainRadiusNm);
  rep.real("compression.grain_radius_max_nm", c.has_grain_radius_max_nm(), c.grain_radius_max_nm(),
           r::kGrainRadiusNm);
  rep.real("compression.porosity", c.has_porosity(), c.porosity(), r::kPorosity);
  check_particle_shape(c, rep);
  check_grain_count(c, rep);
  check_material(c, rep);
  check_bond(c, rep);
  check_compression_loading(c, rep);
  rep.real("compression.local_damping", c.has_local_damping(), c.local_damping(), r::kLocalDamping);
}

}  // namespace

double compression_grain_estimate(const mdem::v1::CompressionSpec& c) {
  const double outer = c.has_outer_radius_nm() ? c.outer_radius_nm() : d::kOuterRadiusNm;
  const double inner = c.has_inner_radius_nm() ? c.inner_radius_nm() : d::kInnerRadiusNm;
  const double a = c.has_grain_radius_min_nm() ? c.grain_radius_min_nm() : d::kGrainRadiusMinNm;
  const double b = c.has_grain_radius_max_nm() ? c.grain_radius_max_nm() : d::kGrainRadiusMaxNm;
  const double porosity = c.has_porosity() ? c.porosity() : d::kPorosity;
  const double mean_r3 = (a + b) * (a * a + b * b) / 4.0;
  return (1.0 - porosity) * (outer * outer * outer - inner * inner * inner) / mean_r3;
}

KindRules compression_rules() {
  return {"compression", v1::JobSpec::kCompression,
          [](v1::JobSpec& spec) { default_compression(*spec.mutable_compression()); },
          [](const v1::JobSpec& spec, Checks& checks) {
            check_compression(spec.compression(), checks);
          }};
}

}  // namespace mdem::spec
