#include "spec_flags.h"

#include <algorithm>
#include <climits>
#include <sstream>

#include "compression_spec.h"
#include "tensile_spec.h"
#include "twist_spec.h"

namespace mdem::cli {

const FlagFields& common_flag_fields() {
  static const FlagFields m = {
      {"--name", "name"},
      {"--seed", "seed"},
      {"--dt", "run.dt_ps"},
      {"--safety", "run.safety"},
      {"--threads", "run.threads"},
      {"--respa-k", "run.respa_k"},
      {"--energy-every", "outputs.energy_every_ps"},
      {"--snapshot-every", "outputs.snapshot_every_ps"},
  };
  return m;
}

double spec_number(const std::string& flag, const std::string& text) {
  return parse_number(flag, text, "a finite number");
}

int spec_int(const std::string& flag, const std::string& text) {
  return static_cast<int>(parse_integer(flag, text, -2147483648L, 2147483647L));
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, sep);) out.push_back(item);
  return out;
}

void apply_common_flags(const FlagValues& f, v1::JobSpec& spec) {
  auto has = [&](const char* k) { return f.count(k) > 0; };
  auto val = [&](const char* k) { return f.at(k); };
  if (has("--name")) spec.set_name(val("--name"));
  if (has("--seed"))
    spec.set_seed(static_cast<std::uint64_t>(parse_integer("--seed", val("--seed"), 0, LONG_MAX)));
  if (has("--dt") && val("--dt") != "auto")
    spec.mutable_run()->set_dt_ps(spec_number("--dt", val("--dt")));
  if (has("--safety")) spec.mutable_run()->set_safety(spec_number("--safety", val("--safety")));
  if (has("--threads")) spec.mutable_run()->set_threads(spec_int("--threads", val("--threads")));
  if (has("--respa-k")) spec.mutable_run()->set_respa_k(spec_int("--respa-k", val("--respa-k")));
  if (has("--energy-every"))
    spec.mutable_outputs()->set_energy_every_ps(
        spec_number("--energy-every", val("--energy-every")));
  if (has("--snapshot-every"))
    spec.mutable_outputs()->set_snapshot_every_ps(
        spec_number("--snapshot-every", val("--snapshot-every")));
}

const SpecKindRegistry& spec_kinds() {
  static const SpecKindRegistry kinds = {twist_kind(), compression_kind(), tensile_kind()};
  return kinds;
}

const SpecKind* find_spec_kind(const std::string& name) { return spec_kinds().find(name); }

std::string spec_kind_names() { return spec_kinds().names(); }

FlagSpec spec_flag_spec(const SpecKind& kind) {
  FlagSpec fs;
  fs.with_value.push_back("--spec");
  for (const auto& [flag, field] : common_flag_fields()) fs.with_value.push_back(flag);
  for (const auto& [flag, field] : kind.flag_fields()) {
    std::vector<std::string>& names = kind.switches.count(flag) ? fs.switches : fs.with_value;
    if (std::find(names.begin(), names.end(), flag) == names.end()) names.push_back(flag);
  }
  return fs;
}

v1::JobSpec spec_from_flags(const SpecKind& kind, const FlagValues& given,
                            const spec::KindRulesRegistry& rules) {
  v1::JobSpec spec;
  if (given.count("--spec")) spec = spec::load_file(given.at("--spec"));
  if (spec.kind_case() != kind.kind_case && spec.kind_case() != v1::JobSpec::KIND_NOT_SET)
    throw UsageError("--spec: the file describes another job kind (allowed here: " + kind.name +
                     ")");
  apply_common_flags(given, spec);
  kind.apply_flags(given, spec);
  return spec::finalize(spec, rules);
}

std::string describe_spec_error(const spec::SpecError& e) {
  std::ostringstream o;
  for (const spec::FieldError& f : e.errors()) {
    std::string flag;
    auto match = [&](const FlagFields& fields) {
      for (const auto& [fl, field] : fields)
        if (flag.empty() && (f.field == field || f.field.rfind(field + "[", 0) == 0)) flag = fl;
    };
    match(common_flag_fields());
    for (const SpecKind& k : spec_kinds().all()) match(k.flag_fields());
    o << "  " << f.field << (flag.empty() ? "" : " (" + flag + ")") << ": " << f.message << "\n";
  }
  return o.str();
}

namespace {

constexpr const char* kSpecFileHelp =
    "Spec:\n"
    "  --spec FILE          a JobSpec as JSON or YAML (.json/.yaml/.yml); flags override it\n";

std::string run_flags_help() {
  namespace r = spec::ranges;
  namespace d = spec::defaults;
  return "Run:\n" +
         flag_help("--dt X|auto", "time step", r::kDtPs, "auto = safety x critical step") +
         flag_help("--safety X", "fraction of the critical step", r::kSafety,
                   default_of(d::kSafety)) +
         flag_help("--threads N", "OpenMP threads, 0 = all cores", r::kThreads,
                   default_of(d::kThreads)) +
         flag_help("--respa-k N", "multiple time stepping: slow pair forces every N steps",
                   r::kRespaK, default_of(d::kRespaK)) +
         flag_help("--energy-every X", "energy/observable frame interval", r::kEnergyEveryPs,
                   default_of(d::kEnergyEveryPs)) +
         flag_help("--snapshot-every X", "snapshot interval, 0 = none", r::kSnapshotEveryPs,
                   default_of(d::kSnapshotEveryPs)) +
         "  --name TEXT          a label for `mdem ls`\n"
         "  --seed N             random seed (default " +
         std::to_string(d::kSeed) + ")\n";
}

}  // namespace

std::string flag_help(std::string_view usage, std::string_view text, const spec::Range& range,
                      std::string_view default_text) {
  constexpr std::size_t kColumn = 23;  // where the text starts
  std::string line = "  " + std::string(usage);
  line.append(line.size() < kColumn ? kColumn - line.size() : 1, ' ');
  line.append(text);
  line += (text.empty() ? "" : ", ") + spec::interval_text(range);
  if (!default_text.empty()) line += " (default " + std::string(default_text) + ")";
  return line + "\n";
}

std::string default_of(double v) { return spec::number_text(v); }

std::string spec_flags_help(const SpecKind& kind) {
  return std::string(kSpecFileHelp) + kind.flags_help + run_flags_help();
}

std::string all_spec_flags_help() {
  std::string s = kSpecFileHelp;
  for (const SpecKind& k : spec_kinds().all()) s += "\n== " + k.name + " jobs ==\n" + k.flags_help;
  return s + "\n" + run_flags_help();
}

}  // namespace mdem::cli
