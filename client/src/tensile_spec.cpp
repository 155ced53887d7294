#include "tensile_spec.h"

#include <cmath>
#include <sstream>
#include <string_view>

namespace mdem::cli {

const FlagFields& tensile_flag_fields() {
  static const FlagFields m = {
      {"--size", "tensile.size"},
      {"--side", "tensile.side_nm"},
      {"--thickness", "tensile.thickness_nm"},
      {"--tubes", "tensile.tubes"},
      {"--segments", "tensile.segments_per_tube"},
      {"--tilt", "tensile.max_tilt_deg"},
      {"--nps", "tensile.nanoparticles"},
      {"--np-deposit", "tensile.np_deposit"},
      {"--prerelax", "tensile.prerelax_max_ps"},
      {"--relax", "tensile.relax_ps"},
      {"--damping-ratio", "tensile.vdw_damping_ratio"},
      {"--local-damping", "tensile.local_damping"},
      {"--dashpot-shear", "tensile.vdw_dashpot_shear"},
      {"--mode", "tensile.mode"},
      {"--strain", "tensile.target_strain_percent"},
      {"--rate", "tensile.strain_rate_per_ps"},
      {"--ramp", "tensile.ramp_ps"},
      {"--cycles", "tensile.cycles"},
      {"--amplitude", "tensile.amplitude_percent"},
      {"--grip-width", "tensile.grip_width_nm"},
      {"--zero-velocities", "tensile.zero_velocities"},
      {"--report-strains", "tensile.report_strains_percent"},
      {"--report-times", "tensile.report_times_ps"},
  };
  return m;
}

namespace {

// "A,B,C" as numbers (each strictly parsed), replacing the list.
void set_points(const std::string& flag, const std::string& text,
                google::protobuf::RepeatedField<double>& out) {
  out.Clear();
  const std::vector<std::string> parts = split(text, ',');
  if (parts.empty() || text.back() == ',')
    throw UsageError(flag + ": '" + text + "' is not a list of numbers A,B,... (e.g. 0,2,10,20)");
  for (const std::string& p : parts) out.Add(spec_number(flag, p));
}

}  // namespace

void apply_tensile_flags(const FlagValues& f, v1::JobSpec& spec) {
  v1::TensileSpec& t = *spec.mutable_tensile();
  auto has = [&](const char* k) { return f.count(k) > 0; };
  auto num = [&](const char* k) { return spec_number(k, f.at(k)); };
  auto whole = [&](const char* k) { return spec_int(k, f.at(k)); };
  if (has("--size"))
    t.set_size(choice<v1::FilmSize>(
        "--size", f.at("--size"),
        {{"small", v1::FILM_SMALL}, {"medium", v1::FILM_MEDIUM}, {"large", v1::FILM_LARGE}}));
  if (has("--side")) t.set_side_nm(num("--side"));
  if (has("--thickness")) t.set_thickness_nm(num("--thickness"));
  if (has("--tubes")) t.set_tubes(whole("--tubes"));
  if (has("--segments")) t.set_segments_per_tube(whole("--segments"));
  if (has("--tilt")) t.set_max_tilt_deg(num("--tilt"));
  if (has("--nps")) t.set_nanoparticles(whole("--nps"));
  if (has("--np-deposit"))
    t.set_np_deposit(choice<v1::NpDeposit>(
        "--np-deposit", f.at("--np-deposit"),
        {{"after-relax", v1::AFTER_RELAX}, {"before-relax", v1::BEFORE_RELAX}}));
  if (has("--prerelax")) t.set_prerelax_max_ps(num("--prerelax"));
  if (has("--relax")) t.set_relax_ps(num("--relax"));
  if (has("--damping-ratio")) t.set_vdw_damping_ratio(num("--damping-ratio"));
  if (has("--local-damping")) t.set_local_damping(num("--local-damping"));
  if (has("--dashpot-shear")) t.set_vdw_dashpot_shear(true);
  if (has("--mode"))
    t.set_mode(choice<v1::TensileMode>("--mode", f.at("--mode"),
                                       {{"monotonic", v1::MONOTONIC}, {"cyclic", v1::CYCLIC}}));
  if (has("--strain")) t.set_target_strain_percent(num("--strain"));
  if (has("--rate")) t.set_strain_rate_per_ps(num("--rate"));
  if (has("--ramp")) t.set_ramp_ps(num("--ramp"));
  if (has("--cycles")) t.set_cycles(whole("--cycles"));
  if (has("--amplitude")) t.set_amplitude_percent(num("--amplitude"));
  if (has("--grip-width")) t.set_grip_width_nm(num("--grip-width"));
  if (has("--zero-velocities")) t.set_zero_velocities(true);
  if (has("--report-strains"))
    set_points("--report-strains", f.at("--report-strains"), *t.mutable_report_strains_percent());
  if (has("--report-times"))
    set_points("--report-times", f.at("--report-times"), *t.mutable_report_times_ps());
}

namespace {

const char* size_word(v1::FilmSize s) {
  switch (s) {
    case v1::FILM_MEDIUM:
      return "medium";
    case v1::FILM_LARGE:
      return "large";
    default:
      return "small";
  }
}

// A count flag's help line with its range as whole numbers, "1..100000" (the interval text
// would print 1e+05, which the flag does not take).
std::string count_help(std::string_view usage, std::string_view text, const spec::Range& range,
                       const std::string& default_text) {
  constexpr std::size_t kColumn = 23;  // where flag_help's text starts
  std::string line = "  " + std::string(usage);
  line.append(line.size() < kColumn ? kColumn - line.size() : 1, ' ');
  line += std::string(text) + ", " + std::to_string(std::lround(range.lo)) + ".." +
          std::to_string(std::lround(range.hi));
  if (!range.unit.empty()) line.append(" ").append(range.unit);
  return line + " (default " + default_text + ")\n";
}

// Ranges and defaults from the spec rules (mdem/spec_rules.h).
std::string tensile_flags_help() {
  namespace r = spec::ranges;
  namespace d = spec::defaults;
  const spec::FilmPreset small = spec::film_preset(v1::FILM_SMALL);
  const std::string max_elements = spec::number_text(spec::kMaxTensileElements);
  return "Film:\n"
         "  --size S             small (default: 300 x 300 x 11 nm, 200 tubes of 200 segments),\n"
         "                       medium (500 nm, 350 of 350) or large (1000 nm, 500 of 700):\n"
         "                       Table 5-1's films; the flags below override its numbers\n" +
         flag_help("--side NM", "film side (length = width)", r::kSideNm,
                   default_of(small.side_nm) + " for small") +
         flag_help("--thickness NM", "film thickness", r::kThicknessNm,
                   default_of(d::kThicknessNm)) +
         count_help("--tubes N", "generated tubes", r::kTubes,
                    std::to_string(small.tubes) + " for small") +
         count_help("--segments N", "1.356 nm segments per tube", r::kSegmentsPerTube,
                    std::to_string(small.segments_per_tube) + " for small") +
         "                       at most " + max_elements + " elements, tubes x segments + NPs\n" +
         flag_help("--tilt DEG", "largest out-of-plane tilt", r::kMaxTiltDeg,
                   default_of(d::kMaxTiltDeg)) +
         count_help("--nps N", "Si nanoparticles (r 2.5 nm)", r::kNanoparticles,
                    std::to_string(d::kNanoparticles)) +
         "                       and as many as fit the slab with centres 5.4287 nm apart\n"
         "  --np-deposit D       after-relax (default: into the relaxed film) or before-relax\n"
         "Stages:\n" +
         flag_help("--prerelax PS", "cap of the damped pre-relaxation", r::kPrerelaxMaxPs,
                   default_of(d::kPrerelaxMaxPs)) +
         flag_help("--relax PS", "hands-off relaxation, 0 = ready-to-relax", r::kRelaxPs,
                   default_of(d::kRelaxPs)) +
         flag_help("--damping-ratio X", "vdW/NP contact dashpot ratio", r::kVdwDampingRatio,
                   default_of(d::kVdwDampingRatio)) +
         flag_help("--local-damping X", "PFC local damping", r::kLocalDamping,
                   default_of(d::kTensileLocalDamping)) +
         "  --dashpot-shear      the contact dashpots (CNT-CNT, NP-CNT, NP-NP) damp shear too,\n"
         "                       as the thesis's (default: along the centre line only;\n"
         "                       docs/tensile.md)\n"
         "Loading:\n"
         "  --mode M             monotonic (default: ramp to a constant rate up to --strain) or\n"
         "                       cyclic (down to -amplitude and back, --cycles times)\n" +
         flag_help("--strain PCT", "target strain (monotonic)", r::kTargetStrainPercent,
                   default_of(d::kTargetStrainPercent)) +
         flag_help("--rate X", "strain rate in 1/ps (1e-4/ps = 1e-7/fs)", r::kStrainRatePerPs,
                   default_of(d::kStrainRatePerPs)) +
         "                       (cyclic: the mean rate over a half cycle, default " +
         default_of(d::kCyclicStrainRatePerPs) + ")\n" +
         flag_help("--ramp PS", "smooth ramp to the rate", r::kRampPs, default_of(d::kRampPs)) +
         flag_help("--cycles N", "cycles (cyclic)", r::kCycles, std::to_string(d::kCycles)) +
         flag_help("--amplitude PCT", "cyclic amplitude", r::kAmplitudePercent,
                   default_of(d::kAmplitudePercent)) +
         flag_help("--grip-width NM", "depth of each grip", r::kGripWidthNm,
                   default_of(d::kGripWidthNm)) +
         "  --zero-velocities    zero velocities and spins when the test starts\n"
         "  --report-strains A,B,...  strains (%) for pores and aligned pairs (default 0,2,10,20)\n"
         "  --report-times T,...  relaxation times (ps) for pores (default "
         "0,1000,2000,3000,4000,4500)\n";
}

constexpr const char* kTensileAbout =
    "Stretches (or cycles) a thin film of randomly laid (10,10) CNTs, optionally filled with\n"
    "Si nanoparticles (thesis Ch. 5): the film of --size (or --side, --tubes, --segments) is\n"
    "generated from --seed, pre-relaxed, relaxed hands-off for --relax ps, then pulled by two\n"
    "clamped grips (--grip-width) at --rate after a smooth --ramp to --strain, or cycled.\n"
    "Reports the stress-strain curve, Young's modulus, yield strain, tubes in tension,\n"
    "shrinkage, toughness, and per cycle the loop area and modulus.\n"
    "--dt sets the step of the relaxation and the test (the thesis's: 0.03); the pre-\n"
    "relaxations pick their own. A --dt above the automatic step's bound is checked against\n"
    "the pre-relaxed film's critical step, measured, and must be within --safety of it.\n";

std::string stages_text(const v1::TensileSpec& t) {
  std::ostringstream o;
  o << "pre-relax <= " << t.prerelax_max_ps() << " ps, ";
  if (t.relax_ps() > 0)
    o << "relax " << t.relax_ps() << " ps, ";
  else
    o << "ready-to-relax, ";
  if (t.mode() == v1::CYCLIC)
    o << t.cycles() << " cycles to -" << t.amplitude_percent() << " % at " << t.strain_rate_per_ps()
      << "/ps";
  else
    o << "tensile to " << t.target_strain_percent() << " % at " << t.strain_rate_per_ps()
      << "/ps (ramp " << t.ramp_ps() << " ps)";
  return o.str();
}

std::string describe_tensile(Job& job, const v1::JobSpec& spec) {
  std::ostringstream o;
  o << tensile_film_text(spec.tensile()) << ", " << stages_text(spec.tensile());
  if (job.duration() > 0) o << ", " << job.duration() << " ps";
  return o.str();
}

std::string building_tensile(const v1::JobSpec& spec) {
  return "generating a " + tensile_film_text(spec.tensile());
}

}  // namespace

std::string tensile_film_text(const v1::TensileSpec& t) {
  const spec::FilmPreset p = spec::film_preset(t.size());
  const bool preset = t.side_nm() == p.side_nm && t.tubes() == p.tubes &&
                      t.segments_per_tube() == p.segments_per_tube &&
                      t.thickness_nm() == spec::defaults::kThicknessNm;
  std::ostringstream o;
  o << (preset ? std::string(size_word(t.size())) + " film " : std::string("film ")) << t.side_nm()
    << "×" << t.side_nm() << "×" << t.thickness_nm() << " nm, " << t.tubes() << " tubes × "
    << t.segments_per_tube() << " segments";
  if (t.nanoparticles() > 0)
    o << " + " << t.nanoparticles() << " NPs"
      << (t.np_deposit() == v1::BEFORE_RELAX ? " (before relaxing)" : " (after relaxing)");
  return o.str();
}

SpecKind tensile_kind() {
  return {"tensile",
          v1::JobSpec::kTensile,
          tensile_flag_fields,
          {"--zero-velocities", "--dashpot-shear"},
          apply_tensile_flags,
          kTensileAbout,
          tensile_flags_help(),
          describe_tensile,
          building_tensile};
}

}  // namespace mdem::cli
