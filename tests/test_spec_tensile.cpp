// The tensile job spec (mdem.v1.TensileSpec): Table 5-1's presets and tensile.md's defaults, every
// field's range with wrong, missing, huge and non-finite values, the cross-field rules (element
// count, NP room, grips, loading time, report points), and the JSON and YAML round trip.
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "mdem/job/tensile_job.h"
#include "mdem/spec.h"
#include "mdem/spec_job.h"
#include "spec_support.h"

using google::protobuf::util::MessageDifferencer;
using mdem::spec::FieldError;
using namespace mdem::testing;
using mdem::v1::JobSpec;
using mdem::v1::TensileSpec;

namespace {

// ---- defaults ----

TEST(SpecTensileDefaults, EmptyTensileIsTheSmallFilmOfTable51) {
  const JobSpec spec = finalized_json(R"({"tensile":{}})");
  ASSERT_EQ(spec.kind_case(), JobSpec::kTensile);
  const TensileSpec& t = spec.tensile();
  EXPECT_EQ(t.size(), mdem::v1::FILM_SMALL);
  EXPECT_DOUBLE_EQ(t.side_nm(), 300.0);
  EXPECT_DOUBLE_EQ(t.thickness_nm(), 11.0);
  EXPECT_EQ(t.tubes(), 200);
  EXPECT_EQ(t.segments_per_tube(), 200);  // round(271.2 nm / 1.356 nm)
  EXPECT_DOUBLE_EQ(t.max_tilt_deg(), 2.0);
  EXPECT_EQ(t.nanoparticles(), 0);
  EXPECT_EQ(t.np_deposit(), mdem::v1::AFTER_RELAX);
  EXPECT_DOUBLE_EQ(t.prerelax_max_ps(), 50.0);
  EXPECT_DOUBLE_EQ(t.relax_ps(), 4500.0);
  EXPECT_DOUBLE_EQ(t.vdw_damping_ratio(), 0.03);
  EXPECT_DOUBLE_EQ(t.local_damping(), 0.0);  // hands-off (§3.4), not twist's 0.1
  EXPECT_EQ(t.mode(), mdem::v1::MONOTONIC);
  EXPECT_DOUBLE_EQ(t.target_strain_percent(), 20.0);
  EXPECT_DOUBLE_EQ(t.strain_rate_per_ps(), 1e-4);  // 1e-7 /fs
  EXPECT_DOUBLE_EQ(t.ramp_ps(), 600.0);
  EXPECT_EQ(t.cycles(), 6);
  EXPECT_DOUBLE_EQ(t.amplitude_percent(), 1.0);
  EXPECT_DOUBLE_EQ(t.grip_width_nm(), 15.0);
  EXPECT_TRUE(t.has_zero_velocities());
  EXPECT_FALSE(t.zero_velocities());
  EXPECT_TRUE(t.has_vdw_dashpot_shear());
  EXPECT_FALSE(t.vdw_dashpot_shear());  // the engine's normal-only dashpot
  EXPECT_EQ(
      std::vector<double>(t.report_strains_percent().begin(), t.report_strains_percent().end()),
      (std::vector<double>{0, 2, 10, 20}));
  EXPECT_EQ(std::vector<double>(t.report_times_ps().begin(), t.report_times_ps().end()),
            (std::vector<double>{0, 1000, 2000, 3000, 4000, 4500}));
  // 200 x 200 segments (tensile.md §1.1: 40 000).
  EXPECT_DOUBLE_EQ(mdem::spec::tensile_element_count(t), 40000.0);
  // 0.3 ramp + (0.2 - 0.03)/1e-4: 600/2 + 2000 = 2300 ps (§3.5: "20 % test: 2.3 ns").
  EXPECT_NEAR(mdem::spec::tensile_loading_ps(t), 2300.0, 1e-9);
}

TEST(SpecTensileDefaults, SizesFollowTable51AndNumbersOverrideThem) {
  const TensileSpec medium = finalized_json(R"({"tensile":{"size":"FILM_MEDIUM"}})").tensile();
  EXPECT_DOUBLE_EQ(medium.side_nm(), 500.0);
  EXPECT_EQ(medium.tubes(), 350);
  EXPECT_EQ(medium.segments_per_tube(), 350);
  EXPECT_DOUBLE_EQ(mdem::spec::tensile_element_count(medium), 122500.0);
  const TensileSpec large =
      finalized_json(R"({"tensile":{"size":"FILM_LARGE", "nanoparticles":10000}})").tensile();
  EXPECT_DOUBLE_EQ(large.side_nm(), 1000.0);
  EXPECT_EQ(large.tubes(), 500);
  EXPECT_EQ(large.segments_per_tube(), 700);
  EXPECT_DOUBLE_EQ(mdem::spec::tensile_element_count(large), 360000.0);  // §1.1
  const TensileSpec mixed =
      finalized_json(R"({"tensile":{"size":"FILM_MEDIUM", "tubes":20, "thickness_nm":20}})")
          .tensile();
  EXPECT_DOUBLE_EQ(mixed.side_nm(), 500.0);
  EXPECT_EQ(mixed.tubes(), 20);
  EXPECT_EQ(mixed.segments_per_tube(), 350);
  EXPECT_DOUBLE_EQ(mixed.thickness_nm(), 20.0);
}

TEST(SpecTensileDefaults, ReportPointsDefaultWithinTheirStage) {
  const TensileSpec t =
      finalized_json(R"({"tensile":{"target_strain_percent":5, "relax_ps":1500}})").tensile();
  EXPECT_EQ(
      std::vector<double>(t.report_strains_percent().begin(), t.report_strains_percent().end()),
      (std::vector<double>{0, 2}));
  EXPECT_EQ(std::vector<double>(t.report_times_ps().begin(), t.report_times_ps().end()),
            (std::vector<double>{0, 1000}));
  const TensileSpec given =
      finalized_json(R"({"tensile":{"report_strains_percent":[1, 3]}})").tensile();
  EXPECT_EQ(given.report_strains_percent_size(), 2);
  // A cyclic test reports per cycle: no strain points.
  EXPECT_EQ(
      finalized_json(R"({"tensile":{"mode":"CYCLIC"}})").tensile().report_strains_percent_size(),
      0);
}

TEST(SpecTensileDefaults, LoadingTimesFromTheClosedForms) {
  // Cyclic, by default at Table 5-5's rate: P = 2 a / rate = 2 x 0.01 / 5.7e-5 = 350.9 ps
  // (§3.6's table), six cycles.
  const TensileSpec cyc = finalized_json(R"({"tensile":{"mode":"CYCLIC"}})").tensile();
  EXPECT_DOUBLE_EQ(cyc.strain_rate_per_ps(), 5.7e-5);
  EXPECT_NEAR(mdem::spec::tensile_loading_ps(cyc) / 6.0, 350.877, 1e-3);
  // 300 % at 5e-4 /ps: ramp 0.6 ns + (3 - 0.15)/5e-4 = 5700 ps after it (§3.5).
  const TensileSpec big =
      finalized_json(R"({"tensile":{"target_strain_percent":300, "strain_rate_per_ps":5e-4}})")
          .tensile();
  EXPECT_NEAR(mdem::spec::tensile_loading_ps(big) - 600.0, 5700.0, 1e-9);
  // A target inside the ramp (1 % < 3 %) ends on it.
  EXPECT_DOUBLE_EQ(mdem::spec::tensile_loading_ps(
                       finalized_json(R"({"tensile":{"target_strain_percent":1}})").tensile()),
                   600.0);
}

// ---- ranges of each field ----

const std::vector<FieldCase>& field_cases() {
  static const std::vector<FieldCase> cases = {
      {R"({"tensile":{"side_nm":$}})",
       "tensile.side_nm",
       {"0", "-300", "2000.5", "1e+300"},
       "> 0 and <= 2000 nm"},
      {R"({"tensile":{"thickness_nm":$}})",
       "tensile.thickness_nm",
       {"0", "-11", "100.1", "1e+12"},
       "> 0 and <= 100 nm"},
      {R"({"tensile":{"tubes":$}})",
       "tensile.tubes",
       {"0", "-5", "100001"},
       ">= 1 and <= 1e+05",
       false},
      {R"({"tensile":{"segments_per_tube":$}})",
       "tensile.segments_per_tube",
       {"0", "-1", "100001", "2147483647"},
       ">= 1 and <= 1e+05",
       false},
      {R"({"tensile":{"max_tilt_deg":$}})",
       "tensile.max_tilt_deg",
       {"-0.1", "90.5", "1e+300"},
       ">= 0 and <= 90 degrees"},
      {R"({"tensile":{"nanoparticles":$}})",
       "tensile.nanoparticles",
       {"-1", "10000001", "2147483647"},
       ">= 0 and <= 1e+07 NPs",
       false},
      {R"({"tensile":{"prerelax_max_ps":$}})",
       "tensile.prerelax_max_ps",
       {"0", "-1", "10000.5"},
       "> 0 and <= 10000 ps"},
      {R"({"tensile":{"relax_ps":$}})",
       "tensile.relax_ps",
       {"-0.1", "1000001", "1e+300"},
       ">= 0 and <= 1e+06 ps; 0 = ready-to-relax"},
      {R"({"tensile":{"vdw_damping_ratio":$}})",
       "tensile.vdw_damping_ratio",
       {"-0.01", "1.5"},
       ">= 0 and <= 1"},
      {R"({"tensile":{"local_damping":$}})",
       "tensile.local_damping",
       {"-0.1", "0.995", "1"},
       ">= 0 and <= 0.99"},
      {R"({"tensile":{"target_strain_percent":$}})",
       "tensile.target_strain_percent",
       {"0", "-20", "300.5", "1e+06"},
       "> 0 and <= 300 %"},
      {R"({"tensile":{"strain_rate_per_ps":$}})",
       "tensile.strain_rate_per_ps",
       {"0", "-1", "0.011", "1"},
       "> 0 and <= 0.01 /ps; 1e-4 /ps = 1e-7 /fs"},
      {R"({"tensile":{"ramp_ps":$}})",
       "tensile.ramp_ps",
       {"0", "-600", "100001"},
       "> 0 and <= 1e+05 ps"},
      {R"({"tensile":{"mode":"CYCLIC", "cycles":$}})",
       "tensile.cycles",
       {"0", "-6", "1001"},
       ">= 1 and <= 1000 cycles",
       false},
      {R"({"tensile":{"mode":"CYCLIC", "amplitude_percent":$}})",
       "tensile.amplitude_percent",
       {"0", "-1", "50.5"},
       "> 0 and <= 50 %"},
      {R"({"tensile":{"grip_width_nm":$}})",
       "tensile.grip_width_nm",
       {"0", "-15", "500.5"},
       "> 0 and <= 500 nm"},
      {R"({"tensile":{"size":$}})",
       "tensile.size",
       {"4", "-1", "99"},
       "allowed: FILM_SMALL, FILM_MEDIUM, FILM_LARGE",
       false},
      {R"({"tensile":{"np_deposit":$}})",
       "tensile.np_deposit",
       {"3", "-2"},
       "allowed: AFTER_RELAX, BEFORE_RELAX",
       false},
      {R"({"tensile":{"mode":$}})",
       "tensile.mode",
       {"3", "7"},
       "allowed: MONOTONIC, CYCLIC",
       false},
      {R"({"tensile":{"report_strains_percent":[2, $]}})",
       "tensile.report_strains_percent[1]",
       {"-1", "20.5", "300"},
       ">= 0 and <= 20 %; target_strain_percent"},
      {R"({"tensile":{"report_times_ps":[$]}})",
       "tensile.report_times_ps[0]",
       {"-1", "4501", "1e+300"},
       ">= 0 and <= 4500 ps; relax_ps"},
  };
  return cases;
}

TEST(SpecTensileValidate, EachFieldOutOfRangeNamesFieldAndRange) {
  expect_each_out_of_range_refused(field_cases());
}

TEST(SpecTensileValidate, EachDoubleFieldRefusesNonFiniteJsonStrings) {
  expect_json_non_finite_refused(field_cases());
}

TEST(SpecTensileValidate, EachDoubleFieldRefusesNonFiniteYamlFloats) {
  expect_yaml_non_finite_refused(field_cases(), {".nan", ".inf", "-.inf"});
}

TEST(SpecTensileValidate, WrongTypeIsRefusedByTheParserNamingTheField) {
  for (const FieldCase& c : field_cases()) {
    if (c.field.find('[') != std::string::npos) continue;  // list items: below
    for (const std::string value : {"\"abc\"", "{}", "[1]", "true"}) {
      SCOPED_TRACE(c.field + " = " + value);
      const std::vector<FieldError> errors = json_errors(replace_value(c.json, value));
      ASSERT_EQ(errors.size(), 1u) << describe(errors);
      EXPECT_EQ(errors[0].field, "json");
      const std::string key = c.field.substr(c.field.rfind('.') + 1);
      EXPECT_NE(errors[0].message.find(key), std::string::npos) << errors[0].message;
    }
  }
  expect_one_error(json_errors(R"({"tensile":{"size":"small"}})"), "json", {"size"});
  expect_one_error(json_errors(R"({"tensile":{"zero_velocities":"yes"}})"), "json",
                   {"zero_velocities"});
  expect_one_error(json_errors(R"({"tensile":{"vdw_dashpot_shear":1.5}})"), "json",
                   {"vdw_dashpot_shear"});
  expect_one_error(json_errors(R"({"tensile":{"report_times_ps":["a"]}})"), "json",
                   {"report_times_ps"});
  expect_one_error(json_errors(R"({"tensile":{"strain_rate":1e-4}})"), "json", {"strain_rate"});
  expect_one_error(json_errors(R"({"tensile":{"tubes":1.5}})"), "json", {"tubes"});
}

TEST(SpecTensileValidate, EdgesOfEachRangeAreAccepted) {
  for (
      const std::string json : {
          R"({"tensile":{"side_nm":40, "thickness_nm":100, "tubes":1, "segments_per_tube":1,
               "max_tilt_deg":0, "nanoparticles":0, "prerelax_max_ps":1e-9, "relax_ps":0,
               "vdw_damping_ratio":0, "local_damping":0.99, "target_strain_percent":300,
               "strain_rate_per_ps":0.01, "ramp_ps":1e-9, "grip_width_nm":19.99,
               "zero_velocities":true, "vdw_dashpot_shear":true}})",
          R"({"tensile":{"side_nm":2000, "thickness_nm":1e-6, "tubes":20, "segments_per_tube":100000,
               "max_tilt_deg":90, "prerelax_max_ps":10000, "relax_ps":1e6, "vdw_damping_ratio":1,
               "target_strain_percent":1e-9, "strain_rate_per_ps":1e-9, "ramp_ps":100000,
               "grip_width_nm":500, "np_deposit":"BEFORE_RELAX", "report_times_ps":[1e6, 0]}})",
          R"({"tensile":{"mode":"CYCLIC", "cycles":1000, "amplitude_percent":50,
               "strain_rate_per_ps":0.01}})",
          R"({"tensile":{"mode":"CYCLIC", "cycles":1, "amplitude_percent":1e-9}})",
          R"({"tensile":{"size":"FILM_SIZE_UNSPECIFIED", "np_deposit":"NP_DEPOSIT_UNSPECIFIED",
               "mode":"TENSILE_MODE_UNSPECIFIED"}})",
          R"({"tensile":{"size":"FILM_LARGE", "nanoparticles":10000}})",
      }) {
    SCOPED_TRACE(json);
    EXPECT_TRUE(json_errors(json).empty()) << describe(json_errors(json));
  }
}

// ---- cross-field rules ----

TEST(SpecTensileValidate, HugeFilmIsRefusedBeforeAnythingIsBuilt) {
  // 100000 tubes x 100000 segments = 1e10 elements.
  expect_one_error(json_errors(R"({"tensile":{"tubes":100000, "segments_per_tube":100000}})"),
                   "tensile", {"1e+10 elements", "at most 2e+06"});
  // Just above and at the limit: 2000 x 1000 + 1 NP, 2000 x 1000.
  expect_one_error(json_errors(R"({"tensile":{"side_nm":2000, "tubes":2000,
      "segments_per_tube":1000, "nanoparticles":1}})"),
                   "tensile", {"2e+06 elements"});
  EXPECT_TRUE(json_errors(R"({"tensile":{"side_nm":2000, "tubes":2000, "segments_per_tube":1000}})")
                  .empty());
}

TEST(SpecTensileValidate, NanoparticlesMustFitTheSlab) {
  // tensile.md / docs/tensile.md: at most 18 294 NPs fit the small film by the ball bound.
  const double s = mdem::spec::kNpMinSpacingNm;
  const double most = 6.0 * (300 + s) * (300 + s) * (11 + s) / (std::numbers::pi * s * s * s);
  EXPECT_EQ(static_cast<long>(most), 18294);
  EXPECT_DOUBLE_EQ(mdem::spec::tensile_np_capacity(300, 11), most);
  expect_one_error(json_errors(R"({"tensile":{"nanoparticles":18295}})"), "tensile.nanoparticles",
                   {"18295 NPs cannot fit a 300 x 300 x 11 nm film", "at most 18294"});
  EXPECT_TRUE(json_errors(R"({"tensile":{"nanoparticles":18294}})").empty());
  // With an invalid side, only the side is reported.
  expect_one_error(json_errors(R"({"tensile":{"side_nm":-1, "nanoparticles":100}})"),
                   "tensile.side_nm", {"> 0"});
}

TEST(SpecTensileValidate, GripsMustNotMeet) {
  expect_one_error(json_errors(R"({"tensile":{"side_nm":30}})"), "tensile.grip_width_nm",
                   {"15 nm grips meet in a 30 nm film", "< 15 nm, half of side_nm"});
  expect_one_error(json_errors(R"({"tensile":{"grip_width_nm":200}})"), "tensile.grip_width_nm",
                   {"< 150 nm"});
  EXPECT_TRUE(json_errors(R"({"tensile":{"side_nm":31}})").empty());
}

TEST(SpecTensileValidate, EndlessLoadingIsRefused) {
  // 300 % at 1e-9 /ps: 3e9 ps.
  expect_one_error(json_errors(R"({"tensile":{"target_strain_percent":300,
      "strain_rate_per_ps":1e-9}})"),
                   "tensile.strain_rate_per_ps", {"3e+09 ps", "at most 1e+07 ps"});
  expect_one_error(json_errors(R"({"tensile":{"mode":"CYCLIC", "cycles":1000,
      "strain_rate_per_ps":1e-7}})"),
                   "tensile.strain_rate_per_ps", {"2e+08 ps"});
}

TEST(SpecTensileValidate, ReportPointsAreBoundedAndMatchTheMode) {
  std::string many = R"({"tensile":{"report_times_ps":[)";
  for (int i = 0; i < 101; ++i) many += (i ? "," : "") + std::to_string(i);
  expect_one_error(json_errors(many + "]}}"), "tensile.report_times_ps",
                   {"101 points listed", "at most 100"});
  expect_one_error(json_errors(R"({"tensile":{"mode":"CYCLIC", "report_strains_percent":[1]}})"),
                   "tensile.report_strains_percent", {"MONOTONIC"});
  // Points follow the given target and relaxation.
  expect_one_error(json_errors(R"({"tensile":{"relax_ps":0, "report_times_ps":[10]}})"),
                   "tensile.report_times_ps[0]", {"<= 0 ps; relax_ps"});
}

TEST(SpecTensileValidate, ManyBadFieldsAreAllReported) {
  const std::vector<FieldError> errors = json_errors(R"({"run":{"dt_ps":-1},
      "tensile":{"side_nm":"NaN", "tubes":0, "nanoparticles":-3, "relax_ps":-1,
                 "local_damping":1, "strain_rate_per_ps":0, "mode":5, "grip_width_nm":0}})");
  const std::vector<std::string> expected = {"run.dt_ps",
                                             "tensile.mode",
                                             "tensile.side_nm",
                                             "tensile.tubes",
                                             "tensile.nanoparticles",
                                             "tensile.relax_ps",
                                             "tensile.local_damping",
                                             "tensile.strain_rate_per_ps",
                                             "tensile.grip_width_nm"};
  std::vector<std::string> fields;
  for (const FieldError& e : errors) fields.push_back(e.field);
  EXPECT_EQ(fields, expected) << describe(errors);
}

TEST(SpecTensileValidate, MissingKindNamesTensile) {
  expect_one_error(json_errors("{}"), "kind", {"tensile"});
  expect_one_error(json_errors(R"({"tensile":{}, "twist":{}})"), "json", {"twist"});
}

TEST(SpecTensileValidate, ValidateAcceptsAnUnfinalizedSpec) {
  JobSpec spec;
  spec.mutable_tensile();
  EXPECT_TRUE(mdem::spec::validate(spec).empty());
  spec.mutable_tensile()->set_side_nm(20);  // default 15 nm grips meet
  expect_one_error(mdem::spec::validate(spec), "tensile.grip_width_nm", {"< 10 nm"});
}

// ---- JSON and YAML ----

TEST(SpecTensileJson, FinalizedSpecRoundTripsExactly) {
  for (const std::string json :
       {R"({"tensile":{}})",
        R"({"name":"small + 2000", "seed":"18446744073709551615", "tensile":{
            "size":"FILM_SMALL", "nanoparticles":2000, "np_deposit":"BEFORE_RELAX",
            "relax_ps":0, "zero_velocities":true, "report_strains_percent":[1.5]}})",
        R"({"tensile":{"mode":"CYCLIC", "size":"FILM_LARGE", "strain_rate_per_ps":5.7e-5}})"}) {
    SCOPED_TRACE(json);
    const JobSpec spec = finalized_json(json);
    const std::string text = mdem::spec::to_json(spec, true);
    const JobSpec back = mdem::spec::parse_json(text);
    EXPECT_TRUE(MessageDifferencer::Equals(spec, back)) << text;
    EXPECT_TRUE(MessageDifferencer::Equals(mdem::spec::finalize(back), spec));
  }
}

TEST(SpecTensileYaml, SameSpecAsYamlAndJsonGivesEqualMessages) {
  const JobSpec from_yaml = mdem::spec::parse_yaml(R"(
name: small film + 2000 NPs
seed: 3
tensile:
  size: FILM_SMALL
  nanoparticles: 2000
  strainRatePerPs: 1e-4        # lowerCamel works too
  target_strain_percent: 20
  report_strains_percent: [0, 2, 20]
  ramp_ps: ~                   # null: the default
)");
  const JobSpec from_json = mdem::spec::parse_json(R"({"name":"small film + 2000 NPs", "seed":3,
      "tensile":{"size":"FILM_SMALL", "nanoparticles":2000, "strain_rate_per_ps":1e-4,
      "target_strain_percent":20, "report_strains_percent":[0, 2, 20]}})");
  EXPECT_TRUE(MessageDifferencer::Equals(from_yaml, from_json));
  EXPECT_FALSE(from_yaml.tensile().has_ramp_ps());
  const JobSpec spec = mdem::spec::finalize(from_yaml);
  EXPECT_TRUE(
      MessageDifferencer::Equals(mdem::spec::parse_yaml(mdem::spec::to_json(spec, true)), spec));
}

TEST(SpecTensileYaml, WrongValuesAreRefusedWithTheirField) {
  expect_one_error(yaml_errors("tensile:\n  side_nm: wide\n"), "yaml", {"side_nm"});
  expect_one_error(yaml_errors("tensile:\n  mode: pull\n"), "yaml", {"mode"});
  expect_one_error(yaml_errors("tensile:\n  target_strain_percent: 1e6\n"),
                   "tensile.target_strain_percent", {"1e+06 is out of range"});
  expect_one_error(yaml_errors("tensile:\n  nanoparticles: 99999999999\n"), "yaml",
                   {"nanoparticles"});
  expect_one_error(yaml_errors("tensile: [1, 2]\n"), "yaml", {"tensile"});
}

}  // namespace

// The spec's damping choices reach the engine's job spec (jobs/src/tensile_job_kind.cpp).
TEST(SpecTensileJob, DampingChoicesReachTheEngine) {
  const mdem::TensileJobSpec plain = mdem::tensile_job_spec(finalized_json(R"({"tensile":{}})"));
  EXPECT_FALSE(plain.laws.dashpot_shear);
  EXPECT_DOUBLE_EQ(plain.dashpot_ratio, 0.03);
  const mdem::TensileJobSpec thesis = mdem::tensile_job_spec(finalized_json(
      R"({"tensile":{"vdw_dashpot_shear":true, "vdw_damping_ratio":0.05, "local_damping":0.2}})"));
  EXPECT_TRUE(thesis.laws.dashpot_shear);
  EXPECT_DOUBLE_EQ(thesis.dashpot_ratio, 0.05);
  EXPECT_DOUBLE_EQ(thesis.local_damping, 0.2);
}
