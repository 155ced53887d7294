// validate(): every problem of a spec, each with its field path and the allowed values.
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "mdem/spec.h"
#include "rules.h"

namespace mdem::spec {

namespace {

using detail::allowed;
using detail::contains;
using detail::number_text;
using detail::Range;
namespace d = detail::defaults;
namespace r = detail::ranges;

// Collects the errors; real() and integer() check one optional scalar against its range.
class Report {
 public:
  void add(std::string field, std::string message) {
    errors_.push_back({std::move(field), std::move(message)});
  }
  void real(const std::string& field, bool has, double v, const Range& range) {
    if (!has) return;
    if (!std::isfinite(v))
      add(field, number_text(v) + " is not a finite number " + allowed(range));
    else if (!contains(range, v))
      add(field, number_text(v) + " is out of range " + allowed(range));
  }
  void integer(const std::string& field, bool has, long long v, const Range& range) {
    if (has && !contains(range, static_cast<double>(v)))
      add(field, std::to_string(v) + " is out of range " + allowed(range));
  }
  std::vector<FieldError> take() { return std::move(errors_); }

 private:
  std::vector<FieldError> errors_;
};

// ---- name ----

struct Utf8Scan {
  bool valid = true;
  std::size_t chars = 0;
  long control_at = -1;  // 0-based character index of the first control character
  char32_t control = 0;
};

// Length of the UTF-8 sequence led by byte b, 0 if b cannot lead one.
int utf8_length(unsigned char b) {
  if (b < 0x80) return 1;
  if (b >= 0xC2 && b <= 0xDF) return 2;
  if (b >= 0xE0 && b <= 0xEF) return 3;
  if (b >= 0xF0 && b <= 0xF4) return 4;
  return 0;
}

// Decodes the code point at s[i] of length len; false for a bad continuation, an overlong form,
// a surrogate or a value above U+10FFFF.
bool utf8_decode(std::string_view s, std::size_t i, int len, char32_t& cp) {
  if (i + len > s.size()) return false;
  static constexpr unsigned char kLeadMask[] = {0, 0x7F, 0x1F, 0x0F, 0x07};
  cp = static_cast<unsigned char>(s[i]) & kLeadMask[len];
  for (int k = 1; k < len; ++k) {
    const auto c = static_cast<unsigned char>(s[i + k]);
    if ((c & 0xC0) != 0x80) return false;
    cp = (cp << 6) | (c & 0x3F);
  }
  static constexpr char32_t kMin[] = {0, 0, 0x80, 0x800, 0x10000};
  return cp >= kMin[len] && cp <= 0x10FFFF && !(cp >= 0xD800 && cp <= 0xDFFF);
}

bool is_control(char32_t cp) { return cp < 0x20 || (cp >= 0x7F && cp <= 0x9F); }

Utf8Scan scan_utf8(std::string_view s) {
  Utf8Scan scan;
  for (std::size_t i = 0; i < s.size();) {
    const int len = utf8_length(static_cast<unsigned char>(s[i]));
    char32_t cp = 0;
    if (len == 0 || !utf8_decode(s, i, len, cp)) {
      scan.valid = false;
      return scan;
    }
    if (is_control(cp) && scan.control_at < 0) {
      scan.control_at = static_cast<long>(scan.chars);
      scan.control = cp;
    }
    ++scan.chars;
    i += len;
  }
  return scan;
}

std::string code_point_text(char32_t cp) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "U+%04X", static_cast<unsigned>(cp));
  return buf;
}

void check_name(const mdem::v1::JobSpec& spec, Report& rep) {
  if (!spec.has_name()) return;
  const std::string rule = "(allowed: at most " + std::to_string(r::kNameMaxChars) +
                           " characters of UTF-8 text, no control characters)";
  const Utf8Scan scan = scan_utf8(spec.name());
  if (!scan.valid) return rep.add("name", "is not valid UTF-8 " + rule);
  if (scan.chars > r::kNameMaxChars)
    rep.add("name", std::to_string(scan.chars) + " characters is too long " + rule);
  if (scan.control_at >= 0)
    rep.add("name", "control character " + code_point_text(scan.control) + " at character " +
                        std::to_string(scan.control_at + 1) + " " + rule);
}

// ---- run and outputs ----

void check_run(const mdem::v1::RunSettings& run, Report& rep) {
  rep.real("run.dt_ps", run.has_dt_ps(), run.dt_ps(), r::kDtPs);
  rep.real("run.safety", run.has_safety(), run.safety(), r::kSafety);
  rep.integer("run.threads", run.has_threads(), run.threads(), r::kThreads);
}

void check_outputs(const mdem::v1::Outputs& out, Report& rep) {
  rep.real("outputs.energy_every_ps", out.has_energy_every_ps(), out.energy_every_ps(),
           r::kEnergyEveryPs);
  rep.real("outputs.snapshot_every_ps", out.has_snapshot_every_ps(), out.snapshot_every_ps(),
           r::kSnapshotEveryPs);
}

// ---- twist ----

void check_rope(const mdem::v1::TwistSpec& t, Report& rep) {
  rep.integer("twist.layers", t.has_layers(), t.layers(), r::kLayers);
  rep.real("twist.length_nm", t.has_length_nm(), t.length_nm(), r::kLengthNm);
  rep.real("twist.spacing_nm", t.has_spacing_nm(), t.spacing_nm(), r::kSpacingNm);
}

// Tubes of the rope's lattice, or -1 if layers is invalid (then site ids are not range-checked).
int lattice_size(const mdem::v1::TwistSpec& t) {
  const int layers = t.has_layers() ? t.layers() : d::kLayers;
  return contains(r::kLayers, layers) ? hex_tube_count(layers) : -1;
}

std::string sites_allowed(const mdem::v1::TwistSpec& t, int n) {
  if (n < 0) return "(allowed: >= 0; layers is invalid)";
  const int layers = t.has_layers() ? t.layers() : d::kLayers;
  return "(allowed: 0.." + std::to_string(n - 1) + " for " + std::to_string(layers) + " layers)";
}

std::string times_text(int count) {
  return count == 2 ? "twice" : std::to_string(count) + " times";
}

// Too many entries to be distinct sites: one error instead of one per entry.
bool check_missing_count(const mdem::v1::TwistSpec& t, int n, Report& rep) {
  const int limit = n >= 0 ? n : hex_tube_count(static_cast<int>(r::kLayers.hi));
  if (t.missing_tubes_size() <= limit) return true;
  rep.add("twist.missing_tubes", std::to_string(t.missing_tubes_size()) +
                                     " sites listed, more than the " + std::to_string(limit) +
                                     " tubes of the rope (allowed: distinct sites, at most " +
                                     std::to_string(limit - 1) + ")");
  return false;
}

void check_missing_tubes(const mdem::v1::TwistSpec& t, Report& rep) {
  const int n = lattice_size(t);
  if (!check_missing_count(t, n, rep)) return;
  std::map<int, int> seen;  // site -> times listed so far
  for (int i = 0; i < t.missing_tubes_size(); ++i) {
    const int site = t.missing_tubes(i);
    const std::string field = "twist.missing_tubes[" + std::to_string(i) + "]";
    if (site < 0 || (n >= 0 && site >= n)) {
      rep.add(field, "site " + std::to_string(site) + " does not exist " + sites_allowed(t, n));
      continue;
    }
    const int count = ++seen[site];
    if (count > 1)
      rep.add(field, "site " + std::to_string(site) + " is listed " + times_text(count) +
                         " (allowed: each site once)");
  }
  if (n >= 0 && static_cast<int>(seen.size()) == n)
    rep.add("twist.missing_tubes", "all " + std::to_string(n) +
                                       " tubes are missing (allowed: at most " +
                                       std::to_string(n - 1) + " sites, so that a tube remains)");
}

void check_line_defect(const mdem::v1::LineDefect& line, const std::string& at, Report& rep) {
  rep.real(at + ".angle_deg", line.has_angle_deg(), line.angle_deg(), r::kAngleDeg);
  rep.integer(at + ".width", line.has_width(), line.width(), r::kWidth);
  rep.real(at + ".length_fraction", line.has_length_fraction(), line.length_fraction(),
           r::kLengthFraction);
}

void check_boundary(const mdem::v1::TwistSpec& t, Report& rep) {
  if (mdem::v1::TwistBoundary_IsValid(t.boundary())) return;
  rep.add("twist.boundary", std::to_string(t.boundary()) +
                                " is not a twist boundary (allowed: CONSTANT_MOMENT, "
                                "TWIST_RELAXATION; unset = CONSTANT_MOMENT)");
}

void check_grip_load(const mdem::v1::TwistSpec& t, Report& rep) {
  if (mdem::v1::GripLoad_IsValid(t.grip_load())) return;
  rep.add("twist.grip_load", std::to_string(t.grip_load()) +
                                 " is not a grip load (allowed: RIGID_GRIP, PER_ELEMENT; unset = "
                                 "RIGID_GRIP)");
}

void check_loading(const mdem::v1::TwistSpec& t, Report& rep) {
  rep.real("twist.torque_nn_nm", t.has_torque_nn_nm(), t.torque_nn_nm(), r::kTorqueNnNm);
  rep.real("twist.torque_rate_nn_nm_per_ps", t.has_torque_rate_nn_nm_per_ps(),
           t.torque_rate_nn_nm_per_ps(), r::kTorqueRate);
  rep.real("twist.hold_ps", t.has_hold_ps(), t.hold_ps(), r::kHoldPs);
  check_boundary(t, rep);
  check_grip_load(t, rep);
  rep.real("twist.unload_hold_ps", t.has_unload_hold_ps(), t.unload_hold_ps(), r::kUnloadHoldPs);
}

// "(allowed: >= 1 and <= 12, a quarter of the 50 segments, round(67.8 nm / 1.356 nm))"
std::string grip_allowed(const mdem::v1::TwistSpec& t) {
  const int segments = twist_segments(t);
  const double length = t.has_length_nm() ? t.length_nm() : d::kLengthNm;
  return "(allowed: >= 1 and <= " + std::to_string(segments / 4) + ", a quarter of the " +
         std::to_string(segments) + " segments, round(" + number_text(length) + " nm / " +
         number_text(detail::kSegmentNm) + " nm))";
}

// At most a quarter of the tube's segments per grip; the limit follows from length_nm. With an
// invalid length (reported on its own) only the lower bound is checked.
void check_grip_segments(const mdem::v1::TwistSpec& t, Report& rep) {
  if (!t.has_grip_segments()) return;
  const int grip = t.grip_segments();
  const bool length_ok = !t.has_length_nm() || contains(r::kLengthNm, t.length_nm());
  const bool grip_ok = grip >= 1 && (!length_ok || grip <= twist_segments(t) / 4);
  if (grip_ok) return;
  const std::string rule = length_ok ? grip_allowed(t)
                                     : "(allowed: >= 1 and <= a quarter of the rope's segments; "
                                       "length_nm is invalid)";
  rep.add("twist.grip_segments", std::to_string(grip) + " is out of range " + rule);
}

void check_damping(const mdem::v1::TwistSpec& t, Report& rep) {
  rep.real("twist.vdw_damping_ratio", t.has_vdw_damping_ratio(), t.vdw_damping_ratio(),
           r::kVdwDampingRatio);
  rep.real("twist.local_damping", t.has_local_damping(), t.local_damping(), r::kLocalDamping);
  rep.real("twist.temperature_k", t.has_temperature_k(), t.temperature_k(), r::kTemperatureK);
}

void check_twist(const mdem::v1::TwistSpec& t, Report& rep) {
  check_rope(t, rep);
  check_missing_tubes(t, rep);
  for (int i = 0; i < t.line_defects_size(); ++i)
    check_line_defect(t.line_defects(i), "twist.line_defects[" + std::to_string(i) + "]", rep);
  check_loading(t, rep);
  check_grip_segments(t, rep);
  check_damping(t, rep);
}

// ---- compression ----

// A field's value, or its default when unset.
double value_or(bool has, double v, double fallback) { return has ? v : fallback; }

// Whether the field's value (its default when unset) is within its range: the cross-field
// rules below check only fields that are valid on their own, so one mistake gives one error.
bool valid(bool has, double v, double fallback, const Range& range) {
  return contains(range, value_or(has, v, fallback));
}

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
    const detail::MaterialPreset* m = detail::material_preset(c.material());
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

void check_kind(const mdem::v1::JobSpec& spec, Report& rep) {
  switch (spec.kind_case()) {
    case mdem::v1::JobSpec::kTwist:
      return check_twist(spec.twist(), rep);
    case mdem::v1::JobSpec::kCompression:
      return check_compression(spec.compression(), rep);
    case mdem::v1::JobSpec::KIND_NOT_SET:
      return rep.add("kind", "no job kind given (allowed: twist, compression)");
  }
}

}  // namespace

std::vector<FieldError> validate(const mdem::v1::JobSpec& spec) {
  Report rep;
  check_name(spec, rep);
  if (spec.has_run()) check_run(spec.run(), rep);
  if (spec.has_outputs()) check_outputs(spec.outputs(), rep);
  check_kind(spec, rep);
  return rep.take();
}

}  // namespace mdem::spec
