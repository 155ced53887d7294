// The compression job spec (mdem.v1.CompressionSpec): documented defaults and the material
// presets, every field's range with wrong, missing, huge and non-finite values, the cross-field
// rules (shell, grain size, peak, grain count), the JSON and YAML round trip, and the spec in
// engine terms (units, element bound).
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "mdem/core/units.h"
#include "mdem/spec.h"
#include "mdem/spec_job.h"
#include "spec_support.h"

using google::protobuf::util::MessageDifferencer;
using mdem::spec::FieldError;
using mdem::spec::SpecError;
using namespace mdem::testing;
using mdem::v1::CompressionSpec;
using mdem::v1::JobSpec;

namespace {

// ---- defaults ----

TEST(SpecCompressionDefaults, EmptyCompressionGetsEveryDocumentedDefault) {
  const JobSpec spec = finalized_json(R"({"compression":{}})");
  ASSERT_EQ(spec.kind_case(), JobSpec::kCompression);
  EXPECT_DOUBLE_EQ(spec.run().safety(), 0.6);
  EXPECT_FALSE(spec.run().has_dt_ps());
  const CompressionSpec& c = spec.compression();
  EXPECT_DOUBLE_EQ(c.outer_radius_nm(), 10.0);
  EXPECT_TRUE(c.has_inner_radius_nm());
  EXPECT_DOUBLE_EQ(c.inner_radius_nm(), 0.0);
  EXPECT_DOUBLE_EQ(c.grain_radius_min_nm(), 1.0);
  EXPECT_DOUBLE_EQ(c.grain_radius_max_nm(), 2.0);
  EXPECT_DOUBLE_EQ(c.porosity(), 0.4);
  EXPECT_EQ(c.material(), mdem::v1::GOLD);
  EXPECT_DOUBLE_EQ(c.youngs_gpa(), 79.0);
  EXPECT_DOUBLE_EQ(c.poisson(), 0.46);
  EXPECT_DOUBLE_EQ(c.density_g_cm3(), 19.3);
  EXPECT_EQ(c.bond(), mdem::v1::PLASTIC);
  EXPECT_DOUBLE_EQ(c.strength_gpa(), 8.0);
  EXPECT_DOUBLE_EQ(c.platen_speed_nm_per_ps(), 0.01);
  EXPECT_DOUBLE_EQ(c.peak_displacement_nm(), 4.0);  // 0.4 x outer_radius_nm
  EXPECT_TRUE(c.has_unload());
  EXPECT_TRUE(c.unload());
  EXPECT_DOUBLE_EQ(c.viscous_ratio(), 0.5);
  EXPECT_DOUBLE_EQ(c.local_damping(), 0.7);  // this kind's own, not twist's 0.1
  // (1 - 0.4) x 10^3 / ((1 + 2)(1 + 4)/4) = 160 grains.
  EXPECT_NEAR(mdem::spec::compression_grain_estimate(c), 160.0, 1e-9);
}

TEST(SpecCompressionDefaults, PeakDefaultFollowsTheOuterRadius) {
  EXPECT_DOUBLE_EQ(finalized_json(R"({"compression":{"outer_radius_nm":2, "grain_radius_min_nm":1,
          "grain_radius_max_nm":1}})")
                       .compression()
                       .peak_displacement_nm(),
                   0.8);
  EXPECT_DOUBLE_EQ(
      finalized_json(R"({"compression":{"outer_radius_nm":105, "inner_radius_nm":75}})")
          .compression()
          .peak_displacement_nm(),
      42.0);
  // An invalid radius is reported on its own, not again through the peak.
  expect_one_error(json_errors(R"({"compression":{"outer_radius_nm":5000}})"),
                   "compression.outer_radius_nm", {"5000 is out of range"});
}

TEST(SpecCompressionDefaults, CadmiumSulfideGetsItsOwnPreset) {
  const CompressionSpec c =
      finalized_json(R"({"compression":{"material":"CADMIUM_SULFIDE"}})").compression();
  EXPECT_DOUBLE_EQ(c.youngs_gpa(), 28.0);
  EXPECT_DOUBLE_EQ(c.poisson(), 0.46);
  EXPECT_DOUBLE_EQ(c.density_g_cm3(), 4.82);
  EXPECT_EQ(c.bond(), mdem::v1::BRITTLE);
  EXPECT_DOUBLE_EQ(c.strength_gpa(), 4.0);
}

TEST(SpecCompressionDefaults, GivenValuesOverrideThePreset) {
  const CompressionSpec c = finalized_json(R"({"compression":{"material":"GOLD",
      "youngs_gpa":50, "poisson":0, "bond":"BRITTLE", "strength_gpa":2, "unload":false,
      "viscous_ratio":0, "local_damping":0}})")
                                .compression();
  EXPECT_DOUBLE_EQ(c.youngs_gpa(), 50.0);
  EXPECT_DOUBLE_EQ(c.poisson(), 0.0);
  EXPECT_DOUBLE_EQ(c.density_g_cm3(), 19.3);
  EXPECT_EQ(c.bond(), mdem::v1::BRITTLE);
  EXPECT_DOUBLE_EQ(c.strength_gpa(), 2.0);
  EXPECT_FALSE(c.unload());
  EXPECT_DOUBLE_EQ(c.viscous_ratio(), 0.0);
  EXPECT_DOUBLE_EQ(c.local_damping(), 0.0);
}

TEST(SpecCompressionDefaults, CustomMaterialGetsNoPresetAndElasticBonds) {
  const CompressionSpec c = finalized_json(R"({"compression":{"material":"CUSTOM",
      "youngs_gpa":100, "poisson":0.3, "density_g_cm3":8}})")
                                .compression();
  EXPECT_EQ(c.bond(), mdem::v1::ELASTIC);
  EXPECT_FALSE(c.has_strength_gpa());  // elastic bonds need none
  EXPECT_DOUBLE_EQ(c.youngs_gpa(), 100.0);
}

// ---- ranges of each field ----

const std::vector<FieldCase>& field_cases() {
  static const std::vector<FieldCase> cases = {
      {R"({"compression":{"outer_radius_nm":$}})",
       "compression.outer_radius_nm",
       {"1.99", "1000.5", "0", "-10", "1e+300"},
       ">= 2 and <= 1000 nm"},
      {R"({"compression":{"inner_radius_nm":$}})",
       "compression.inner_radius_nm",
       {"-0.1", "1001", "-1e+300"},
       ">= 0 and <= 1000 nm"},
      {R"({"compression":{"grain_radius_min_nm":$}})",
       "compression.grain_radius_min_nm",
       {"0.19", "0", "-1", "101"},
       ">= 0.2 and <= 100 nm"},
      {R"({"compression":{"grain_radius_max_nm":$}})",
       "compression.grain_radius_max_nm",
       {"0.1", "0", "-2", "100.5"},
       ">= 0.2 and <= 100 nm"},
      {R"({"compression":{"porosity":$}})",
       "compression.porosity",
       {"0.2", "0.95", "0", "1", "-0.4", "0.1"},
       "> 0.2 and < 0.95"},
      {R"({"compression":{"youngs_gpa":$}})",
       "compression.youngs_gpa",
       {"0", "-79", "2000.1", "1e+12"},
       "> 0 and <= 2000 GPa"},
      {R"({"compression":{"poisson":$}})",
       "compression.poisson",
       {"-0.01", "0.5", "0.7"},
       ">= 0 and < 0.5"},
      {R"({"compression":{"density_g_cm3":$}})",
       "compression.density_g_cm3",
       {"0", "-19.3", "50.5"},
       "> 0 and <= 50 g/cm³"},
      {R"({"compression":{"strength_gpa":$}})",
       "compression.strength_gpa",
       {"0", "-8", "100.01"},
       "> 0 and <= 100 GPa"},
      {R"({"compression":{"platen_speed_nm_per_ps":$}})",
       "compression.platen_speed_nm_per_ps",
       {"0", "-0.05", "1.01", "1e+09"},
       "> 0 and <= 1 nm/ps"},
      // The default outer radius is 10 nm: the peak stays below its diameter.
      {R"({"compression":{"peak_displacement_nm":$}})",
       "compression.peak_displacement_nm",
       {"0", "-1", "20", "25"},
       "> 0 and < 20 nm; twice outer_radius_nm"},
      {R"({"compression":{"viscous_ratio":$}})",
       "compression.viscous_ratio",
       {"-0.1", "1.5"},
       ">= 0 and <= 1"},
      {R"({"compression":{"local_damping":$}})",
       "compression.local_damping",
       {"-0.1", "0.995", "1"},
       ">= 0 and <= 0.99"},
      {R"({"compression":{"material":$}})",
       "compression.material",
       {"4", "-1", "99"},
       "allowed: GOLD, CADMIUM_SULFIDE, CUSTOM",
       false},
      {R"({"compression":{"bond":$}})",
       "compression.bond",
       {"4", "-3"},
       "allowed: ELASTIC, PLASTIC, BRITTLE",
       false},
  };
  return cases;
}

TEST(SpecCompressionValidate, EachFieldOutOfRangeNamesFieldAndRange) {
  expect_each_out_of_range_refused(field_cases());
}

TEST(SpecCompressionValidate, EachDoubleFieldRefusesNonFiniteJsonStrings) {
  expect_json_non_finite_refused(field_cases());
}

TEST(SpecCompressionValidate, EachDoubleFieldRefusesNonFiniteYamlFloats) {
  expect_yaml_non_finite_refused(field_cases(), {".nan", ".inf", "-.inf"});
}

TEST(SpecCompressionValidate, WrongTypeIsRefusedByTheParserNamingTheField) {
  for (const FieldCase& c : field_cases())
    for (const std::string value : {"\"abc\"", "{}", "[1]", "true"}) {
      SCOPED_TRACE(c.field + " = " + value);
      const std::vector<FieldError> errors = json_errors(replace_value(c.json, value));
      ASSERT_EQ(errors.size(), 1u) << describe(errors);
      EXPECT_EQ(errors[0].field, "json");
      const std::string key = c.field.substr(c.field.rfind('.') + 1);
      EXPECT_NE(errors[0].message.find(key), std::string::npos) << errors[0].message;
    }
  expect_one_error(json_errors(R"({"compression":{"unload":"maybe"}})"), "json", {"unload"});
  expect_one_error(json_errors(R"({"compression":{"material":"SILVER"}})"), "json", {"material"});
  expect_one_error(json_errors(R"({"compression":{"outer_radius":10}})"), "json", {"outer_radius"});
}

TEST(SpecCompressionValidate, EdgesOfEachRangeAreAccepted) {
  for (const std::string json : {
           // The smallest particle: R1 = 2, grains of 1 nm fill it exactly across.
           R"({"compression":{"outer_radius_nm":2, "grain_radius_min_nm":1,
               "grain_radius_max_nm":1, "porosity":0.2000001, "peak_displacement_nm":3.999,
               "platen_speed_nm_per_ps":1, "viscous_ratio":0, "local_damping":0.99}})",
           R"({"compression":{"outer_radius_nm":1000, "inner_radius_nm":990,
               "grain_radius_min_nm":5, "grain_radius_max_nm":5, "porosity":0.9499,
               "peak_displacement_nm":1999, "viscous_ratio":1, "local_damping":0}})",
           R"({"compression":{"material":"CUSTOM", "youngs_gpa":2000, "poisson":0,
               "density_g_cm3":50, "bond":"PLASTIC", "strength_gpa":100}})",
           R"({"compression":{"material":"CUSTOM", "youngs_gpa":1e-9, "poisson":0.4999,
               "density_g_cm3":1e-9, "bond":"BRITTLE", "strength_gpa":1e-9}})",
           R"({"compression":{"material":"GRAIN_MATERIAL_UNSPECIFIED",
               "bond":"GRAIN_BOND_UNSPECIFIED"}})",
           R"({"compression":{"outer_radius_nm":50, "grain_radius_min_nm":0.2,
               "grain_radius_max_nm":0.2, "porosity":0.94}})",
           R"({"compression":{"outer_radius_nm":1000, "grain_radius_min_nm":100,
               "grain_radius_max_nm":100}})",
       }) {
    SCOPED_TRACE(json);
    EXPECT_TRUE(json_errors(json).empty()) << describe(json_errors(json));
  }
}

// ---- cross-field rules and missing values ----

TEST(SpecCompressionValidate, InnerRadiusMustBeBelowTheOuter) {
  expect_one_error(json_errors(R"({"compression":{"outer_radius_nm":50, "inner_radius_nm":50}})"),
                   "compression.inner_radius_nm",
                   {"50 is not below the outer radius", "< 50 nm, outer_radius_nm"});
  expect_one_error(json_errors(R"({"compression":{"inner_radius_nm":12}})"),
                   "compression.inner_radius_nm", {"< 10 nm"});
}

TEST(SpecCompressionValidate, GrainRadiiMustBeOrderedAndFitTheShell) {
  expect_one_error(
      json_errors(R"({"compression":{"grain_radius_min_nm":3, "grain_radius_max_nm":2}})"),
      "compression.grain_radius_min_nm", {"3 is above grain_radius_max_nm", "<= 2 nm"});
  // Shell 95/90: a wall of 5 nm holds grains of radius up to 2.5 nm.
  expect_one_error(json_errors(R"({"compression":{"outer_radius_nm":95, "inner_radius_nm":90,
      "grain_radius_min_nm":2, "grain_radius_max_nm":3}})"),
                   "compression.grain_radius_max_nm",
                   {"3 nm grains do not fit in the shell's wall of 5 nm", "<= 2.5 nm"});
  // A full sphere of radius 10 holds grains up to radius 5.
  expect_one_error(json_errors(R"({"compression":{"grain_radius_max_nm":5.5}})"),
                   "compression.grain_radius_max_nm", {"<= 5 nm"});
  EXPECT_TRUE(json_errors(R"({"compression":{"grain_radius_max_nm":5}})").empty());
}

TEST(SpecCompressionValidate, PeakFollowsTheOuterRadius) {
  expect_one_error(
      json_errors(R"({"compression":{"outer_radius_nm":95, "peak_displacement_nm":190}})"),
      "compression.peak_displacement_nm", {"190 is out of range", "< 190 nm"});
  EXPECT_TRUE(
      json_errors(R"({"compression":{"outer_radius_nm":95, "peak_displacement_nm":189}})").empty());
  // With an invalid outer radius, only that is reported (the peak's fixed range still holds).
  expect_one_error(
      json_errors(R"({"compression":{"outer_radius_nm":1, "peak_displacement_nm":5}})"),
      "compression.outer_radius_nm", {">= 2"});
}

TEST(SpecCompressionValidate, HugeGrainCountIsRefusedBeforeAnythingIsBuilt) {
  // (1 - 0.4) x 1000^3 / 1 = 6e8 grains.
  const std::string huge =
      R"({"compression":{"outer_radius_nm":1000, "grain_radius_min_nm":1,
          "grain_radius_max_nm":1}})";
  expect_one_error(json_errors(huge), "compression",
                   {"about 6e+08 grains", "at most 2000000 grains"});
  // Just below and above the limit: R1 = 150, grains of 1 nm, porosity 0.4 -> 2.025e6.
  expect_one_error(json_errors(R"({"compression":{"outer_radius_nm":150,
      "grain_radius_min_nm":1, "grain_radius_max_nm":1}})"),
                   "compression", {"2.02e+06 grains"});
  EXPECT_TRUE(json_errors(R"({"compression":{"outer_radius_nm":149,
      "grain_radius_min_nm":1, "grain_radius_max_nm":1}})")
                  .empty());
  // A particle with room for no grain.
  expect_one_error(json_errors(R"({"compression":{"outer_radius_nm":2, "grain_radius_min_nm":1,
      "grain_radius_max_nm":1, "porosity":0.94, "peak_displacement_nm":1}})"),
                   "compression", {"would hold no grain"});
}

TEST(SpecCompressionValidate, CustomMaterialNeedsItsPropertiesAndBondStrength) {
  const std::vector<FieldError> errors =
      json_errors(R"({"compression":{"material":"CUSTOM", "bond":"PLASTIC"}})");
  std::vector<std::string> fields;
  for (const FieldError& e : errors) {
    fields.push_back(e.field);
    EXPECT_NE(e.message.find("is required for material CUSTOM"), std::string::npos) << e.message;
    EXPECT_NE(e.message.find("allowed"), std::string::npos) << e.message;
  }
  EXPECT_EQ(fields,
            (std::vector<std::string>{"compression.youngs_gpa", "compression.poisson",
                                      "compression.density_g_cm3", "compression.strength_gpa"}))
      << describe(errors);
  expect_one_error(json_errors(R"({"compression":{"material":"CUSTOM", "youngs_gpa":70,
      "poisson":0.3, "density_g_cm3":2.7, "bond":"BRITTLE"}})"),
                   "compression.strength_gpa", {"required", "BRITTLE"});
}

TEST(SpecCompressionValidate, ManyBadFieldsAreAllReported) {
  const std::vector<FieldError> errors = json_errors(R"({"run":{"threads":-1},
      "compression":{"outer_radius_nm":"NaN", "porosity":0.99, "poisson":0.5,
                     "strength_gpa":-1, "platen_speed_nm_per_ps":0, "viscous_ratio":2,
                     "local_damping":1, "bond":9}})");
  const std::vector<std::string> expected = {"run.threads",
                                             "compression.outer_radius_nm",
                                             "compression.porosity",
                                             "compression.poisson",
                                             "compression.bond",
                                             "compression.strength_gpa",
                                             "compression.platen_speed_nm_per_ps",
                                             "compression.viscous_ratio",
                                             "compression.local_damping"};
  std::vector<std::string> fields;
  for (const FieldError& e : errors) fields.push_back(e.field);
  EXPECT_EQ(fields, expected) << describe(errors);
}

TEST(SpecCompressionValidate, MissingKindNamesCompression) {
  expect_one_error(json_errors("{}"), "kind", {"allowed: twist, compression"});
  // Two kinds: the oneof keeps one, protobuf refuses the second.
  expect_one_error(json_errors(R"({"twist":{}, "compression":{}})"), "json", {"compression"});
}

TEST(SpecCompressionValidate, ValidateAcceptsAnUnfinalizedSpec) {
  JobSpec spec;
  spec.mutable_compression();
  EXPECT_TRUE(mdem::spec::validate(spec).empty());
  spec.mutable_compression()->set_outer_radius_nm(3);  // default grains up to 2 nm: too big
  expect_one_error(mdem::spec::validate(spec), "compression.grain_radius_max_nm", {"<= 1.5 nm"});
}

// ---- JSON and YAML ----

TEST(SpecCompressionJson, FinalizedSpecRoundTripsExactly) {
  for (const std::string json :
       {R"({"compression":{}})",
        R"({"name":"Au shell", "seed":"18446744073709551615", "compression":{
            "outer_radius_nm":95, "inner_radius_nm":52, "grain_radius_min_nm":3,
            "grain_radius_max_nm":6, "material":"CADMIUM_SULFIDE", "bond":"ELASTIC",
            "unload":false, "viscous_ratio":0}})",
        R"({"compression":{"material":"CUSTOM", "youngs_gpa":70, "poisson":0.33,
            "density_g_cm3":2.7}})"}) {
    SCOPED_TRACE(json);
    const JobSpec spec = finalized_json(json);
    const std::string text = mdem::spec::to_json(spec, true);
    const JobSpec back = mdem::spec::parse_json(text);
    EXPECT_TRUE(MessageDifferencer::Equals(spec, back)) << text;
    EXPECT_TRUE(MessageDifferencer::Equals(mdem::spec::finalize(back), spec));
  }
  const std::string text = mdem::spec::to_json(finalized_json(R"({"compression":{}})"), false);
  for (const char* key :
       {"\"outer_radius_nm\":10", "\"inner_radius_nm\":0", "\"material\":\"GOLD\"",
        "\"bond\":\"PLASTIC\"", "\"unload\":true", "\"local_damping\":0.7"})
    EXPECT_NE(text.find(key), std::string::npos) << key << " in " << text;
}

TEST(SpecCompressionYaml, SameSpecAsYamlAndJsonGivesEqualMessages) {
  const JobSpec from_yaml = mdem::spec::parse_yaml(R"(
name: CdS shell
seed: 3
run: {threads: 2}
compression:
  outer_radius_nm: 105
  inner_radius_nm: 75
  grain_radius_min_nm: 3
  grain_radius_max_nm: 6
  porosity: .4
  material: CADMIUM_SULFIDE
  bond: BRITTLE
  strength_gpa: 4
  platenSpeedNmPerPs: 0.1      # lowerCamel works too
  peak_displacement_nm: 60
  unload: false
  viscous_ratio: ~             # null: the default
)");
  const JobSpec from_json = mdem::spec::parse_json(R"({"name":"CdS shell", "seed":3,
      "run":{"threads":2}, "compression":{"outer_radius_nm":105, "inner_radius_nm":75,
      "grain_radius_min_nm":3, "grain_radius_max_nm":6, "porosity":0.4,
      "material":"CADMIUM_SULFIDE", "bond":"BRITTLE", "strength_gpa":4,
      "platen_speed_nm_per_ps":0.1, "peak_displacement_nm":60, "unload":false}})");
  EXPECT_TRUE(MessageDifferencer::Equals(from_yaml, from_json));
  EXPECT_FALSE(from_yaml.compression().has_viscous_ratio());
  // The finalized spec printed as JSON reads back as YAML (JSON is YAML's flow style).
  const JobSpec spec = mdem::spec::finalize(from_yaml);
  EXPECT_TRUE(
      MessageDifferencer::Equals(mdem::spec::parse_yaml(mdem::spec::to_json(spec, true)), spec));
  EXPECT_DOUBLE_EQ(spec.compression().viscous_ratio(), 0.5);
}

TEST(SpecCompressionYaml, WrongValuesAreRefusedWithTheirField) {
  expect_one_error(yaml_errors("compression:\n  porosity: lots\n"), "yaml", {"porosity"});
  expect_one_error(yaml_errors("compression:\n  unload: maybe\n"), "yaml", {"unload"});
  expect_one_error(yaml_errors("compression:\n  material: gold\n"), "yaml", {"material"});
  expect_one_error(yaml_errors("compression:\n  outer_radius_nm: 1e6\n"),
                   "compression.outer_radius_nm", {"1e+06 is out of range"});
  expect_one_error(yaml_errors("compression: [1, 2]\n"), "yaml", {"compression"});
}

// ---- the spec in engine terms ----

TEST(SpecCompressionJob, EngineSpecIsInInternalUnits) {
  const JobSpec spec = finalized_json(R"({"seed":42, "compression":{"outer_radius_nm":95,
      "inner_radius_nm":52, "grain_radius_min_nm":3, "grain_radius_max_nm":6,
      "platen_speed_nm_per_ps":0.1, "peak_displacement_nm":40, "unload":false,
      "viscous_ratio":0.25, "local_damping":0.6}})");
  const mdem::CompressionJobSpec job = mdem::compression_job_spec(spec);
  EXPECT_EQ(job.particle.shape, mdem::PackingShape::Shell);
  EXPECT_DOUBLE_EQ(job.particle.r_outer, 95);
  EXPECT_DOUBLE_EQ(job.particle.r_inner, 52);
  EXPECT_DOUBLE_EQ(job.particle.grain_r_min, 3);
  EXPECT_DOUBLE_EQ(job.particle.grain_r_max, 6);
  EXPECT_DOUBLE_EQ(job.particle.target_porosity, 0.4);
  EXPECT_EQ(job.particle.seed, 42u);
  EXPECT_DOUBLE_EQ(job.particle.material.youngs, mdem::units::GPa(79));
  EXPECT_DOUBLE_EQ(job.particle.material.poisson, 0.46);
  EXPECT_NEAR(job.particle.material.density,
              19.3 * mdem::units::kGramPerCm3InAmuPerNm3 * mdem::units::kAmu, 1e-9);
  EXPECT_EQ(job.bond.behaviour, mdem::BondBehaviour::Plastic);
  EXPECT_DOUBLE_EQ(job.bond.strength, mdem::units::GPa(8));
  EXPECT_DOUBLE_EQ(job.bond.material.youngs, job.particle.material.youngs);
  EXPECT_DOUBLE_EQ(job.loading.speed, 0.1);
  EXPECT_DOUBLE_EQ(job.loading.peak_displacement, 40);
  EXPECT_FALSE(job.loading.unload);
  EXPECT_DOUBLE_EQ(job.viscous_ratio, 0.25);
  EXPECT_DOUBLE_EQ(mdem::integrator_settings(spec).local_damping, 0.6);
  EXPECT_EQ(mdem::job_kind_name(spec), "compression");
  // (1 - 0.4)(95^3 - 52^3) / ((3 + 6)(9 + 36)/4) = 4247.5 grains: ceil(1.01 x 4247.5 + 10)
  // + 2 platens.
  EXPECT_EQ(mdem::element_bound(spec), 4302);
  // The default material of the engine's presets matches the spec's.
  const mdem::GrainMaterial gold = mdem::gold(), cds = mdem::cadmium_sulfide();
  EXPECT_NEAR(job.particle.material.youngs, gold.youngs, 1e-9 * gold.youngs);
  EXPECT_NEAR(job.particle.material.density, gold.density, 1e-9 * gold.density);
  const mdem::CompressionJobSpec cjob = mdem::compression_job_spec(
      finalized_json(R"({"compression":{"material":"CADMIUM_SULFIDE"}})"));
  EXPECT_NEAR(cjob.particle.material.youngs, cds.youngs, 1e-9 * cds.youngs);
  EXPECT_NEAR(cjob.particle.material.density, cds.density, 1e-9 * cds.density);
  EXPECT_DOUBLE_EQ(cjob.particle.material.poisson, cds.poisson);
  EXPECT_EQ(cjob.bond.behaviour, mdem::BondBehaviour::Brittle);
  EXPECT_DOUBLE_EQ(cjob.bond.strength, mdem::units::GPa(4));
}

TEST(SpecCompressionJob, CustomElasticBondsHaveNoStrength) {
  const mdem::CompressionJobSpec job = mdem::compression_job_spec(finalized_json(
      R"({"compression":{"material":"CUSTOM", "youngs_gpa":70, "poisson":0.33,
          "density_g_cm3":2.7}})"));
  EXPECT_EQ(job.bond.behaviour, mdem::BondBehaviour::Elastic);
  EXPECT_DOUBLE_EQ(job.bond.strength, 0.0);
  EXPECT_DOUBLE_EQ(job.particle.material.youngs, mdem::units::GPa(70));
}

}  // namespace
