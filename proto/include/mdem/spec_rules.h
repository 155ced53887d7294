#pragma once
// The one source of job.proto's defaults and allowed ranges: apply_defaults and validate read
// them, and so does the CLI's flag help (a flag's range text is allowed_interval of its field's
// Range), so the three cannot disagree. Ranges the engine checks on its own (threads, dashpot
// ratios) are the engine's limits (mdem/core/limits.h), read here.
#include <cstddef>
#include <string>
#include <string_view>

#include "mdem/core/limits.h"

namespace mdem::spec {

inline constexpr double kSegmentNm = 1.356;  // (10,10) CNT segment length T

// An interval of allowed values, open or closed at each end, with the unit the message names.
struct Range {
  double lo;
  double hi;
  bool lo_open;
  bool hi_open;
  std::string_view unit;  // "" for counts
  std::string_view note;  // appended after "; " when not empty
};

// Closed [lo, hi], half-open (lo, hi] and [lo, hi).
constexpr Range closed(double lo, double hi, std::string_view unit, std::string_view note = {}) {
  return {lo, hi, false, false, unit, note};
}
constexpr Range above(double lo, double hi, std::string_view unit) {
  return {lo, hi, true, false, unit, {}};
}
constexpr Range below(double lo, double hi, std::string_view unit) {
  return {lo, hi, false, true, unit, {}};
}

bool contains(const Range& r, double v);
// "(allowed: > 0 and <= 500 nN·nm)"
std::string allowed(const Range& r);
// "(0, 500] nN·nm": the interval in mathematical notation with its unit, for flag help.
std::string interval_text(const Range& r);
// Shortest text that reads back as v: "67.8", "1e-06", "nan", "inf".
std::string number_text(double v);

namespace defaults {
inline constexpr double kSafety = 0.6;
inline constexpr int kThreads = 0;
inline constexpr int kRespaK = 1;
inline constexpr double kEnergyEveryPs = 1.0;
inline constexpr double kSnapshotEveryPs = 10.0;
inline constexpr unsigned long long kSeed = 1;
inline constexpr double kAngleDeg = 0.0;
inline constexpr int kWidth = 1;
inline constexpr double kLengthFraction = 1.0;
inline constexpr int kLayers = 6;
inline constexpr double kLengthNm = 67.8;
inline constexpr double kTorqueNnNm = 64.0;
inline constexpr double kTorqueRate = 1.0;
inline constexpr double kHoldPs = 100.0;
inline constexpr bool kUnload = false;
inline constexpr double kUnloadHoldPs = 50.0;
inline constexpr int kGripSegments = 1;
inline constexpr double kVdwDampingRatio = 0.03;
inline constexpr double kLocalDamping = 0.1;
inline constexpr double kTemperatureK = 0.0;
// compression (the grain material's defaults are in its material preset)
inline constexpr double kOuterRadiusNm = 10.0;
inline constexpr double kInnerRadiusNm = 0.0;
inline constexpr double kGrainRadiusMinNm = 1.0;
inline constexpr double kGrainRadiusMaxNm = 2.0;
inline constexpr double kPorosity = 0.4;
inline constexpr double kPlatenSpeed = 0.01;
// The peak displacement's default is this fraction of outer_radius_nm (20 % of the diameter).
inline constexpr double kPeakPerOuterRadius = 0.4;
inline constexpr bool kCompressionUnload = true;
inline constexpr double kViscousRatio = 0.5;
inline constexpr double kCompressionLocalDamping = 0.7;
// tensile (tensile.md §0 and §6; the film's size, side and tube counts come from its Table 5-1
// preset, tensile_preset())
inline constexpr double kThicknessNm = 11.0;
inline constexpr double kMaxTiltDeg = 2.0;
inline constexpr int kNanoparticles = 0;
inline constexpr double kPrerelaxMaxPs = 50.0;
inline constexpr double kRelaxPs = 4500.0;
inline constexpr double kTensileLocalDamping = 0.0;
inline constexpr double kTargetStrainPercent = 20.0;
inline constexpr double kStrainRatePerPs = 1e-4;          // 1e-7 /fs
inline constexpr double kCyclicStrainRatePerPs = 5.7e-5;  // Table 5-5: 5.7e-8 /fs
inline constexpr double kRampPs = 600.0;
inline constexpr int kCycles = 6;
inline constexpr double kAmplitudePercent = 1.0;
inline constexpr double kGripWidthNm = 15.0;
inline constexpr bool kZeroVelocities = false;
inline constexpr bool kVdwDashpotShear = false;
inline constexpr double kReportStrainsPercent[] = {0.0, 2.0, 10.0, 20.0};
inline constexpr double kReportTimesPs[] = {0.0, 1000.0, 2000.0, 3000.0, 4000.0, 4500.0};
}  // namespace defaults

namespace ranges {
inline constexpr Range kDtPs = closed(1e-6, 1.0, "ps");
inline constexpr Range kSafety = above(0.0, 1.0, "of the critical step");
inline constexpr Range kThreads = closed(0, limits::kMaxThreads, "threads", "0 = all cores");
inline constexpr Range kRespaK = closed(1, limits::kMaxRespaK, "steps per outer step", "1 = off");
inline constexpr Range kEnergyEveryPs = above(0.0, 1e6, "ps");
inline constexpr Range kSnapshotEveryPs = closed(0.0, 1e6, "ps", "0 = no snapshots");
inline constexpr Range kAngleDeg = below(0.0, 360.0, "degrees");
inline constexpr Range kWidth = closed(1, 3, "rows");
inline constexpr Range kLengthFraction = above(0.0, 1.0, "of the rope length");
inline constexpr Range kLayers = closed(2, 10, "layers");
inline constexpr Range kLengthNm = closed(5.0, 2000.0, "nm");
inline constexpr Range kSpacingNm = closed(1.5, 2.5, "nm", "unset = vdW equilibrium");
inline constexpr Range kTorqueNnNm = above(0.0, 500.0, "nN·nm");
inline constexpr Range kTorqueRate = above(0.0, 100.0, "nN·nm/ps");
inline constexpr Range kHoldPs = closed(0.0, 1e6, "ps");
inline constexpr Range kUnloadHoldPs = closed(0.0, 1e6, "ps");
inline constexpr Range kVdwDampingRatio = closed(0.0, limits::kMaxDashpotRatio, "");
inline constexpr Range kLocalDamping = closed(0.0, 0.99, "");
inline constexpr Range kTemperatureK = closed(0.0, 2000.0, "K");
inline constexpr Range kOuterRadiusNm = closed(2.0, 1000.0, "nm");
inline constexpr Range kInnerRadiusNm = closed(0.0, 1000.0, "nm", "0 = a full sphere");
inline constexpr Range kGrainRadiusNm = closed(0.2, 100.0, "nm");
inline constexpr Range kPorosity = {0.2, 0.95, true, true, "", {}};
inline constexpr Range kYoungsGpa = above(0.0, 2000.0, "GPa");
inline constexpr Range kPoisson = below(0.0, 0.5, "");
inline constexpr Range kDensity = above(0.0, 50.0, "g/cm³");
inline constexpr Range kStrengthGpa = above(0.0, 100.0, "GPa");
inline constexpr Range kPlatenSpeed = above(0.0, 1.0, "nm/ps");
inline constexpr Range kPeakDisplacementNm = above(0.0, 2000.0, "nm");
inline constexpr Range kViscousRatio = closed(0.0, limits::kMaxDashpotRatio, "");
// tensile
inline constexpr Range kSideNm = above(0.0, 2000.0, "nm");
inline constexpr Range kThicknessNm = above(0.0, 100.0, "nm");
inline constexpr Range kTubes = closed(1, 100000, "tubes");
inline constexpr Range kSegmentsPerTube = closed(1, 100000, "segments");
inline constexpr Range kMaxTiltDeg = closed(0.0, 90.0, "degrees");
inline constexpr Range kNanoparticles = closed(0, 10000000, "NPs");
inline constexpr Range kPrerelaxMaxPs = above(0.0, 10000.0, "ps");
inline constexpr Range kRelaxPs = closed(0.0, 1e6, "ps", "0 = ready-to-relax");
inline constexpr Range kTargetStrainPercent = above(0.0, 300.0, "%");
inline constexpr Range kStrainRatePerPs = {0.0, 0.01, true, false, "/ps", "1e-4 /ps = 1e-7 /fs"};
inline constexpr Range kRampPs = above(0.0, 100000.0, "ps");
inline constexpr Range kCycles = closed(1, 1000, "cycles");
inline constexpr Range kAmplitudePercent = above(0.0, 50.0, "%");
inline constexpr Range kGripWidthNm = above(0.0, 500.0, "nm");
inline constexpr std::size_t kMaxReportPoints = 100;
inline constexpr std::size_t kNameMaxChars = 200;
}  // namespace ranges

}  // namespace mdem::spec
