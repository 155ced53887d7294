// Spec input read as written (issue 11, points 4 and 6): a field given twice in a JSON or YAML
// spec is refused wherever it is, in either spelling, never merged; every parse error names the
// field path the user wrote, where it is, what is wrong and what is allowed, in no internal
// terms; huge, non-finite and out-of-type values are refused at the field that holds them.
#include <google/protobuf/descriptor.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "mdem/spec.h"
#include "spec_support.h"

using mdem::spec::FieldError;
using namespace mdem::testing;

namespace {

// "line L, column C" of the byte `offset` of `text`, counted here by hand.
std::string line_column(const std::string& text, std::size_t offset) {
  std::size_t line = 1;
  std::size_t column = 1;
  for (std::size_t i = 0; i < offset; ++i) {
    column = text[i] == '\n' ? 1 : column + 1;
    line += text[i] == '\n';
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

// Where the second `"key"` (or `key:` in YAML) of the text starts.
std::string second(const std::string& text, const std::string& token) {
  const std::size_t first = text.find(token);
  return line_column(text, text.find(token, first + 1));
}

// Text that no message may show: protobuf's internal names.
void expect_no_internals(const std::vector<FieldError>& errors) {
  for (const FieldError& e : errors)
    for (const std::string internal : {"TYPE_", "type.googleapis.com", "oneof field '_",
                                       "Message too deep", "number overflow", "Cannot find field"})
      EXPECT_EQ(e.message.find(internal), std::string::npos) << e.message;
}

// ---- 1. a field given twice ----

TEST(SpecInputDuplicates, JsonListGivenTwiceIsRefusedNotMerged) {
  const std::string json = R"({"twist":{"missing_tubes":[1], "missing_tubes":[2]}})";
  expect_one_error(json_errors(json), "json",
                   {"twist.missing_tubes", "duplicate key \"missing_tubes\"",
                    second(json, "\"missing_tubes\""), line_column(json, json.find("\"missing"))});
}

TEST(SpecInputDuplicates, JsonMessageGivenTwiceIsRefusedNotMerged) {
  const std::string json =
      "{\"twist\": {},\n \"outputs\": {\"energy_every_ps\": 2},\n \"outputs\": "
      "{\"snapshot_every_ps\": 3}}";
  expect_one_error(json_errors(json), "json",
                   {"outputs (line 3, column 2)", "duplicate key \"outputs\"", "each field once"});
  expect_no_internals(json_errors(json));
}

TEST(SpecInputDuplicates, JsonScalarGivenTwiceNamesTheFieldNotAnInternalOneof) {
  const std::string json = R"({"twist":{"layers":3, "layers":4}})";
  expect_one_error(json_errors(json), "json",
                   {"twist.layers", "duplicate key \"layers\"", second(json, "\"layers\"")});
  expect_no_internals(json_errors(json));
}

TEST(SpecInputDuplicates, BothSpellingsOfOneFieldAreADuplicate) {
  const std::string json = R"({"twist":{"length_nm":100, "lengthNm":200}})";
  expect_one_error(json_errors(json), "json",
                   {"twist.lengthNm", "duplicate key \"lengthNm\"", "as \"length_nm\"",
                    line_column(json, json.find("\"lengthNm\""))});
  expect_one_error(yaml_errors("twist:\n  lengthNm: 100\n  length_nm: 200\n"), "yaml",
                   {"twist.length_nm (line 3, column 3)", "as \"lengthNm\" at line 2, column 3"});
}

TEST(SpecInputDuplicates, DuplicatesAreFoundAtAnyDepth) {
  const std::string json = R"({"twist":{"line_defects":[{"width":1}, {"width":2,
      "angle_deg":5, "width":3}]}})";
  expect_one_error(json_errors(json), "json",
                   {"twist.line_defects[1].width", line_column(json, json.rfind("\"width\""))});
  expect_one_error(json_errors(R"({"seed":1, "twist":{}, "seed":2})"), "json", {"seed"});
  expect_one_error(json_errors(R"({"run":{"threads":1, "threads":1}, "twist":{}})"), "json",
                   {"run.threads", "duplicate"});
  // The same key in different objects is no duplicate.
  EXPECT_TRUE(json_errors(R"({"twist":{"line_defects":[{"width":1}, {"width":2}]}})").empty());
}

TEST(SpecInputDuplicates, YamlDuplicatesNameThePathAndLine) {
  const std::string yaml = "twist:\n  missing_tubes: [1]\n  layers: 3\n  missing_tubes: [2]\n";
  expect_one_error(yaml_errors(yaml), "yaml",
                   {"twist.missing_tubes (line 4, column 3)", "duplicate key \"missing_tubes\"",
                    "already given at line 2, column 3"});
  expect_one_error(yaml_errors("outputs: {energy_every_ps: 2}\ntwist: {}\noutputs: {}\n"), "yaml",
                   {"outputs (line 3, column 1)", "duplicate key"});
  expect_one_error(
      yaml_errors("twist:\n  line_defects:\n    - width: 1\n    - width: 2\n      width: 3\n"),
      "yaml", {"twist.line_defects[1].width (line 5, column 7)"});
}

TEST(SpecInputDuplicates, TwoJobKindsNameBoth) {
  const std::vector<FieldError> errors = json_errors(R"({"twist":{}, "compression":{}})");
  expect_one_error(errors, "json", {"\"compression\" and \"twist\" are both given", "one kind"});
  expect_no_internals(errors);
}

// ---- 2. errors name the field the user wrote ----

TEST(SpecInputMessages, NumberOverflowNamesFieldAndRange) {
  expect_one_error(json_errors(R"({"twist":{"layers":1e400}})"), "json",
                   {"twist.layers (line 1, column 11)", "1e400: out of range for an integer field",
                    "(allowed: >= 2 and <= 10 layers)"});
  expect_one_error(json_errors(R"({"twist":{"length_nm":-1e400}})"), "json",
                   {"twist.length_nm", "-1e400", "(allowed: >= 5 and <= 2000 nm)"});
  expect_one_error(json_errors(R"({"twist":{"missing_tubes":[3, 1e999]}})"), "json",
                   {"twist.missing_tubes[1]", "1e999", "0..90 for 6 layers"});
  expect_one_error(yaml_errors("twist:\n  layers: 1e400\n"), "yaml",
                   {"twist.layers (line 2, column 3)", "1e400", ">= 2 and <= 10 layers"});
  expect_one_error(yaml_errors("compression:\n  porosity: 1e400\n"), "yaml",
                   {"compression.porosity (line 2, column 3)", "> 0.2 and < 0.95"});
  expect_no_internals(json_errors(R"({"twist":{"layers":1e400}})"));
}

TEST(SpecInputMessages, IntegersThatDoNotFitTheirTypeNameTheRange) {
  expect_one_error(json_errors(R"({"twist":{"grip_segments":-3000000000}})"), "json",
                   {"twist.grip_segments", "-3000000000", "out of range for an integer field",
                    "(allowed: >= 1 and <= 12"});
  expect_one_error(json_errors(R"({"seed":18446744073709551616, "twist":{}})"), "json",
                   {"seed", "0..18446744073709551615"});
  expect_one_error(json_errors(R"({"seed":"-1", "twist":{}})"), "json",
                   {"seed", "\"-1\"", "0..18446744073709551615"});
  expect_one_error(yaml_errors("run: {threads: 2.5}\ntwist: {}\n"), "yaml",
                   {"run.threads", "not a whole number", ">= 0 and <= "});
}

TEST(SpecInputMessages, DeepNestingNamesThePath) {
  // The input behind "Message too deep ... for key 'a'": now an unknown field, named.
  std::string deep = "{\"twist\":";
  for (int i = 0; i < 200; ++i) deep += "{\"a\":";
  deep += "1";
  for (int i = 0; i < 201; ++i) deep += "}";
  std::vector<FieldError> errors = json_errors(deep);
  expect_one_error(
      errors, "json",
      {"twist.a (line 1, column 11)", "unknown field \"a\"", "allowed: layers, length_nm"});
  expect_no_internals(errors);
  // Deep through the lists protobuf flattens: refused at the depth bound, with the path.
  std::string lists = R"({"twist":{"missing_tubes":)";
  for (int i = 0; i < 100; ++i) lists += "[";
  for (int i = 0; i < 100; ++i) lists += "]";
  lists += "}}";
  expect_one_error(
      json_errors(lists), "json",
      {"twist.missing_tubes[0][0]", "nested deeper than 32 levels", "allowed: at most 32"});
  std::string yaml = "twist:\n  missing_tubes: ";
  for (int i = 0; i < 40; ++i) yaml += "[";
  for (int i = 0; i < 40; ++i) yaml += "]";
  expect_one_error(yaml_errors(yaml), "yaml",
                   {"twist.missing_tubes[0][0]", "(line 2, column", "nested deeper than 32"});
}

TEST(SpecInputMessages, WrongKindsOfValueSayWhatIsAllowed) {
  expect_one_error(json_errors(R"({"twist":{"length_nm":"abc"}})"), "json",
                   {"twist.length_nm", "\"abc\": not a number", ">= 5 and <= 2000 nm"});
  expect_one_error(json_errors(R"({"twist":{"layers":{}}})"), "json",
                   {"twist.layers", "not a whole number", ">= 2 and <= 10"});
  expect_one_error(json_errors(R"({"twist":{"length_nm":[1]}})"), "json",
                   {"twist.length_nm", "[...]"});
  expect_one_error(json_errors(R"({"twist":{"boundary":"SIDEWAYS"}})"), "json",
                   {"twist.boundary", "CONSTANT_MOMENT, TWIST_RELAXATION"});
  expect_one_error(json_errors(R"({"twist":{"unload":1}})"), "json",
                   {"twist.unload", "(allowed: true or false)"});
  expect_one_error(json_errors(R"({"name":5, "twist":{}})"), "json", {"name", "text"});
  expect_one_error(json_errors(R"({"twist":5})"), "json", {"twist", "an object of the fields"});
  // Hexadecimal and padded numbers in strings were read by protobuf; only the documented forms
  // (a number, or a number, "NaN", "Infinity", "-Infinity" in quotes) are.
  expect_one_error(json_errors(R"({"twist":{"length_nm":"0x10"}})"), "json",
                   {"twist.length_nm", "0x10"});
  expect_one_error(json_errors(R"({"twist":{"length_nm":" 100"}})"), "json", {"twist.length_nm"});
  EXPECT_EQ(finalized_json(R"({"twist":{"length_nm":"100"}})").twist().length_nm(), 100.0);
  for (const std::string json :
       {R"({"twist":{"length_nm":"abc"}})", R"({"twist":{"boundary":true}})",
        R"({"twist":{"a":{}}})", R"([1])", R"({"twist":{"layers":2.5}})"})
    expect_no_internals(json_errors(json));
}

TEST(SpecInputMessages, NullInAListIsRefusedNotDropped) {
  expect_one_error(json_errors(R"({"twist":{"missing_tubes":[1, null]}})"), "json",
                   {"twist.missing_tubes[1]", "null in a list", "0..90 for 6 layers"});
  expect_one_error(yaml_errors("twist:\n  line_defects: [{width: 2}, ~]\n"), "yaml",
                   {"twist.line_defects[1]", "null in a list"});
}

// ---- 3. wrong, missing, huge and non-finite values ----

// Every number field of the schema, by its JSON path: its message's place and its name.
struct NumberField {
  std::string json;  // with "$" for the value
  std::string path;
  bool integer;
};

std::vector<NumberField> number_fields() {
  using google::protobuf::Descriptor;
  using google::protobuf::FieldDescriptor;
  struct Place {
    const Descriptor* message;
    std::string open, close, path;
  };
  const std::vector<Place> places = {
      {mdem::v1::RunSettings::descriptor(), R"({"twist":{}, "run":{)", "}}", "run."},
      {mdem::v1::Outputs::descriptor(), R"({"twist":{}, "outputs":{)", "}}", "outputs."},
      {mdem::v1::TwistSpec::descriptor(), R"({"twist":{)", "}}", "twist."},
      {mdem::v1::LineDefect::descriptor(), R"({"twist":{"line_defects":[{)", "}]}}",
       "twist.line_defects[0]."},
      {mdem::v1::CompressionSpec::descriptor(), R"({"compression":{)", "}}", "compression."},
  };
  std::vector<NumberField> fields;
  for (const Place& p : places)
    for (int i = 0; i < p.message->field_count(); ++i) {
      const FieldDescriptor* f = p.message->field(i);
      const bool integer = f->cpp_type() == FieldDescriptor::CPPTYPE_INT32;
      if (!integer && f->cpp_type() != FieldDescriptor::CPPTYPE_DOUBLE) continue;
      const std::string value = f->is_repeated() ? "[$]" : "$";
      fields.push_back({p.open + "\"" + f->name() + "\":" + value + p.close,
                        p.path + f->name() + (f->is_repeated() ? "[0]" : ""), integer});
    }
  return fields;
}

// The "(allowed: ...)" of validate's message for a value out of range, e.g. 1e9 or -1e9.
std::string validated_allowed(const NumberField& f) {
  for (const std::string value : {"2000000000", "-2000000000"}) {
    const std::vector<FieldError> errors = json_errors(replace_value(f.json, value));
    for (const FieldError& e : errors)
      if (e.field == f.path && e.message.find("(allowed") != std::string::npos)
        return e.message.substr(e.message.find("(allowed"));
  }
  return "";
}

TEST(SpecInputValues, EveryNumberFieldRefusesOverflowWithItsFieldAndRange) {
  const std::vector<NumberField> fields = number_fields();
  ASSERT_GE(fields.size(), 30u);
  for (const NumberField& f : fields) {
    const std::string allowed = validated_allowed(f);
    ASSERT_FALSE(allowed.empty()) << f.path;
    for (const std::string value : {"1e400", "-1e400"}) {
      SCOPED_TRACE(f.path + " = " + value);
      expect_one_error(json_errors(replace_value(f.json, value)), "json",
                       {f.path + " (line 1, column", value, "out of range", allowed});
      expect_one_error(yaml_errors(replace_value(f.json, value)), "yaml",
                       {f.path + " (line 1, column", value, "out of range", allowed});
    }
  }
}

TEST(SpecInputValues, NonFiniteValuesInWholeNumberFieldsAreRefusedWithTheRange) {
  for (const NumberField& f : number_fields()) {
    if (!f.integer) continue;
    const std::string allowed = validated_allowed(f);
    for (const std::string value : {"\"NaN\"", "\"Infinity\"", "\"-Infinity\""}) {
      SCOPED_TRACE(f.path + " = " + value);
      expect_one_error(json_errors(replace_value(f.json, value)), "json",
                       {f.path, "not a whole number", allowed});
    }
    for (const std::string value : {".nan", ".inf", "-.inf"}) {
      SCOPED_TRACE(f.path + " = " + value);
      expect_one_error(yaml_errors(replace_value(f.json, value)), "yaml",
                       {f.path, "not a whole number", allowed});
    }
  }
  expect_one_error(yaml_errors("seed: .inf\ntwist: {}\n"), "yaml",
                   {"seed (line 1, column 1)", "0..18446744073709551615"});
}

TEST(SpecInputValues, HugeStringsAreRefusedAndShownShort) {
  const std::string huge(1 << 20, '7');
  // In a number field: named, shown cut, with its length.
  std::vector<FieldError> errors = json_errors(R"({"twist":{"length_nm":")" + huge + "x\"}}");
  expect_one_error(errors, "json", {"twist.length_nm", "(1048577 bytes)", ">= 5 and <= 2000 nm"});
  EXPECT_LT(errors[0].message.size(), 300u);
  errors = yaml_errors("twist:\n  boundary: " + huge + "\n");
  expect_one_error(errors, "yaml", {"twist.boundary (line 2, column 3)", "(1048576 bytes)"});
  errors = yaml_errors("twist:\n  boundary: x" + huge + "\n");
  expect_one_error(errors, "yaml", {"twist.boundary (line 2, column 3)", "(1048577 bytes)"});
  EXPECT_LT(errors[0].message.size(), 300u);
  EXPECT_LT(errors[0].message.size(), 300u);
  // As the name: validation's length limit.
  expect_one_error(json_errors(R"({"name":")" + huge + R"(", "twist":{}})"), "name",
                   {"1048576 characters is too long", "at most 200 characters"});
  expect_one_error(yaml_errors("name: " + huge + "\ntwist: {}\n"), "name",
                   {"at most 200 characters"});
  // As a key: an unknown field, named.
  expect_one_error(json_errors("{\"" + huge + "\":1}"), "json", {"unknown field", "allowed: name"});
}

TEST(SpecInputValues, HugeListsAreRefusedAtTheirField) {
  std::string list = "0";
  for (int i = 1; i < 200000; ++i) list += ",1";
  expect_one_error(json_errors(R"({"twist":{"missing_tubes":[)" + list + "]}}"),
                   "twist.missing_tubes", {"200000 sites listed", "at most 90"});
  expect_one_error(yaml_errors("twist:\n  missing_tubes: [" + list + "]\n"), "twist.missing_tubes",
                   {"200000 sites listed"});
  // A bad entry deep in a long list is found and named by its index.
  expect_one_error(json_errors(R"({"twist":{"missing_tubes":[)" + list + ",2.5]}}"), "json",
                   {"twist.missing_tubes[200000]", "2.5: not a whole number"});
}

TEST(SpecInputValues, MissingValuesAreSyntaxErrorsWithLineAndColumn) {
  expect_one_error(json_errors("{\"twist\":{\n  \"layers\": ,\n}}"), "json",
                   {"line 2, column 13", "syntax error"});
  expect_one_error(json_errors(R"({"twist":{"layers"}})"), "json", {"line 1", "syntax error"});
  // In YAML an empty value is null, which means unset.
  EXPECT_EQ(mdem::spec::finalize(mdem::spec::parse_yaml("twist:\n  layers:\n")).twist().layers(),
            6);
}

}  // namespace
