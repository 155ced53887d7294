// Job specs (proto/mdem/v1/job.proto, mdem/spec.h): defaults, validation of every field, the JSON
// and YAML readers, load_file and the JSON round trip.
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "mdem/spec.h"
#include "spec_support.h"

using google::protobuf::util::MessageDifferencer;
using mdem::spec::FieldError;
using mdem::spec::SpecError;
using namespace mdem::testing;
using mdem::v1::JobSpec;

namespace {

namespace fs = std::filesystem;

// ---- defaults ----

TEST(SpecDefaults, EmptyTwistGetsEveryDocumentedDefault) {
  const JobSpec spec = finalized_json(R"({"twist":{}})");
  EXPECT_TRUE(spec.has_name());
  EXPECT_EQ(spec.name(), "");
  EXPECT_TRUE(spec.has_seed());
  EXPECT_EQ(spec.seed(), 1u);
  EXPECT_FALSE(spec.run().has_dt_ps());  // automatic
  EXPECT_TRUE(spec.run().has_safety());
  EXPECT_DOUBLE_EQ(spec.run().safety(), 0.6);
  EXPECT_TRUE(spec.run().has_threads());
  EXPECT_EQ(spec.run().threads(), 0);
  EXPECT_DOUBLE_EQ(spec.outputs().energy_every_ps(), 1.0);
  EXPECT_DOUBLE_EQ(spec.outputs().snapshot_every_ps(), 10.0);
  const mdem::v1::TwistSpec& t = spec.twist();
  EXPECT_EQ(t.layers(), 6);
  EXPECT_DOUBLE_EQ(t.length_nm(), 67.8);
  EXPECT_FALSE(t.has_spacing_nm());  // vdW equilibrium
  EXPECT_EQ(t.missing_tubes_size(), 0);
  EXPECT_EQ(t.line_defects_size(), 0);
  EXPECT_DOUBLE_EQ(t.torque_nn_nm(), 64.0);
  EXPECT_DOUBLE_EQ(t.torque_rate_nn_nm_per_ps(), 1.0);
  EXPECT_DOUBLE_EQ(t.hold_ps(), 100.0);
  EXPECT_EQ(t.boundary(), mdem::v1::CONSTANT_MOMENT);
  EXPECT_EQ(t.grip_load(), mdem::v1::RIGID_GRIP);
  EXPECT_EQ(t.grip_hold(), mdem::v1::HOLD_POSITIONS);
  EXPECT_TRUE(t.has_unload());
  EXPECT_FALSE(t.unload());
  EXPECT_DOUBLE_EQ(t.unload_hold_ps(), 50.0);
  EXPECT_EQ(t.grip_segments(), 1);
  EXPECT_DOUBLE_EQ(t.vdw_damping_ratio(), 0.03);
  EXPECT_DOUBLE_EQ(t.local_damping(), 0.1);
  EXPECT_DOUBLE_EQ(t.temperature_k(), 0.0);
  EXPECT_EQ(mdem::spec::twist_segments(t), 50);
  EXPECT_EQ(mdem::spec::hex_tube_count(t.layers()), 91);
}

TEST(SpecDefaults, EachLineDefectGetsDefaults) {
  const JobSpec spec = finalized_json(R"({"twist":{"line_defects":[{}, {"width": 2}]}})");
  ASSERT_EQ(spec.twist().line_defects_size(), 2);
  for (const mdem::v1::LineDefect& line : spec.twist().line_defects()) {
    EXPECT_TRUE(line.has_angle_deg());
    EXPECT_DOUBLE_EQ(line.angle_deg(), 0.0);
    EXPECT_DOUBLE_EQ(line.length_fraction(), 1.0);
  }
  EXPECT_EQ(spec.twist().line_defects(0).width(), 1);
  EXPECT_EQ(spec.twist().line_defects(1).width(), 2);
}

TEST(SpecDefaults, SetValuesAreKeptAndAutoFieldsStayUnset) {
  const JobSpec spec = finalized_json(
      R"({"seed": 0, "run": {"safety": 1, "threads": 2}, "twist": {"layers": 2, "unload": true,
          "boundary": "TWIST_RELAXATION", "hold_ps": 0}})");
  EXPECT_EQ(spec.seed(), 0u);
  EXPECT_DOUBLE_EQ(spec.run().safety(), 1.0);
  EXPECT_EQ(spec.run().threads(), 2);
  EXPECT_FALSE(spec.run().has_dt_ps());
  EXPECT_EQ(spec.twist().layers(), 2);
  EXPECT_TRUE(spec.twist().unload());
  EXPECT_EQ(spec.twist().boundary(), mdem::v1::TWIST_RELAXATION);
  EXPECT_DOUBLE_EQ(spec.twist().hold_ps(), 0.0);
  EXPECT_FALSE(spec.twist().has_spacing_nm());
}

TEST(SpecDefaults, ApplyDefaultsWithoutKindFillsRunAndOutputsOnly) {
  JobSpec spec;
  mdem::spec::apply_defaults(spec);
  EXPECT_TRUE(spec.has_run());
  EXPECT_TRUE(spec.has_outputs());
  EXPECT_FALSE(spec.has_twist());
  EXPECT_EQ(spec.kind_case(), JobSpec::KIND_NOT_SET);
}

// ---- validation of each field ----

const std::vector<FieldCase>& field_cases() {
  static const std::vector<FieldCase> cases = {
      {R"({"twist":{}, "run":{"dt_ps":$}})",
       "run.dt_ps",
       {"0", "9e-7", "1.5", "-1"},
       ">= 1e-06 and <= 1 ps"},
      {R"({"twist":{}, "run":{"safety":$}})", "run.safety", {"0", "-0.1", "1.01"}, "> 0 and <= 1"},
      {R"({"twist":{}, "run":{"threads":$}})",
       "run.threads",
       {"-1", "257", "2147483647"},
       ">= 0 and <= 256",
       false},
      {R"({"twist":{}, "outputs":{"energy_every_ps":$}})",
       "outputs.energy_every_ps",
       {"0", "-1", "1000001"},
       "> 0 and <= 1e+06 ps"},
      {R"({"twist":{}, "outputs":{"snapshot_every_ps":$}})",
       "outputs.snapshot_every_ps",
       {"-0.5", "2e6", "1e300"},
       ">= 0 and <= 1e+06 ps"},
      {R"({"twist":{"layers":$}})",
       "twist.layers",
       {"1", "11", "0", "-3"},
       ">= 2 and <= 10",
       false},
      {R"({"twist":{"length_nm":$}})",
       "twist.length_nm",
       {"4.9", "2000.5", "0", "-67.8"},
       ">= 5 and <= 2000 nm"},
      {R"({"twist":{"spacing_nm":$}})",
       "twist.spacing_nm",
       {"1.49", "2.51", "0"},
       ">= 1.5 and <= 2.5 nm"},
      {R"({"twist":{"missing_tubes":[$]}})",
       "twist.missing_tubes[0]",
       {"91", "-1", "2147483647"},
       "0..90 for 6 layers",
       false},
      {R"({"twist":{"line_defects":[{"angle_deg":$}]}})",
       "twist.line_defects[0].angle_deg",
       {"-0.001", "360", "720"},
       ">= 0 and < 360 degrees"},
      {R"({"twist":{"line_defects":[{"width":$}]}})",
       "twist.line_defects[0].width",
       {"0", "4", "-1"},
       ">= 1 and <= 3",
       false},
      {R"({"twist":{"line_defects":[{"length_fraction":$}]}})",
       "twist.line_defects[0].length_fraction",
       {"0", "1.01", "-1"},
       "> 0 and <= 1"},
      {R"({"twist":{"torque_nn_nm":$}})",
       "twist.torque_nn_nm",
       {"0", "-5", "500.01", "1e9"},
       "> 0 and <= 500 nN·nm"},
      {R"({"twist":{"torque_rate_nn_nm_per_ps":$}})",
       "twist.torque_rate_nn_nm_per_ps",
       {"0", "-1", "100.5"},
       "> 0 and <= 100 nN·nm/ps"},
      {R"({"twist":{"hold_ps":$}})",
       "twist.hold_ps",
       {"-1", "1e12", "1.000001e6"},
       ">= 0 and <= 1e+06 ps"},
      {R"({"twist":{"boundary":$}})",
       "twist.boundary",
       {"7", "-1"},
       "allowed: CONSTANT_MOMENT, TWIST_RELAXATION",
       false},
      {R"({"twist":{"temperature_k":$}})",
       "twist.temperature_k",
       {"-1", "2001", "1e300"},
       ">= 0 and <= 2000 K"},
      {R"({"twist":{"grip_load":$}})",
       "twist.grip_load",
       {"3", "-2"},
       "allowed: RIGID_GRIP, PER_ELEMENT",
       false},
      {R"({"twist":{"grip_hold":$}})",
       "twist.grip_hold",
       {"3", "-1"},
       "allowed: HOLD_POSITIONS, HOLD_POSITIONS_AND_SPINS",
       false},
      {R"({"twist":{"unload_hold_ps":$}})",
       "twist.unload_hold_ps",
       {"-0.1", "1e7"},
       ">= 0 and <= 1e+06 ps"},
      {R"({"twist":{"grip_segments":$}})",
       "twist.grip_segments",
       {"0", "-1", "13"},
       ">= 1 and <= 12, a quarter of the 50 segments",
       false},
      {R"({"twist":{"vdw_damping_ratio":$}})",
       "twist.vdw_damping_ratio",
       {"-0.01", "1.01"},
       ">= 0 and <= 1"},
      {R"({"twist":{"local_damping":$}})",
       "twist.local_damping",
       {"-0.1", "0.995", "1"},
       ">= 0 and <= 0.99"},
  };
  return cases;
}

TEST(SpecValidate, EachFieldOutOfRangeOnEitherSideNamesFieldAndRange) {
  for (const FieldCase& c : field_cases())
    for (const std::string& value : c.bad) {
      SCOPED_TRACE(c.field + " = " + value);
      expect_one_error(json_errors(replace_value(c.json, value)), c.field, {c.allowed});
    }
}

TEST(SpecValidate, OutOfRangeMessageNamesTheValue) {
  expect_one_error(json_errors(R"({"twist":{"torque_nn_nm":-5}})"), "twist.torque_nn_nm",
                   {"-5 is out of range (allowed: > 0 and <= 500 nN·nm)"});
  expect_one_error(json_errors(R"({"twist":{"layers":11}})"), "twist.layers",
                   {"11 is out of range (allowed: >= 2 and <= 10 layers)"});
  expect_one_error(json_errors(R"({"twist":{"missing_tubes":[91]}})"), "twist.missing_tubes[0]",
                   {"site 91 does not exist (allowed: 0..90 for 6 layers)"});
}

// Only a twist-relaxation hold holds the grips: held spins under a constant moment are refused.
TEST(SpecValidate, HeldSpinsNeedTheTwistRelaxationBoundary) {
  expect_one_error(json_errors(R"({"twist":{"grip_hold":"HOLD_POSITIONS_AND_SPINS"}})"),
                   "twist.grip_hold",
                   {"boundary is CONSTANT_MOMENT",
                    "allowed: HOLD_POSITIONS_AND_SPINS with boundary TWIST_RELAXATION, or "
                    "HOLD_POSITIONS"});
  expect_one_error(json_errors(R"({"twist":{"grip_hold":"SPINS"}})"), "json",
                   {"twist.grip_hold", "HOLD_POSITIONS, HOLD_POSITIONS_AND_SPINS"});
  const JobSpec held = finalized_json(
      R"({"twist":{"boundary":"TWIST_RELAXATION", "grip_hold":"HOLD_POSITIONS_AND_SPINS"}})");
  EXPECT_EQ(held.twist().grip_hold(), mdem::v1::HOLD_POSITIONS_AND_SPINS);
}

TEST(SpecValidate, EachDoubleFieldRefusesNonFiniteJsonStrings) {
  for (const FieldCase& c : field_cases()) {
    if (!c.real) continue;
    for (const std::string value : {"\"NaN\"", "\"Infinity\"", "\"-Infinity\""}) {
      SCOPED_TRACE(c.field + " = " + value);
      const std::string shown = value == std::string("\"NaN\"")        ? "nan"
                                : value == std::string("\"Infinity\"") ? "inf"
                                                                       : "-inf";
      expect_one_error(json_errors(replace_value(c.json, value)), c.field,
                       {shown + " is not a finite number", c.allowed});
    }
  }
}

// JSON is YAML's flow style, so the same templates read as YAML with YAML's special floats.
TEST(SpecValidate, EachDoubleFieldRefusesNonFiniteYamlFloats) {
  expect_yaml_non_finite_refused(field_cases(), {".nan", ".inf", "-.inf", ".NaN", "+.Inf"});
}

TEST(SpecValidate, WrongTypeIsRefusedByTheParser) {
  for (const FieldCase& c : field_cases())
    for (const std::string value : {"\"abc\"", "{}", "[1]", "true"}) {
      SCOPED_TRACE(c.field + " = " + value);
      // Protobuf's parser flattens a nested list into a repeated field (see below).
      if (value == "[1]" && c.field.find('[') != std::string::npos) continue;
      const std::vector<FieldError> errors = json_errors(replace_value(c.json, value));
      ASSERT_EQ(errors.size(), 1u) << describe(errors);
      EXPECT_EQ(errors[0].field, "json");
      const std::string leaf = c.field.substr(c.field.rfind('.') + 1);
      const std::string key = leaf.substr(0, leaf.find('['));
      EXPECT_NE(errors[0].message.find(key), std::string::npos) << errors[0].message;
    }
}

// A leniency of protobuf's JSON parser (3.21), pinned so a change is noticed: nested lists and a
// bare scalar fill a repeated field as if flat. The values are still validated.
TEST(SpecValidate, ProtobufFlattensListsOfRepeatedFields) {
  const JobSpec spec = mdem::spec::parse_json(R"({"twist":{"missing_tubes":[[1,[2]],3]}})");
  EXPECT_EQ(spec.twist().missing_tubes_size(), 3);
  EXPECT_EQ(mdem::spec::parse_json(R"({"twist":{"missing_tubes":5}})").twist().missing_tubes(0), 5);
  expect_one_error(json_errors(R"({"twist":{"missing_tubes":[[1],[91]]}})"),
                   "twist.missing_tubes[1]", {"site 91 does not exist"});
}

TEST(SpecValidate, NonIntegerOrOverflowingIntegersAreRefusedByTheParser) {
  for (const std::string json :
       {R"({"twist":{"layers":2.5}})", R"({"twist":{"layers":1e10}})",
        R"({"twist":{"grip_segments":-3000000000}})", R"({"seed":-1,"twist":{}})",
        R"({"seed":1e30,"twist":{}})", R"({"twist":{"missing_tubes":[0.5]}})"}) {
    SCOPED_TRACE(json);
    const std::vector<FieldError> errors = json_errors(json);
    ASSERT_EQ(errors.size(), 1u) << describe(errors);
    EXPECT_EQ(errors[0].field, "json");
    EXPECT_NE(errors[0].message.find("invalid value"), std::string::npos) << errors[0].message;
  }
}

TEST(SpecValidate, EdgesOfEachRangeAreAccepted) {
  for (const std::string json : {
           R"({"twist":{}, "run":{"dt_ps":1e-6, "safety":1, "threads":256}})",
           R"({"twist":{}, "run":{"dt_ps":1, "threads":0},
               "outputs":{"energy_every_ps":1e6, "snapshot_every_ps":0}})",
           R"({"twist":{"layers":2, "length_nm":5, "spacing_nm":1.5, "torque_nn_nm":500,
               "torque_rate_nn_nm_per_ps":100, "hold_ps":0, "unload_hold_ps":1e6,
               "vdw_damping_ratio":0, "local_damping":0.99,
               "line_defects":[{"angle_deg":0, "width":3, "length_fraction":1}]}})",
           R"({"twist":{"layers":10, "length_nm":2000, "spacing_nm":2.5, "hold_ps":1e6,
               "vdw_damping_ratio":1, "local_damping":0, "grip_segments":368,
               "missing_tubes":[0, 270], "line_defects":[{"angle_deg":359.999, "width":1,
               "length_fraction":1e-9}]}})",
           R"({"seed":"18446744073709551615", "twist":{"boundary":"TWIST_BOUNDARY_UNSPECIFIED"}})",
       }) {
    SCOPED_TRACE(json);
    EXPECT_TRUE(json_errors(json).empty()) << describe(json_errors(json));
  }
}

TEST(SpecValidate, ManyBadFieldsAreAllReported) {
  const std::string name(201, 'x');
  const std::vector<FieldError> errors = json_errors(R"({"name":")" + name + R"(",
      "run":{"threads":-1, "dt_ps":"NaN"}, "outputs":{"snapshot_every_ps":-1},
      "twist":{"layers":1, "torque_nn_nm":0, "missing_tubes":[-2],
               "line_defects":[{"width":0}, {"angle_deg":400, "length_fraction":0}]}})");
  const std::vector<std::string> expected = {"name",
                                             "run.dt_ps",
                                             "run.threads",
                                             "outputs.snapshot_every_ps",
                                             "twist.layers",
                                             "twist.missing_tubes[0]",
                                             "twist.line_defects[0].width",
                                             "twist.line_defects[1].angle_deg",
                                             "twist.line_defects[1].length_fraction",
                                             "twist.torque_nn_nm"};
  std::vector<std::string> fields;
  for (const FieldError& e : errors) fields.push_back(e.field);
  EXPECT_EQ(fields, expected) << describe(errors);
}

TEST(SpecValidate, SpecErrorWhatListsEveryErrorOnItsOwnLine) {
  try {
    finalized_json(R"({"twist":{"layers":1, "hold_ps":-1}})");
    FAIL() << "no SpecError";
  } catch (const SpecError& e) {
    EXPECT_EQ(std::string(e.what()),
              "twist.layers: 1 is out of range (allowed: >= 2 and <= 10 layers)\n"
              "twist.hold_ps: -1 is out of range (allowed: >= 0 and <= 1e+06 ps)");
    EXPECT_EQ(e.errors().size(), 2u);
  }
}

TEST(SpecValidate, MissingKindIsAnError) {
  expect_one_error(json_errors("{}"), "kind",
                   {"no job kind given (allowed: twist, compression, tensile)"});
  expect_one_error(json_errors(R"({"name":"x", "run":{"threads":1}})"), "kind", {"twist"});
}

TEST(SpecValidate, ValidateAcceptsAnUnfinalizedSpec) {
  JobSpec spec;
  spec.mutable_twist();
  EXPECT_TRUE(mdem::spec::validate(spec).empty());
  spec.mutable_twist()->set_grip_segments(13);  // over the default length's limit of 12
  expect_one_error(mdem::spec::validate(spec), "twist.grip_segments", {"<= 12"});
}

// ---- name ----

TEST(SpecName, AtMost200CharactersCountedAsCharactersNotBytes) {
  std::string accented;
  for (int i = 0; i < 200; ++i) accented += "é";  // 400 bytes
  JobSpec spec;
  spec.mutable_twist();
  spec.set_name(accented);
  EXPECT_TRUE(mdem::spec::validate(spec).empty());
  spec.set_name(accented + "x");
  expect_one_error(mdem::spec::validate(spec), "name",
                   {"201 characters is too long", "at most 200 characters"});
}

TEST(SpecName, ControlCharactersAndInvalidUtf8AreRefused) {
  expect_one_error(json_errors(R"({"name":"line\nbreak", "twist":{}})"), "name",
                   {"control character U+000A at character 5", "no control characters"});
  expect_one_error(json_errors(R"({"name":"nul\u0000", "twist":{}})"), "name", {"U+0000"});
  expect_one_error(json_errors(R"({"name":"del\u007f", "twist":{}})"), "name", {"U+007F"});
  JobSpec spec;
  spec.mutable_twist();
  for (const std::string bad : {"\xff", "\xc3", "\xc0\xaf", "\xed\xa0\x80"}) {
    spec.set_name("ok" + bad);
    expect_one_error(mdem::spec::validate(spec), "name", {"is not valid UTF-8"});
  }
  spec.set_name("tab\tand ünïcödé");
  expect_one_error(mdem::spec::validate(spec), "name", {"U+0009"});
}

// ---- the rope's sites and grips ----

TEST(SpecTwist, MissingTubesListedTwiceAreRefused) {
  const std::vector<FieldError> errors = json_errors(R"({"twist":{"missing_tubes":[7, 3, 7, 7]}})");
  ASSERT_EQ(errors.size(), 2u) << describe(errors);
  EXPECT_EQ(errors[0].field, "twist.missing_tubes[2]");
  EXPECT_NE(errors[0].message.find("site 7 is listed twice"), std::string::npos);
  EXPECT_EQ(errors[1].field, "twist.missing_tubes[3]");
  EXPECT_NE(errors[1].message.find("site 7 is listed 3 times"), std::string::npos);
}

// A huge list of line defects (2 000 000 entries parsed in seconds) is one error naming the
// field and the limit, not a rope the engine is asked to build.
TEST(SpecTwist, HugeLineDefectListIsOneError) {
  JobSpec spec = mdem::spec::finalize(mdem::spec::parse_json(R"({"twist":{}})"));
  for (int i = 0; i < 200000; ++i) spec.mutable_twist()->add_line_defects()->set_width(1);
  expect_one_error(mdem::spec::validate(spec), "twist.line_defects",
                   {"200000 line defects", "at most 64"});
  spec.mutable_twist()->mutable_line_defects()->DeleteSubrange(64, 200000 - 64);
  EXPECT_TRUE(mdem::spec::validate(spec).empty());
}

TEST(SpecTwist, SiteRangeFollowsLayers) {
  expect_one_error(json_errors(R"({"twist":{"layers":3, "missing_tubes":[19]}})"),
                   "twist.missing_tubes[0]", {"site 19 does not exist", "0..18 for 3 layers"});
  EXPECT_TRUE(json_errors(R"({"twist":{"layers":3, "missing_tubes":[18, 0]}})").empty());
  // With invalid layers only the layers are reported for an otherwise plausible site.
  expect_one_error(json_errors(R"({"twist":{"layers":11, "missing_tubes":[200]}})"), "twist.layers",
                   {">= 2 and <= 10"});
}

TEST(SpecTwist, RemovingEveryTubeIsRefused) {
  expect_one_error(json_errors(R"({"twist":{"layers":2, "missing_tubes":[0,1,2,3,4,5,6]}})"),
                   "twist.missing_tubes", {"all 7 tubes are missing", "at most 6"});
  EXPECT_TRUE(json_errors(R"({"twist":{"layers":2, "missing_tubes":[0,1,2,3,4,5]}})").empty());
}

TEST(SpecTwist, MoreEntriesThanTubesGiveOneError) {
  std::string list = "0";
  for (int i = 1; i < 1000; ++i) list += ",1";
  expect_one_error(json_errors(R"({"twist":{"layers":2, "missing_tubes":[)" + list + "]}}"),
                   "twist.missing_tubes", {"1000 sites listed", "7 tubes"});
}

TEST(SpecTwist, GripLimitIsAQuarterOfTheSegmentsOfTheGivenLength) {
  expect_one_error(
      json_errors(R"({"twist":{"length_nm":5, "grip_segments":2}})"), "twist.grip_segments",
      {"2 is out of range", "<= 1, a quarter of the 4 segments, round(5 nm / 1.356 nm)"});
  EXPECT_TRUE(json_errors(R"({"twist":{"length_nm":2000, "grip_segments":368}})").empty());
  expect_one_error(json_errors(R"({"twist":{"length_nm":2000, "grip_segments":369}})"),
                   "twist.grip_segments", {"<= 368", "1475 segments, round(2000 nm"});
  // An invalid length is reported once; a grip below 1 is still wrong.
  expect_one_error(json_errors(R"({"twist":{"length_nm":1e9, "grip_segments":100000}})"),
                   "twist.length_nm", {"<= 2000 nm"});
  const std::vector<FieldError> both =
      json_errors(R"({"twist":{"length_nm":"NaN", "grip_segments":0}})");
  ASSERT_EQ(both.size(), 2u) << describe(both);
  EXPECT_EQ(both[1].field, "twist.grip_segments");
}

TEST(SpecTwist, SegmentAndTubeCounts) {
  mdem::v1::TwistSpec t;
  EXPECT_EQ(mdem::spec::twist_segments(t), 50);
  t.set_length_nm(5);
  EXPECT_EQ(mdem::spec::twist_segments(t), 4);
  t.set_length_nm(2000);
  EXPECT_EQ(mdem::spec::twist_segments(t), 1475);
  t.set_length_nm(0.1);
  EXPECT_EQ(mdem::spec::twist_segments(t), 1);
  t.set_length_nm(std::nan(""));
  EXPECT_EQ(mdem::spec::twist_segments(t), 1);
  EXPECT_EQ(mdem::spec::hex_tube_count(0), 0);
  EXPECT_EQ(mdem::spec::hex_tube_count(1), 1);
  EXPECT_EQ(mdem::spec::hex_tube_count(2), 7);
  EXPECT_EQ(mdem::spec::hex_tube_count(6), 91);
  EXPECT_EQ(mdem::spec::hex_tube_count(10), 271);
  EXPECT_GT(mdem::spec::hex_tube_count(2147483647), 0);  // clamped, no overflow
}

// ---- JSON ----

TEST(SpecJson, UnknownFieldIsRefusedAndNamed) {
  expect_one_error(json_errors(R"({"twist":{"torque":5}})"), "json", {"torque", "twist"});
  expect_one_error(json_errors(R"({"twisty":{}})"), "json", {"twisty"});
  expect_one_error(json_errors(R"({"twist":{}, "compression":{}})"), "json", {"compression"});
}

TEST(SpecJson, WrongTypeIsRefusedWithTheField) {
  expect_one_error(json_errors(R"({"twist":{"torque_nn_nm":"abc"}})"), "json",
                   {"twist.torque_nn_nm", "abc"});
  expect_one_error(json_errors(R"({"twist":{"unload":"maybe"}})"), "json", {"twist.unload"});
  expect_one_error(json_errors(R"({"name":5, "twist":{}})"), "json", {"name"});
  expect_one_error(json_errors(R"({"twist":{"boundary":"SIDEWAYS"}})"), "json",
                   {"twist.boundary", "SIDEWAYS"});
  expect_one_error(json_errors(R"({"twist":5})"), "json", {"twist"});
  expect_one_error(json_errors(R"([{"twist":{}}])"), "json", {"message"});
}

TEST(SpecJson, MalformedJsonIsRefusedWithLineAndColumn) {
  expect_one_error(json_errors("{\"twist\": {\n  \"layers\": 4,\n  \"hold_ps\": ]\n}}"), "json",
                   {"line 3, column 14"});
  expect_one_error(json_errors(R"({"twist":{}} trailing)"), "json", {"line 1"});
  expect_one_error(json_errors(""), "json", {"unexpected end of input"});
  expect_one_error(json_errors(R"({"twist":{},})"), "json", {"syntax error"});
}

TEST(SpecJson, SnakeCaseAndLowerCamelNamesAreEqual) {
  const JobSpec snake = mdem::spec::parse_json(R"({"name":"r", "seed":3,
      "run":{"dt_ps":0.01, "safety":0.5, "threads":2},
      "outputs":{"energy_every_ps":2, "snapshot_every_ps":0},
      "twist":{"layers":4, "length_nm":100, "spacing_nm":1.7, "missing_tubes":[1,2],
               "line_defects":[{"angle_deg":30, "width":2, "length_fraction":0.5}],
               "torque_nn_nm":10, "torque_rate_nn_nm_per_ps":2, "hold_ps":5,
               "boundary":"TWIST_RELAXATION", "unload":true, "unload_hold_ps":7,
               "grip_segments":2, "vdw_damping_ratio":0.1, "local_damping":0.2}})");
  const JobSpec camel = mdem::spec::parse_json(R"({"name":"r", "seed":"3",
      "run":{"dtPs":0.01, "safety":0.5, "threads":2},
      "outputs":{"energyEveryPs":2, "snapshotEveryPs":0},
      "twist":{"layers":4, "lengthNm":100, "spacingNm":1.7, "missingTubes":[1,2],
               "lineDefects":[{"angleDeg":30, "width":2, "lengthFraction":0.5}],
               "torqueNnNm":10, "torqueRateNnNmPerPs":2, "holdPs":5,
               "boundary":2, "unload":true, "unloadHoldPs":7,
               "gripSegments":2, "vdwDampingRatio":0.1, "localDamping":0.2}})");
  EXPECT_TRUE(MessageDifferencer::Equals(snake, camel));
  EXPECT_TRUE(mdem::spec::validate(snake).empty()) << describe(mdem::spec::validate(snake));
  EXPECT_DOUBLE_EQ(camel.twist().line_defects(0).length_fraction(), 0.5);
  EXPECT_EQ(camel.twist().boundary(), mdem::v1::TWIST_RELAXATION);
}

TEST(SpecJson, NullMeansUnset) {
  const JobSpec spec = finalized_json(R"({"twist":{"spacing_nm":null}, "run":{"dt_ps":null}})");
  EXPECT_FALSE(spec.run().has_dt_ps());
  EXPECT_FALSE(spec.twist().has_spacing_nm());
}

// ---- YAML ----

TEST(SpecYaml, SameSpecAsYamlAndJsonGivesEqualMessages) {
  const JobSpec from_yaml = mdem::spec::parse_yaml(R"(
# a twisted rope with a line defect
name: "rope \"A\""
seed: 42
run:
  dt_ps: 0.02
  threads: 2
outputs: {energy_every_ps: 0.5}
twist:
  layers: 5
  lengthNm: 135.6
  missing_tubes: [0, 12]
  line_defects:
    - angle_deg: 60
      width: 2
    - length_fraction: 0.25
  torque_nn_nm: 32
  boundary: TWIST_RELAXATION
  unload: true
  spacing_nm: ~
)");
  const JobSpec from_json = mdem::spec::parse_json(R"({"name":"rope \"A\"", "seed":42,
      "run":{"dt_ps":0.02, "threads":2}, "outputs":{"energy_every_ps":0.5},
      "twist":{"layers":5, "length_nm":135.6, "missing_tubes":[0,12],
               "line_defects":[{"angle_deg":60, "width":2}, {"length_fraction":0.25}],
               "torque_nn_nm":32, "boundary":"TWIST_RELAXATION", "unload":true}})");
  EXPECT_TRUE(MessageDifferencer::Equals(from_yaml, from_json))
      << mdem::spec::to_json(from_yaml, true) << "\nvs\n"
      << mdem::spec::to_json(from_json, true);
  EXPECT_FALSE(from_yaml.twist().has_spacing_nm());
}

TEST(SpecYaml, SyntaxErrorGivesLineAndColumn) {
  expect_one_error(yaml_errors("twist:\n  layers: 3\n  missing_tubes: [1, 2\n"), "yaml",
                   {"line 4"});
  expect_one_error(yaml_errors("twist:\n\tlayers: 3\n"), "yaml", {"line 2, column"});
}

TEST(SpecYaml, NumbersAsStringsAndAsNumbers) {
  const JobSpec plain = mdem::spec::parse_yaml("twist:\n  layers: 4\n  torque_nn_nm: 12.5\n");
  const JobSpec quoted =
      mdem::spec::parse_yaml("twist:\n  layers: \"4\"\n  torque_nn_nm: '12.5'\n");
  EXPECT_TRUE(MessageDifferencer::Equals(plain, quoted));
  EXPECT_EQ(plain.twist().layers(), 4);
  // YAML number spellings JSON lacks.
  const JobSpec spelled =
      mdem::spec::parse_yaml("twist:\n  length_nm: +.5e3\n  layers: 007\n  hold_ps: 5.\n");
  EXPECT_DOUBLE_EQ(spelled.twist().length_nm(), 500.0);
  EXPECT_EQ(spelled.twist().layers(), 7);
  EXPECT_DOUBLE_EQ(spelled.twist().hold_ps(), 5.0);
  // 64-bit integers keep every digit.
  EXPECT_EQ(mdem::spec::parse_yaml("seed: 18446744073709551615\ntwist: {}\n").seed(),
            18446744073709551615ull);
  // A string field keeps a number-like scalar as text.
  EXPECT_EQ(mdem::spec::parse_yaml("name: 2024\ntwist: {}\n").name(), "2024");
  EXPECT_EQ(mdem::spec::parse_yaml("name: 1.50\ntwist: {}\n").name(), "1.50");
  EXPECT_EQ(mdem::spec::parse_yaml("name: true\ntwist: {}\n").name(), "true");
  // Text in a number field is refused with the field.
  expect_one_error(yaml_errors("twist:\n  torque_nn_nm: abc\n"), "yaml",
                   {"twist.torque_nn_nm", "abc"});
  expect_one_error(yaml_errors("twist:\n  torque_nn_nm: \"\"\n"), "yaml", {"twist.torque_nn_nm"});
  expect_one_error(yaml_errors("twist:\n  layers: 2.5\n"), "yaml", {"twist.layers"});
}

TEST(SpecYaml, Booleans) {
  EXPECT_TRUE(mdem::spec::parse_yaml("twist: {unload: true}").twist().unload());
  EXPECT_TRUE(mdem::spec::parse_yaml("twist: {unload: True}").twist().unload());
  const JobSpec off = mdem::spec::parse_yaml("twist: {unload: false}");
  EXPECT_TRUE(off.twist().has_unload());
  EXPECT_FALSE(off.twist().unload());
  expect_one_error(yaml_errors("twist: {unload: maybe}"), "yaml", {"twist.unload"});
  expect_one_error(yaml_errors("twist: {layers: true}"), "yaml", {"twist.layers"});
}

TEST(SpecYaml, NullAndEmptyValuesMeanUnset) {
  const JobSpec spec = mdem::spec::finalize(
      mdem::spec::parse_yaml("run:\n  dt_ps:\ntwist:\n  spacing_nm: null\n  layers: ~\n"));
  EXPECT_FALSE(spec.run().has_dt_ps());
  EXPECT_FALSE(spec.twist().has_spacing_nm());
  EXPECT_EQ(spec.twist().layers(), 6);
}

TEST(SpecYaml, UnknownFieldIsRefusedAndNamed) {
  expect_one_error(yaml_errors("twist:\n  torque: 5\n"), "yaml", {"torque"});
}

TEST(SpecYaml, DocumentMustBeOneMappingWithoutDuplicateKeys) {
  expect_one_error(yaml_errors("twist:\n  layers: 3\n  layers: 4\n"), "yaml",
                   {"line 3", "duplicate key \"layers\""});
  expect_one_error(yaml_errors(""), "yaml", {"empty"});
  expect_one_error(yaml_errors("# only a comment\n"), "yaml", {"empty"});
  expect_one_error(yaml_errors("- twist: {}\n"), "yaml", {"not a mapping"});
  expect_one_error(yaml_errors("twist: {}\n---\ntwist: {}\n"), "yaml", {"2 documents"});
  expect_one_error(yaml_errors("? [a, b]\n: 1\n"), "yaml", {"key"});
}

TEST(SpecYaml, DeepNestingIsRefusedWithoutCrashing) {
  std::string deep = "twist: ";
  for (int i = 0; i < 5000; ++i) deep += "[";
  expect_one_error(yaml_errors(deep), "yaml", {"line 1", "nested too deeply"});
  std::string nested = "twist: ";
  for (int i = 0; i < 40; ++i) nested += "[";
  for (int i = 0; i < 40; ++i) nested += "]";
  expect_one_error(yaml_errors(nested), "yaml", {"nested deeper than 32 levels"});
}

// "[item, item, ...]", ten times.
std::string ten_of(const std::string& item) {
  std::string list = "[";
  for (int i = 0; i < 10; ++i) list.append(i ? ", " : "").append(item);
  return list.append("]");
}

TEST(SpecYaml, AliasesThatExpandPastTheSizeLimitAreRefused) {
  // Each level repeats the one before ten times: 10 KB, 100 KB, ... 100 GB of JSON.
  std::string yaml = "l0: &l0 " + ten_of(std::string(1000, 'a')) + "\n";
  for (int level = 1; level < 8; ++level) {
    const std::string n = std::to_string(level);
    yaml.append("l").append(n).append(": &l").append(n).append(" ");
    yaml.append(ten_of("*l" + std::to_string(level - 1))).append("\n");
  }
  expect_one_error(yaml_errors(yaml), "yaml", {"expands to more than 16 MiB"});
  // A small alias is just a repeated value.
  const JobSpec spec =
      mdem::spec::parse_yaml("twist:\n  line_defects:\n    - &d {width: 2}\n    - *d\n");
  EXPECT_EQ(spec.twist().line_defects_size(), 2);
  EXPECT_EQ(spec.twist().line_defects(1).width(), 2);
}

// ---- files ----

class SpecFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("mdem_spec_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }

  static std::vector<FieldError> load_errors(const std::string& path) {
    try {
      mdem::spec::load_file(path);
      return {};
    } catch (const SpecError& e) {
      return e.errors();
    }
  }

  fs::path dir_;
};

TEST_F(SpecFile, LoadsJsonAndYamlByExtension) {
  const JobSpec j = mdem::spec::load_file(write("a.json", R"({"twist":{"layers":3}})"));
  const JobSpec y = mdem::spec::load_file(write("a.yaml", "twist:\n  layers: 3\n"));
  const JobSpec yml = mdem::spec::load_file(write("a.YML", "twist: {layers: 3}\n"));
  EXPECT_TRUE(MessageDifferencer::Equals(j, y));
  EXPECT_TRUE(MessageDifferencer::Equals(j, yml));
  EXPECT_EQ(j.twist().layers(), 3);
}

TEST_F(SpecFile, MissingFileNamesThePath) {
  const std::string path = (dir_ / "nope.json").string();
  expect_one_error(load_errors(path), "file", {path, "no such file"});
}

TEST_F(SpecFile, WrongExtensionNamesTheAllowedOnes) {
  const std::string path = write("spec.txt", R"({"twist":{}})");
  expect_one_error(load_errors(path), "file", {path, ".txt", ".json, .yaml, .yml"});
  expect_one_error(load_errors(write("spec", "{}")), "file", {"no extension"});
}

TEST_F(SpecFile, DirectoryIsRefused) {
  const fs::path d = dir_ / "specs.json";
  fs::create_directory(d);
  expect_one_error(load_errors(d.string()), "file", {d.string(), "is a directory"});
}

TEST_F(SpecFile, OversizedFileIsRefused) {
  const std::string path = write("big.json", "");
  fs::resize_file(path, mdem::spec::kMaxSpecBytes + 1);
  expect_one_error(load_errors(path), "file", {path, "16777217 bytes", "at most 16 MiB"});
  fs::resize_file(path, mdem::spec::kMaxSpecBytes);  // at the limit: read, then refused as JSON
  expect_one_error(load_errors(path), "json", {"syntax error"});
}

TEST_F(SpecFile, ParseErrorsKeepTheirField) {
  expect_one_error(load_errors(write("bad.yaml", "twist: [\n")), "yaml", {"line"});
  expect_one_error(load_errors(write("bad.json", "{")), "json", {"line 1"});
}

// ---- JSON out ----

JobSpec full_spec() {
  return finalized_json(R"({"name":"rope \"B\" – ünï", "seed":"18446744073709551615",
      "run":{"dt_ps":0.013, "threads":3}, "outputs":{"snapshot_every_ps":0},
      "twist":{"layers":7, "length_nm":271.2, "spacing_nm":1.71294, "missing_tubes":[0, 5, 90],
               "line_defects":[{"angle_deg":37.5, "width":3, "length_fraction":0.1}, {}],
               "torque_nn_nm":0.1, "boundary":"TWIST_RELAXATION", "unload":true,
               "grip_segments":50, "vdw_damping_ratio":0, "local_damping":0.99}})");
}

TEST(SpecToJson, FinalizedSpecRoundTripsExactly) {
  for (const JobSpec& spec : {full_spec(), finalized_json(R"({"twist":{}})")})
    for (bool pretty : {false, true}) {
      const std::string json = mdem::spec::to_json(spec, pretty);
      const JobSpec back = mdem::spec::parse_json(json);
      EXPECT_TRUE(MessageDifferencer::Equals(spec, back)) << json;
      EXPECT_TRUE(mdem::spec::validate(back).empty());
    }
}

TEST(SpecToJson, PrintsProtoNamesAndSetZerosButNotAutoFields) {
  const std::string json = mdem::spec::to_json(finalized_json(R"({"twist":{}})"), false);
  for (const std::string part : {"\"threads\":0", "\"unload\":false", "\"torque_nn_nm\":64",
                                 "\"boundary\":\"CONSTANT_MOMENT\"", "\"name\":\"\""})
    EXPECT_NE(json.find(part), std::string::npos) << part << " not in " << json;
  EXPECT_EQ(json.find("dt_ps"), std::string::npos) << json;
  EXPECT_EQ(json.find("spacing_nm"), std::string::npos) << json;
  EXPECT_EQ(json.find("torqueNnNm"), std::string::npos) << json;
  EXPECT_EQ(json.find('\n'), std::string::npos);
  EXPECT_NE(mdem::spec::to_json(full_spec(), true).find('\n'), std::string::npos);
}

}  // namespace
