// The kind registries (issue 12 item 6): a kind registered in each layer's registry flows from
// flags through validation, the job factory and the runner to its declared summary, with no
// switch edited; every declared summary value of the built-in kinds reaches the report's JSON and
// the printer; job states are one enum.
#include <gtest/gtest.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "../client/src/console.h"
#include "../client/src/spec_flags.h"
#include "mdem/core/units.h"
#include "mdem/job/twist_job.h"
#include "mdem/job_id.h"
#include "mdem/job_kinds.h"
#include "mdem/job_runner.h"
#include "mdem/job_state.h"
#include "mdem/spec.h"
#include "mdem/spec_kinds.h"
#include "mdem/spec_rules.h"

namespace {

using mdem::JobKind;
using mdem::SummaryField;
namespace v1 = mdem::v1;
namespace spec = mdem::spec;

// ---- a stand-in kind, "dummy", registered only in this test's own registries ----
// Protobuf's oneof is fixed when job.proto is compiled, so the stand-in keeps its settings in
// the TwistSpec message (a real new kind adds its own message and oneof field to job.proto).
// Everything else is its own: its rules (only 2 layers, a short hold), its factory, its flag
// table and its summary layout.

constexpr spec::Range kDummyLayers = spec::closed(2, 2, "layers", "the dummy rope has two");

spec::KindRules dummy_rules() {
  return {"dummy", v1::JobSpec::kTwist,
          [](v1::JobSpec& s) {
            v1::TwistSpec& t = *s.mutable_twist();
            if (!t.has_layers()) t.set_layers(2);
            if (!t.has_length_nm()) t.set_length_nm(4 * spec::kSegmentNm);
          },
          [](const v1::JobSpec& s, spec::Checks& checks) {
            checks.integer("dummy.layers", s.twist().has_layers(), s.twist().layers(),
                           kDummyLayers);
          }};
}

JobKind dummy_job_kind() {
  JobKind k;
  k.name = "dummy";
  k.kind_case = v1::JobSpec::kTwist;
  k.build = [](const v1::JobSpec& s, const mdem::IntegratorSettings& settings) {
    mdem::TwistJobSpec job;
    job.rope.layers = s.twist().layers();
    job.rope.segments = static_cast<int>(std::lround(s.twist().length_nm() / spec::kSegmentNm));
    job.loading.torque_max = mdem::units::nNnm(0.5);
    job.loading.rate = mdem::units::nNnm(5.0);
    job.loading.hold = 0.2;
    return std::unique_ptr<mdem::Job>(std::make_unique<mdem::TwistJob>(job, settings));
  };
  k.local_damping = [](const v1::JobSpec&) { return 0.2; };
  k.element_bound = [](const v1::JobSpec& s) { return 7L * 4; };
  k.summary = {
      {"elements", SummaryField::Type::Count, "", "pieces", 1, 6, true},
      {"rope_radius_nm", SummaryField::Type::Real, "nm", "dummy radius", 2, 4, false},
  };
  return k;
}

const mdem::cli::FlagFields& dummy_flag_fields() {
  static const mdem::cli::FlagFields f = {{"--size", "twist.layers"}};
  return f;
}

mdem::cli::SpecKind dummy_cli_kind() {
  return {"dummy",
          v1::JobSpec::kTwist,
          dummy_flag_fields,
          {},
          [](const mdem::cli::FlagValues& f, v1::JobSpec& s) {
            s.mutable_twist();
            if (f.count("--size"))
              s.mutable_twist()->set_layers(mdem::cli::spec_int("--size", f.at("--size")));
          },
          "A stand-in kind.\n",
          "Dummy:\n  --size N   layers\n",
          [](mdem::Job&, const v1::JobSpec&) { return std::string(); },
          [](const v1::JobSpec&) { return std::string(); }};
}

TEST(KindRegistry, AStandInKindFlowsFromFlagsToItsPrintedSummary) {
  spec::KindRulesRegistry rules = {dummy_rules()};
  mdem::JobKindRegistry jobs = {dummy_job_kind()};
  mdem::cli::SpecKindRegistry cli = {dummy_cli_kind()};
  const mdem::cli::SpecKind& kind = *cli.find("dummy");

  // Validation: the stand-in's own rule, under its own field name; the built-in twist rules
  // (2..10 layers) would have accepted 3.
  try {
    mdem::cli::spec_from_flags(kind, {{"--size", "3"}, {"--threads", "1"}}, rules);
    FAIL() << "3 layers passed the dummy's rules";
  } catch (const spec::SpecError& e) {
    ASSERT_EQ(e.errors().size(), 1u) << e.what();
    EXPECT_EQ(e.errors()[0].field, "dummy.layers");
    EXPECT_NE(e.errors()[0].message.find("the dummy rope has two"), std::string::npos);
  }
  EXPECT_NO_THROW(spec::finalize(
      mdem::cli::spec_from_flags(*mdem::cli::find_spec_kind("twist"), {{"--layers", "3"}})));

  // Defaults from the stand-in's rules; the factory of its registry builds and runs it.
  const v1::JobSpec s = mdem::cli::spec_from_flags(
      kind, {{"--threads", "1"}, {"--energy-every", "0.1"}, {"--snapshot-every", "0"}}, rules);
  EXPECT_EQ(s.twist().layers(), 2);
  EXPECT_EQ(jobs.of(s)->element_bound(s), 28);
  mdem::JobRunner runner(s, 1, jobs);
  EXPECT_EQ(runner.job().system().elements().size(), 7u * 4u);  // 7 tubes x 4 segments
  const mdem::JobOutcome outcome = runner.run({}, nullptr);
  ASSERT_EQ(outcome.state, v1::SUCCEEDED) << outcome.reason;
  const mdem::ReportJson doc = runner.report("j-dummy", outcome);
  EXPECT_EQ(doc["kind"], "dummy");
  EXPECT_EQ(doc["state"], "SUCCEEDED");
  // The summary in the declared order, the declared values first.
  const auto& summary = doc["summary"];
  ASSERT_GE(summary.size(), 2u);
  EXPECT_EQ(summary.begin().key(), "elements");
  EXPECT_EQ(std::next(summary.begin()).key(), "rope_radius_nm");
  EXPECT_EQ(summary["elements"], 28);
  // Printed from the layout: labels, units, the declared precision (4 digits).
  const std::vector<std::string> lines = mdem::summary_lines(jobs.find("dummy")->summary, summary);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0], "pieces 28");
  char radius[32];
  std::snprintf(radius, sizeof radius, "%.4g", summary["rope_radius_nm"].get<double>());
  EXPECT_EQ(lines[1], std::string("dummy radius ") + radius + " nm");
  EXPECT_EQ(mdem::summary_highlights(jobs.find("dummy")->summary, summary),
            std::vector<std::string>{"28 pieces"});

  // A registry refuses a kind twice (by name or by oneof case).
  EXPECT_THROW(jobs.add(dummy_job_kind()), std::logic_error);
  JobKind other = dummy_job_kind();
  other.name = "other";
  EXPECT_THROW(jobs.add(other), std::logic_error);
}

// Every built-in kind has its entry in each layer, under the same name and oneof case.
TEST(KindRegistry, EveryKindIsRegisteredInEveryLayer) {
  const auto& rules = spec::kind_rules().all();
  const auto& jobs = mdem::job_kinds().all();
  const auto& cli = mdem::cli::spec_kinds().all();
  ASSERT_EQ(rules.size(), jobs.size());
  ASSERT_EQ(rules.size(), cli.size());
  for (std::size_t i = 0; i < rules.size(); ++i) {
    EXPECT_EQ(rules[i].name, jobs[i].name);
    EXPECT_EQ(rules[i].name, cli[i].name);
    EXPECT_EQ(rules[i].kind_case, jobs[i].kind_case);
    EXPECT_EQ(rules[i].kind_case, cli[i].kind_case);
  }
}

// Runs a small job of a built-in kind through the shared runner.
mdem::ReportJson run_small(const std::string& kind, const std::vector<std::string>& flags) {
  mdem::cli::FlagValues f;
  for (std::size_t i = 0; i + 1 < flags.size(); i += 2) f[flags[i]] = flags[i + 1];
  const v1::JobSpec s = mdem::cli::spec_from_flags(*mdem::cli::find_spec_kind(kind), f);
  mdem::JobRunner runner(s, 1);
  const mdem::JobOutcome o = runner.run({}, nullptr);
  EXPECT_EQ(o.state, v1::SUCCEEDED) << o.reason;
  return runner.report("j-" + kind, o);
}

void expect_summary_declared_and_shown(const std::string& kind, const mdem::ReportJson& doc) {
  SCOPED_TRACE(kind);
  const mdem::SummaryLayout& layout = *mdem::summary_layout(kind);
  const auto& summary = doc["summary"];
  // Every value the engine reports is declared, and every declared value is reported: the
  // JSON holds exactly the layout's keys, in its order.
  std::vector<std::string> keys, declared;
  for (const auto& [k, v] : summary.items()) keys.push_back(k);
  for (const SummaryField& f : layout) declared.push_back(f.key);
  EXPECT_EQ(keys, declared);
  // The printer (print_report, as `mdem run` and `mdem watch` print) shows each one with its
  // label and unit.
  std::ostringstream out, err;
  mdem::cli::print_report(out, err, doc, std::nullopt);
  for (const SummaryField& f : layout) {
    ASSERT_TRUE(summary.contains(f.key)) << f.key;
    const std::string shown = f.label + " " + mdem::summary_value_text(f, summary[f.key]);
    // Line 0: in the JSON only (the accuracy line says the energy balance and dt); a count
    // whose negative value means none is not printed then.
    const bool none = f.none_if_negative && summary[f.key].get<double>() < 0;
    if (f.line != 0 && !none) {
      EXPECT_NE(out.str().find(shown), std::string::npos) << shown << "\n" << out.str();
    }
    // Types as declared.
    if (f.type == SummaryField::Type::Label) {
      EXPECT_TRUE(summary[f.key].is_string()) << f.key;
    } else if (f.type == SummaryField::Type::Count) {
      EXPECT_TRUE(summary[f.key].is_number_integer()) << f.key;
    } else {
      EXPECT_TRUE(summary[f.key].is_number()) << f.key;
    }
  }
  // The energy balance is said once.
  const std::string text = out.str();
  const std::size_t first = text.find("energy balance error");
  ASSERT_NE(first, std::string::npos) << text;
  EXPECT_EQ(text.find("energy balance error", first + 1), std::string::npos) << text;
}

TEST(KindRegistry, EveryDeclaredSummaryValueIsInTheJsonAndPrinted) {
  expect_summary_declared_and_shown(
      "twist", run_small("twist", {"--layers", "2", "--length", "8", "--torque", "1", "--hold", "1",
                                   "--threads", "1", "--snapshot-every", "0"}));
  expect_summary_declared_and_shown(
      "compression",
      run_small("compression", {"--outer-radius", "4", "--grain-radius", "1,1.5", "--peak", "1",
                                "--speed", "0.05", "--threads", "1", "--snapshot-every", "0"}));
}

// Reals print to the field's digits with its unit; a round-off zero prints as 0.
TEST(KindRegistry, SummaryValuesPrintToTheirDigitsAndRoundOffAsZero) {
  const SummaryField f{"x_nm", SummaryField::Type::Real, "nm", "x", 1, 4};
  EXPECT_EQ(mdem::summary_value_text(f, 702.774102409747), "702.8 nm");
  EXPECT_EQ(mdem::summary_value_text(f, 1.9e-13), "0 nm");
  EXPECT_EQ(mdem::summary_value_text(f, -1.9e-13), "0 nm");
  EXPECT_EQ(mdem::summary_value_text(f, 2.5e-6), "2.5e-06 nm");
  const SummaryField n{"n", SummaryField::Type::Count, "", "n", 1};
  EXPECT_EQ(mdem::summary_value_text(n, 7), "7");
}

TEST(JobState, OneEnumWithNamesAndFinality) {
  for (const v1::JobState s :
       {v1::QUEUED, v1::RUNNING, v1::SUCCEEDED, v1::FAILED, v1::CANCELLED, v1::TIMEOUT})
    EXPECT_EQ(mdem::parse_job_state(mdem::job_state_name(s)), s);
  EXPECT_EQ(mdem::job_state_name(v1::JOB_STATE_UNSPECIFIED), "QUEUED");
  EXPECT_FALSE(mdem::parse_job_state("DONE").has_value());
  EXPECT_FALSE(mdem::parse_job_state("succeeded").has_value());
  std::set<std::string> final_states;
  for (const char* n :
       {"QUEUED", "RUNNING", "SUCCEEDED", "FAILED", "CANCELLED", "TIMEOUT", "BOGUS"})
    if (mdem::is_final(std::string_view(n))) final_states.insert(n);
  // TIMEOUT has ended too (a ResumeJob may queue it again): a watch stops at it.
  EXPECT_EQ(final_states, (std::set<std::string>{"SUCCEEDED", "FAILED", "CANCELLED", "TIMEOUT"}));
}

// ---- ranges in flag help are the validation ranges (issue 12 item 8) ----

struct Interval {
  double lo, hi;
  bool lo_open, hi_open;
};

// The interval "[a, b]", "(a, b]", ... on a help line, if any.
std::optional<Interval> interval_on(const std::string& line) {
  static const std::regex re(
      R"(([\[(])(-?[0-9.]+(?:e[-+]?[0-9]+)?), (-?[0-9.]+(?:e[-+]?[0-9]+)?)([\])]))");
  std::smatch m;
  if (!std::regex_search(line, m, re)) return std::nullopt;
  return Interval{std::stod(m[2]), std::stod(m[3]), m[1] == "(", m[4] == ")"};
}

// Whether the proto field at a dotted path ("twist.layers") is an integer.
bool integer_field(const std::string& path) {
  const google::protobuf::Descriptor* d = v1::JobSpec::descriptor();
  const google::protobuf::FieldDescriptor* f = nullptr;
  std::stringstream ss(path);
  for (std::string part; std::getline(ss, part, '.');) {
    f = d->FindFieldByName(part);
    if (!f) return false;
    if (f->message_type()) d = f->message_type();
  }
  return f && f->cpp_type() == google::protobuf::FieldDescriptor::CPPTYPE_INT32;
}

std::string text_of(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// Whether validation refuses `value` for `field` given through `flag` as out of its range.
bool refused(const mdem::cli::SpecKind& kind, const std::string& flag, const std::string& field,
             double value) {
  try {
    mdem::cli::spec_from_flags(kind, {{flag, text_of(value)}});
  } catch (const spec::SpecError& e) {
    for (const spec::FieldError& f : e.errors())
      if (f.field == field && (f.message.find("out of range") != std::string::npos ||
                               f.message.find("not a finite") != std::string::npos))
        return true;
  }
  return false;
}

TEST(FlagHelp, RangesInTheHelpAreTheRangesValidationEnforces) {
  for (const mdem::cli::SpecKind& kind : mdem::cli::spec_kinds().all()) {
    SCOPED_TRACE(kind.name);
    const std::string help = mdem::cli::spec_flags_help(kind);
    mdem::cli::FlagFields fields = mdem::cli::common_flag_fields();
    for (const auto& ff : kind.flag_fields()) fields.push_back(ff);
    int checked = 0;
    for (const auto& [flag, field] : fields) {
      // The flag's own help line: "  --torque X   T_max, (0, 500] nN·nm (default 64)".
      const std::size_t at = help.find("\n  " + flag + " ");
      if (at == std::string::npos) continue;
      const std::string line = help.substr(at + 1, help.find('\n', at + 1) - at - 1);
      const std::optional<Interval> in = interval_on(line);
      if (!in) continue;
      SCOPED_TRACE(line);
      ++checked;
      const bool whole = integer_field(field);
      auto step = [&](double b) { return whole ? 1.0 : std::max(std::abs(b) * 1e-9, 1e-12); };
      // Each end: the end itself is allowed unless open, the next value outward never is;
      // inside an open end the next value is allowed.
      EXPECT_EQ(refused(kind, flag, field, in->lo), in->lo_open) << field << " at " << in->lo;
      EXPECT_TRUE(refused(kind, flag, field, in->lo - step(in->lo))) << field;
      EXPECT_EQ(refused(kind, flag, field, in->hi), in->hi_open) << field << " at " << in->hi;
      EXPECT_TRUE(refused(kind, flag, field, in->hi + step(in->hi))) << field;
      if (in->lo_open) {
        EXPECT_FALSE(refused(kind, flag, field, in->lo + step(in->lo))) << field;
      }
      if (in->hi_open) {
        EXPECT_FALSE(refused(kind, flag, field, in->hi - step(in->hi))) << field;
      }
    }
    // Every numeric flag with a fixed range states it: run 5, twist 10, compression 10.
    EXPECT_GE(checked, kind.name == "twist" ? 15 : 14);
  }
}

// One id generator serves mdem run (4 random hex digits) and mdemd (6).
TEST(JobId, TimeThenRandomHex) {
  EXPECT_TRUE(std::regex_match(mdem::new_job_id(), std::regex(R"(j-\d{8}-\d{6}-[0-9a-f]{4})")));
  EXPECT_TRUE(std::regex_match(mdem::new_job_id(6), std::regex(R"(j-\d{8}-\d{6}-[0-9a-f]{6})")));
  std::set<std::string> ids;
  for (int i = 0; i < 200; ++i) ids.insert(mdem::new_job_id(16));
  EXPECT_EQ(ids.size(), 200u);
  EXPECT_THROW(mdem::new_job_id(0), std::invalid_argument);
  EXPECT_THROW(mdem::new_job_id(17), std::invalid_argument);
}

// The run's accuracy line prints the energy-balance error and dt; a kind's layout keeps them in the
// JSON (line 0), so that the end block does not say them twice (a compression run did).
TEST(KindRegistry, AccuracyFieldsAreJsonOnlyInEveryLayout) {
  for (const mdem::JobKind& kind : mdem::job_kinds().all()) {
    nlohmann::ordered_json summary = nlohmann::ordered_json::object();
    for (const mdem::SummaryField& f : kind.summary) summary[f.key] = 1.0;
    for (const mdem::SummaryField& f : kind.summary) {
      if (f.key == "energy_balance_error" || f.key == "dt_ps" || f.key == "critical_dt_ps") {
        EXPECT_EQ(f.line, 0) << kind.name << ": " << f.key;
      }
    }
    const std::vector<std::string> lines = mdem::summary_lines(kind.summary, summary);
    EXPECT_FALSE(lines.empty()) << kind.name;
    for (const std::string& line : lines)
      EXPECT_EQ(line.find("energy balance error"), std::string::npos) << kind.name << ": " << line;
  }
}

}  // namespace
