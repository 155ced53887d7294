#include "twist_spec.h"

#include <cmath>
#include <sstream>

#include "flags.h"
#include "mdem/units.h"

namespace mdem::cli {

EngineJob twist_engine_job(const v1::JobSpec& spec) {
  const v1::TwistSpec& t = spec.twist();
  EngineJob job;
  RopeSpec& r = job.twist.rope;
  r.layers = t.layers();
  r.segments = std::max(2, static_cast<int>(std::lround(t.length_nm() / 1.356)));
  r.spacing = t.has_spacing_nm() ? t.spacing_nm() : 0.0;
  r.missing.assign(t.missing_tubes().begin(), t.missing_tubes().end());
  for (const v1::LineDefect& d : t.line_defects())
    r.lines.push_back({d.angle_deg(), d.width(), d.length_fraction()});
  r.grip_segments = t.grip_segments();
  TwistLoading& l = job.twist.loading;
  l.torque_max = units::nNnm(t.torque_nn_nm());
  l.rate = units::nNnm(t.torque_rate_nn_nm_per_ps());
  l.hold = t.hold_ps();
  l.boundary = t.boundary() == v1::TWIST_RELAXATION ? TwistBoundary::TwistRelaxation
                                                    : TwistBoundary::ConstantMoment;
  l.grip_load = t.grip_load() == v1::PER_ELEMENT ? GripLoad::PerElement : GripLoad::RigidGrip;
  l.unload = t.unload();
  l.unload_hold = t.unload_hold_ps();
  job.twist.vdw_damping_ratio = t.vdw_damping_ratio();
  job.twist.temperature_k = t.temperature_k();
  job.twist.seed = static_cast<unsigned>(spec.seed());
  job.settings.local_damping = t.local_damping();
  if (spec.run().has_dt_ps()) job.settings.dt = spec.run().dt_ps();
  job.settings.safety = spec.run().safety();
  job.settings.threads = spec.run().threads();
  job.cadence.frame_every_ps = spec.outputs().energy_every_ps();
  job.cadence.snapshot_every_ps = spec.outputs().snapshot_every_ps();
  return job;
}

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
  if (has("--bc")) {
    const std::string bc = val("--bc");
    if (bc == "constant-moment")
      t.set_boundary(v1::CONSTANT_MOMENT);
    else if (bc == "twist-relaxation")
      t.set_boundary(v1::TWIST_RELAXATION);
    else
      throw UsageError("--bc: '" + bc +
                       "' is not allowed (allowed: constant-moment, twist-relaxation)");
  }
  if (has("--grip-load")) {
    const std::string g = val("--grip-load");
    if (g == "rigid-grip")
      t.set_grip_load(v1::RIGID_GRIP);
    else if (g == "per-element")
      t.set_grip_load(v1::PER_ELEMENT);
    else
      throw UsageError("--grip-load: '" + g +
                       "' is not allowed (allowed: rigid-grip, per-element)");
  }
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

}  // namespace mdem::cli
