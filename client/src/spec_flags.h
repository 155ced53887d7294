#pragma once
// The command-line flags that make a job spec, shared by `mdem run <kind>` and `mdem submit
// <kind>`: the flags every kind has (--spec, --name, --seed, run and output settings), the
// helpers a kind's own flags use (strict numbers, a choice of names for an enum), the job kinds
// the CLI builds from flags, and spec errors as usage lines naming the flag. Each kind's own
// flags are in <kind>_spec.{h,cpp}.
#include <initializer_list>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "flags.h"
#include "mdem/job/job.h"
#include "mdem/kind_registry.h"
#include "mdem/spec.h"
#include "mdem/spec_kinds.h"
#include "mdem/spec_rules.h"
#include "mdem/v1/job.pb.h"

namespace mdem::cli {

using FlagValues = std::map<std::string, std::string>;
// Flag -> dotted spec field, in help order; a flag may set more than one field.
using FlagFields = std::vector<std::pair<std::string, std::string>>;

// --name, --seed, --dt, --safety, --threads, --energy-every, --snapshot-every.
const FlagFields& common_flag_fields();
// Sets the spec fields of the common flags that are given.
void apply_common_flags(const FlagValues& f, v1::JobSpec& spec);

// Any finite number; the range is spec::validate's job (it names the field and the range).
double spec_number(const std::string& flag, const std::string& text);
// A whole number that fits a proto int32.
int spec_int(const std::string& flag, const std::string& text);
// `s` split at each `sep`.
std::vector<std::string> split(const std::string& s, char sep);

// The enum value named by a flag that takes one of a fixed set of names; UsageError naming the
// flag and the names otherwise.
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

// A job kind `mdem run` and `mdem submit` build from flags.
struct SpecKind {
  std::string name;  // "twist": the command word and JobSpec's oneof field
  v1::JobSpec::KindCase kind_case;
  const FlagFields& (*flag_fields)();  // the kind's own flags
  std::set<std::string> switches;      // those of its own flags that take no value
  // Sets the kind's fields from its given flags (and selects the kind, even with none given).
  void (*apply_flags)(const FlagValues& f, v1::JobSpec& spec);
  const char* about;       // what the job does, for the help of `mdem run <kind>`
  std::string flags_help;  // help of the kind's own flags, its sections with their titles
  // A line on the built job before it runs (stderr of `mdem run`), and one while it is built
  // (may be empty).
  std::string (*describe)(Job& job, const v1::JobSpec& spec);
  std::string (*building)(const v1::JobSpec& spec);
};

// The client's registry of job kinds: one entry per kind (its flag table, help and lines), one
// line per kind in spec_kinds() (spec_flags.cpp); the kind's spec rules and job factory are
// registered in the proto and jobs layers under the same name.
using SpecKindRegistry = KindRegistry<SpecKind>;
const SpecKindRegistry& spec_kinds();
// The kind named `name`, or nullptr.
const SpecKind* find_spec_kind(const std::string& name);
// "twist, compression"
std::string spec_kind_names();

// All flags of a kind's spec: --spec, the common flags and the kind's own. A command adds its own.
FlagSpec spec_flag_spec(const SpecKind& kind);
// The finalized spec of parsed flags: --spec FILE (if given), the flags over it, then
// spec::finalize. Throws UsageError (a bad flag, a file of another kind) or spec::SpecError.
v1::JobSpec spec_from_flags(const SpecKind& kind, const FlagValues& given,
                            const spec::KindRulesRegistry& rules = spec::kind_rules());

// A spec error as usage lines: each field, the flag that sets it, and what is allowed.
std::string describe_spec_error(const spec::SpecError& e);

// One line of flag help with the field's allowed range and default from the spec rules
// (mdem/spec_rules.h), so help and validation cannot disagree:
// "  --torque X           T_max, (0, 500] nN·nm (default 64)". default_text may be empty.
std::string flag_help(std::string_view usage, std::string_view text, const spec::Range& range,
                      std::string_view default_text);
// A default for flag_help: the number as validation prints it ("67.8", "1e+06").
std::string default_of(double v);

// Help of the flags of spec_flag_spec(kind): Spec, the kind's sections, Run.
std::string spec_flags_help(const SpecKind& kind);
// The same for every kind: Spec, each kind's sections under its name, Run.
std::string all_spec_flags_help();

}  // namespace mdem::cli
