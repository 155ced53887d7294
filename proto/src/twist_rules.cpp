// The twist kind's rules (mdem.v1.TwistSpec): its defaults, its validation and the rope's derived
// counts, registered as one entry of kind_rules().
#include <climits>
#include <cmath>
#include <map>
#include <string>

#include "rules.h"

namespace mdem::spec {

namespace {

namespace d = defaults;
namespace r = ranges;
using Report = Checks;

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
  if (t.grip_hold() == mdem::v1::GRIP_HOLD_UNSPECIFIED) t.set_grip_hold(mdem::v1::HOLD_POSITIONS);
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

// ---- validation ----

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

// Only a twist-relaxation hold holds anything: under a constant moment the grips are loaded.
void check_grip_hold(const mdem::v1::TwistSpec& t, Report& rep) {
  if (!mdem::v1::GripHold_IsValid(t.grip_hold())) {
    rep.add("twist.grip_hold", std::to_string(t.grip_hold()) +
                                   " is not a grip hold (allowed: HOLD_POSITIONS, "
                                   "HOLD_POSITIONS_AND_SPINS; unset = HOLD_POSITIONS)");
    return;
  }
  if (t.grip_hold() == mdem::v1::HOLD_POSITIONS_AND_SPINS &&
      t.boundary() != mdem::v1::TWIST_RELAXATION)
    rep.add("twist.grip_hold",
            "HOLD_POSITIONS_AND_SPINS holds the grips of a twist-relaxation hold, but boundary is "
            "CONSTANT_MOMENT, whose grips carry the torque and are not held (allowed: "
            "HOLD_POSITIONS_AND_SPINS with boundary TWIST_RELAXATION, or HOLD_POSITIONS)");
}

void check_loading(const mdem::v1::TwistSpec& t, Report& rep) {
  rep.real("twist.torque_nn_nm", t.has_torque_nn_nm(), t.torque_nn_nm(), r::kTorqueNnNm);
  rep.real("twist.torque_rate_nn_nm_per_ps", t.has_torque_rate_nn_nm_per_ps(),
           t.torque_rate_nn_nm_per_ps(), r::kTorqueRate);
  rep.real("twist.hold_ps", t.has_hold_ps(), t.hold_ps(), r::kHoldPs);
  check_boundary(t, rep);
  check_grip_load(t, rep);
  check_grip_hold(t, rep);
  rep.real("twist.unload_hold_ps", t.has_unload_hold_ps(), t.unload_hold_ps(), r::kUnloadHoldPs);
}

// "(allowed: >= 1 and <= 12, a quarter of the 50 segments, round(67.8 nm / 1.356 nm))"
std::string grip_allowed(const mdem::v1::TwistSpec& t) {
  const int segments = twist_segments(t);
  const double length = t.has_length_nm() ? t.length_nm() : d::kLengthNm;
  return "(allowed: >= 1 and <= " + std::to_string(segments / 4) + ", a quarter of the " +
         std::to_string(segments) + " segments, round(" + number_text(length) + " nm / " +
         number_text(kSegmentNm) + " nm))";
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
  // Each line defect removes a row of tubes from the centre outwards: a few dozen directions
  // already remove every tube of the largest rope, so a longer list is a mistake (and one error,
  // not one per entry, however long it is).
  constexpr int kMaxLineDefects = 64;
  if (t.line_defects_size() > kMaxLineDefects)
    rep.add("twist.line_defects", std::to_string(t.line_defects_size()) +
                                      " line defects listed (allowed: at most " +
                                      std::to_string(kMaxLineDefects) + ")");
  else
    for (int i = 0; i < t.line_defects_size(); ++i)
      check_line_defect(t.line_defects(i), "twist.line_defects[" + std::to_string(i) + "]", rep);
  check_loading(t, rep);
  check_grip_segments(t, rep);
  check_damping(t, rep);
}

}  // namespace

int twist_segments(const mdem::v1::TwistSpec& twist) {
  const double length = twist.has_length_nm() ? twist.length_nm() : d::kLengthNm;
  const double segments = std::round(length / kSegmentNm);
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

KindRules twist_rules() {
  return {"twist", v1::JobSpec::kTwist,
          [](v1::JobSpec& spec) { default_twist(*spec.mutable_twist()); },
          [](const v1::JobSpec& spec, Checks& checks) { check_twist(spec.twist(), checks); }};
}

}  // namespace mdem::spec
