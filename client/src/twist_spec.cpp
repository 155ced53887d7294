#include "twist_spec.h"

#include <sstream>

#include "mdem/job/twist_job.h"

namespace mdem::cli {

const FlagFields& twist_flag_fields() {
  static const FlagFields m = {
      {"--layers", "twist.layers"},
      {"--length", "twist.length_nm"},
      {"--spacing", "twist.spacing_nm"},
      {"--missing", "twist.missing_tubes"},
      {"--line-defects", "twist.line_defects"},
      {"--torque", "twist.torque_nn_nm"},
      {"--rate", "twist.torque_rate_nn_nm_per_ps"},
      {"--hold", "twist.hold_ps"},
      {"--bc", "twist.boundary"},
      {"--grip-load", "twist.grip_load"},
      {"--grip-hold", "twist.grip_hold"},
      {"--unload", "twist.unload"},
      {"--unload-hold", "twist.unload_hold_ps"},
      {"--grip-segments", "twist.grip_segments"},
      {"--damping-ratio", "twist.vdw_damping_ratio"},
      {"--local-damping", "twist.local_damping"},
      {"--temperature", "twist.temperature_k"},
  };
  return m;
}

namespace {

double number(const std::string& flag, const std::string& text) { return spec_number(flag, text); }
int whole(const std::string& flag, const std::string& text) { return spec_int(flag, text); }

}  // namespace

void apply_twist_flags(const FlagValues& f, v1::JobSpec& spec) {
  v1::TwistSpec& t = *spec.mutable_twist();
  auto has = [&](const char* k) { return f.count(k) > 0; };
  auto val = [&](const char* k) { return f.at(k); };
  if (has("--layers")) t.set_layers(static_cast<int>(whole("--layers", val("--layers"))));
  if (has("--length")) t.set_length_nm(number("--length", val("--length")));
  if (has("--spacing") && val("--spacing") != "auto")
    t.set_spacing_nm(number("--spacing", val("--spacing")));
  if (has("--missing")) {
    t.clear_missing_tubes();
    for (const std::string& s : split(val("--missing"), ','))
      t.add_missing_tubes(static_cast<int>(whole("--missing", s)));
  }
  if (has("--line-defects")) {
    t.clear_line_defects();
    for (const std::string& d : split(val("--line-defects"), ';')) {
      const std::vector<std::string> p = split(d, ':');
      if (p.empty() || p.size() > 3)
        throw UsageError("--line-defects: '" + d +
                         "' is not ANGLE[:WIDTH[:FRACTION]] (e.g. 0:2:1;180:1:0.5)");
      v1::LineDefect* ld = t.add_line_defects();
      ld->set_angle_deg(number("--line-defects", p[0]));
      if (p.size() > 1) ld->set_width(static_cast<int>(whole("--line-defects", p[1])));
      if (p.size() > 2) ld->set_length_fraction(number("--line-defects", p[2]));
    }
  }
  if (has("--torque")) t.set_torque_nn_nm(number("--torque", val("--torque")));
  if (has("--rate")) t.set_torque_rate_nn_nm_per_ps(number("--rate", val("--rate")));
  if (has("--hold")) t.set_hold_ps(number("--hold", val("--hold")));
  if (has("--bc"))
    t.set_boundary(choice<v1::TwistBoundary>(
        "--bc", val("--bc"),
        {{"constant-moment", v1::CONSTANT_MOMENT}, {"twist-relaxation", v1::TWIST_RELAXATION}}));
  if (has("--grip-load"))
    t.set_grip_load(
        choice<v1::GripLoad>("--grip-load", val("--grip-load"),
                             {{"rigid-grip", v1::RIGID_GRIP}, {"per-element", v1::PER_ELEMENT}}));
  if (has("--grip-hold"))
    t.set_grip_hold(choice<v1::GripHold>("--grip-hold", val("--grip-hold"),
                                         {{"positions", v1::HOLD_POSITIONS},
                                          {"positions-and-spins", v1::HOLD_POSITIONS_AND_SPINS}}));
  if (has("--unload")) t.set_unload(true);
  if (has("--unload-hold")) t.set_unload_hold_ps(number("--unload-hold", val("--unload-hold")));
  if (has("--grip-segments"))
    t.set_grip_segments(static_cast<int>(whole("--grip-segments", val("--grip-segments"))));
  if (has("--damping-ratio"))
    t.set_vdw_damping_ratio(number("--damping-ratio", val("--damping-ratio")));
  if (has("--temperature")) t.set_temperature_k(number("--temperature", val("--temperature")));
  if (has("--local-damping"))
    t.set_local_damping(number("--local-damping", val("--local-damping")));
}

namespace {

// Ranges and defaults from the spec rules (mdem/spec_rules.h).
std::string twist_flags_help() {
  namespace r = spec::ranges;
  namespace d = spec::defaults;
  return "Rope:\n" +
         flag_help("--layers N", "hexagon layers incl. the centre tube", r::kLayers,
                   default_of(d::kLayers) + " = " +
                       std::to_string(spec::hex_tube_count(d::kLayers)) + " tubes") +
         flag_help("--length NM", "tube length in whole 1.356 nm segments", r::kLengthNm,
                   default_of(d::kLengthNm)) +
         flag_help("--spacing NM|auto", "tube spacing", r::kSpacingNm,
                   "auto: the lattice vdW minimum") +
         "  --missing I,J,...    point defects: lattice sites without a tube (0 = centre)\n"
         "  --line-defects A[:W[:F]];...  rows of missing tubes from the centre at angle A deg\n"
         "                       " +
         spec::interval_text(r::kAngleDeg) + ", W rows wide " + spec::interval_text(r::kWidth) +
         ",\n"
         "                       over the central fraction F " +
         spec::interval_text(r::kLengthFraction) +
         "\n"
         "Loading:\n" +
         flag_help("--torque X", "T_max", r::kTorqueNnNm, default_of(d::kTorqueNnNm)) +
         flag_help("--rate X", "ramp rate", r::kTorqueRate, default_of(d::kTorqueRate)) +
         flag_help("--hold X", "hold at T_max", r::kHoldPs, default_of(d::kHoldPs)) +
         "  --bc B               constant-moment (default) or twist-relaxation\n"
         "  --grip-load G        rigid-grip (default: the grip's moment about the rope axis is "
         "T)\n"
         "                       or per-element (each grip element carries T about its own\n"
         "                       centre, the thesis's PFC ball moments)\n"
         "  --grip-hold H        what --bc twist-relaxation holds: positions (default: the grip\n"
         "                       elements spin freely, the thesis's §4.3) or positions-and-spins\n"
         "                       (clamped: keeps each tube's twist under --grip-load per-element)\n"
         "  --unload             ramp the torque down after the hold, then relax\n" +
         flag_help("--unload-hold X", "relaxation after unloading", r::kUnloadHoldPs,
                   default_of(d::kUnloadHoldPs)) +
         "  --grip-segments N    end segments per tube in each grip, 1..segments/4 (default " +
         std::to_string(d::kGripSegments) + ")\n" +
         flag_help("--damping-ratio X", "vdW contact dashpot ratio", r::kVdwDampingRatio,
                   default_of(d::kVdwDampingRatio)) +
         flag_help("--local-damping X", "PFC local damping", r::kLocalDamping,
                   default_of(d::kLocalDamping)) +
         flag_help("--temperature K", "random velocities and spins at start", r::kTemperatureK,
                   default_of(d::kTemperatureK) + ": at rest") +
         "                       (noise lets buckling start; seeded by --seed)\n";
}

constexpr const char* kTwistAbout =
    "Twists a hexagonal rope of parallel (10,10) CNTs by torques on its end grips (thesis\n"
    "Ch. 4): the torque rises at --rate to --torque, is held for --hold, and optionally\n"
    "unloaded. Reports twist angle, end shift, radius, topological charge Q of the mid\n"
    "cross-section and the morphology.\n";

std::string describe_twist(Job& job, const v1::JobSpec& spec) {
  auto* twist = dynamic_cast<TwistJob*>(&job);
  if (!twist) return {};
  const v1::TwistSpec& t = spec.twist();
  std::ostringstream o;
  o << twist->rope().tubes.size() << " tubes x " << twist->rope().segments
    << " segments = " << job.system().elements().size() << " elements, " << job.duration()
    << " ps (ramp " << twist->protocol().ramp_time() << " ps to " << t.torque_nn_nm()
    << " nN·nm, hold " << t.hold_ps() << " ps, "
    << (t.boundary() == v1::TWIST_RELAXATION
            ? (t.grip_hold() == v1::HOLD_POSITIONS_AND_SPINS ? "twist-relaxation, grips clamped"
                                                             : "twist-relaxation")
            : "constant-moment")
    << ")";
  return o.str();
}

std::string no_building_line(const v1::JobSpec&) { return {}; }

}  // namespace

SpecKind twist_kind() {
  return {"twist",     v1::JobSpec::kTwist, twist_flag_fields, {"--unload"},    apply_twist_flags,
          kTwistAbout, twist_flags_help(),  describe_twist,    no_building_line};
}

}  // namespace mdem::cli
