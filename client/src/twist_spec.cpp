#include "twist_spec.h"

#include <cmath>
#include <initializer_list>
#include <sstream>
#include <utility>

#include "flags.h"

namespace mdem::cli {

const std::map<std::string, std::string>& twist_flag_fields() {
  static const std::map<std::string, std::string> m = {
      {"--name", "name"},
      {"--seed", "seed"},
      {"--dt", "run.dt_ps"},
      {"--safety", "run.safety"},
      {"--threads", "run.threads"},
      {"--energy-every", "outputs.energy_every_ps"},
      {"--snapshot-every", "outputs.snapshot_every_ps"},
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

// Any finite number; the range is spec::validate's job (it names the field and the range).
double number(const std::string& flag, const std::string& text) {
  return parse_number(flag, text, "a finite number");
}

long whole(const std::string& flag, const std::string& text) {
  return parse_integer(flag, text, -2147483648L, 2147483647L);
}

// The enum value named by a flag that takes one of a fixed set of names.
template <class Enum>
Enum choice(const std::string& flag, const std::string& text,
            std::initializer_list<std::pair<const char*, Enum>> allowed) {
  std::string names;
  for (const auto& [name, value] : allowed) {
    if (text == name) return value;
    names += (names.empty() ? "" : ", ") + std::string(name);
  }
  throw UsageError(flag + ": '" + text + "' is not allowed (allowed: " + names + ")");
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, sep);) out.push_back(item);
  return out;
}

}  // namespace

void apply_twist_flags(const std::map<std::string, std::string>& f, v1::JobSpec& spec) {
  v1::TwistSpec& t = *spec.mutable_twist();
  auto has = [&](const char* k) { return f.count(k) > 0; };
  auto val = [&](const char* k) { return f.at(k); };
  if (has("--name")) spec.set_name(val("--name"));
  if (has("--seed"))
    spec.set_seed(static_cast<std::uint64_t>(parse_integer("--seed", val("--seed"), 0, LONG_MAX)));
  if (has("--dt") && val("--dt") != "auto")
    spec.mutable_run()->set_dt_ps(number("--dt", val("--dt")));
  if (has("--safety")) spec.mutable_run()->set_safety(number("--safety", val("--safety")));
  if (has("--threads"))
    spec.mutable_run()->set_threads(static_cast<int>(whole("--threads", val("--threads"))));
  if (has("--energy-every"))
    spec.mutable_outputs()->set_energy_every_ps(number("--energy-every", val("--energy-every")));
  if (has("--snapshot-every"))
    spec.mutable_outputs()->set_snapshot_every_ps(
        number("--snapshot-every", val("--snapshot-every")));
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

FlagSpec twist_flag_spec() {
  FlagSpec fs;
  for (const auto& [flag, field] : twist_flag_fields())
    if (flag != "--unload") fs.with_value.push_back(flag);
  fs.with_value.push_back("--spec");
  fs.switches = {"--unload"};
  return fs;
}

v1::JobSpec twist_spec_from_flags(const std::map<std::string, std::string>& given) {
  v1::JobSpec spec;
  if (given.count("--spec")) spec = spec::load_file(given.at("--spec"));
  if (spec.kind_case() != v1::JobSpec::kTwist && spec.kind_case() != v1::JobSpec::KIND_NOT_SET)
    throw UsageError("--spec: the file describes another job kind (allowed here: twist)");
  apply_twist_flags(given, spec);
  return spec::finalize(spec);
}

std::string describe_spec_error(const spec::SpecError& e) {
  std::ostringstream o;
  for (const spec::FieldError& f : e.errors()) {
    std::string flag;
    for (const auto& [fl, field] : twist_flag_fields())
      if (f.field == field || f.field.rfind(field + "[", 0) == 0) flag = fl;
    o << "  " << f.field << (flag.empty() ? "" : " (" + flag + ")") << ": " << f.message << "\n";
  }
  return o.str();
}

const char* const kTwistSpecFlagsHelp =
    "Spec:\n"
    "  --spec FILE          a JobSpec as JSON or YAML (.json/.yaml/.yml); flags override it\n"
    "Rope:\n"
    "  --layers N           hexagon layers incl. the centre tube, 2..10 (default 6 = 91 "
    "tubes)\n"
    "  --length NM          tube length, 5..2000 nm, whole 1.356 nm segments (default 67.8)\n"
    "  --spacing NM|auto    tube spacing 1.5..2.5 nm (default auto: the lattice vdW minimum)\n"
    "  --missing I,J,...    point defects: lattice sites without a tube (0 = centre)\n"
    "  --line-defects A[:W[:F]];...  rows of missing tubes from the centre at angle A deg,\n"
    "                       W rows wide (1..3), over the central fraction F of the length\n"
    "Loading:\n"
    "  --torque X           T_max, (0, 500] nN·nm (default 64)\n"
    "  --rate X             ramp rate, (0, 100] nN·nm/ps (default 1.0)\n"
    "  --hold X             hold at T_max, 0..1e6 ps (default 100)\n"
    "  --bc B               constant-moment (default) or twist-relaxation\n"
    "  --grip-load G        rigid-grip (default: the grip's moment about the rope axis is T)\n"
    "                       or per-element (each grip element carries T about its own\n"
    "                       centre, the thesis's PFC ball moments)\n"
    "  --unload             ramp the torque down after the hold, then relax\n"
    "  --unload-hold X      relaxation after unloading, 0..1e6 ps (default 50)\n"
    "  --grip-segments N    end segments per tube in each grip, 1..segments/4 (default 1)\n"
    "  --damping-ratio X    vdW contact dashpot ratio, 0..1 (default 0.03)\n"
    "  --local-damping X    PFC local damping, 0..0.99 (default 0.1)\n"
    "  --temperature K      seeded random velocities and spins of K kelvin at the start,\n"
    "                       0..2000 (default 0: at rest; noise lets buckling start)\n"
    "Run:\n"
    "  --dt X|auto          time step, 1e-6..1 ps (default auto = safety x critical step)\n"
    "  --safety X           fraction of the critical step, (0, 1] (default 0.6)\n"
    "  --threads N          OpenMP threads, 0 = all cores (default 0)\n"
    "  --energy-every X     energy/observable frame interval, ps (default 1)\n"
    "  --snapshot-every X   snapshot interval, ps; 0 = none (default 10)\n"
    "  --name TEXT          a label for `mdem ls`\n"
    "  --seed N             random seed for --temperature (default 1)\n";

}  // namespace mdem::cli
