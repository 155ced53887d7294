#pragma once
// What a study varies: `--vary FIELD=v1,v2,...` resolved to a numeric field of the job spec
// (a scalar of the kind's message, of run or outputs, or the seed), by its dotted path
// ("run.safety"), its own name ("safety") or its flag ("rate" for --rate); and the runs of a
// study, the cartesian product of the varied values, each a finalized spec. The ranges are the
// spec rules' (spec::validate): a value out of range is refused with the field's allowed range
// before anything runs.
#include <cstddef>
#include <string>
#include <vector>

#include "spec_flags.h"

namespace mdem::cli {

// Most runs a study may have (the product of its value counts).
inline constexpr std::size_t kMaxStudyRuns = 64;

struct VariedField {
  std::string path;      // dotted proto path: "run.safety", "twist.torque_rate_nn_nm_per_ps"
  bool integer = false;  // an integer field (layers, threads, seed): values must be whole
  std::vector<double> values;
};

// Every name `--vary` accepts for the kind, dotted paths first: "seed", "run.dt_ps", ...,
// "twist.layers", ...
std::vector<std::string> variable_fields(const SpecKind& kind);

// Parses one `--vary` argument, "NAME=v1,v2,...". UsageError naming what is wrong and what is
// allowed: no '=', an unknown or non-numeric field (with the allowed names and the closest
// one), an empty list or item, a value that is not a number or not finite, a fraction for an
// integer field, a value listed twice.
VariedField parse_vary(const SpecKind& kind, const std::string& text);

// The study's points: the cartesian product of the fields' values, the first field varying
// slowest. UsageError when there are no fields, a field is varied twice, or the product
// exceeds kMaxStudyRuns.
std::vector<std::vector<double>> study_points(const std::vector<VariedField>& fields);

// `base` (a finalized spec) with the point's values set, finalized. UsageError naming the
// --vary value and the field's allowed range when the spec rules refuse it.
v1::JobSpec varied_spec(const v1::JobSpec& base, const std::vector<VariedField>& fields,
                        const std::vector<double>& point);

// Checks every point's spec (all values of all fields) before anything runs; also refuses a
// varied run.safety when the base spec fixes run.dt_ps (the safety factor would do nothing).
void check_study(const v1::JobSpec& base, const std::vector<VariedField>& fields);

// "safety=0.3" / "safety=0.3, rate=2": a point in words, the fields by their short names.
std::string point_text(const std::vector<VariedField>& fields, const std::vector<double>& point);
// Whether the spec field at the dotted path holds whole numbers (layers, seed); false for a
// real or a path that is no field.
bool integer_field(const std::string& path);
// "safety": the last component of a dotted path.
std::string short_name(const std::string& path);

}  // namespace mdem::cli
