#pragma once
// Helpers shared by the job-spec tests (test_spec*.cpp): parsing and finalizing spec text,
// collecting its field errors and checking them.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "mdem/spec.h"

namespace mdem::testing {

// The errors of finalize(parse(text)), or of the parser if it refuses the text; empty if valid.
template <typename Parse>
std::vector<spec::FieldError> errors_of(Parse parse, const std::string& text) {
  try {
    spec::finalize(parse(text));
    return {};
  } catch (const spec::SpecError& e) {
    return e.errors();
  }
}

inline std::vector<spec::FieldError> json_errors(const std::string& json) {
  return errors_of(spec::parse_json, json);
}
inline std::vector<spec::FieldError> yaml_errors(const std::string& yaml) {
  return errors_of(spec::parse_yaml, yaml);
}

inline std::string describe(const std::vector<spec::FieldError>& errors) {
  std::string s;
  for (const spec::FieldError& e : errors) s += "\n  " + e.field + ": " + e.message;
  return s.empty() ? " (none)" : s;
}

// Exactly one error, on `field`, whose message contains each of `parts`.
inline void expect_one_error(const std::vector<spec::FieldError>& errors, const std::string& field,
                             const std::vector<std::string>& parts) {
  ASSERT_EQ(errors.size(), 1u) << "errors:" << describe(errors);
  EXPECT_EQ(errors[0].field, field);
  for (const std::string& part : parts)
    EXPECT_NE(errors[0].message.find(part), std::string::npos)
        << "message \"" << errors[0].message << "\" lacks \"" << part << "\"";
}

// `text` with its first '$' replaced by `value`.
inline std::string replace_value(std::string text, const std::string& value) {
  return text.replace(text.find('$'), 1, value);
}

// A JSON spec with "$" where the value goes, the field path the error must name, values out of
// range on each side (and other wrong values), and the text of the allowed range.
struct FieldCase {
  std::string json;
  std::string field;
  std::vector<std::string> bad;
  std::string allowed;
  bool real = true;  // a double: also test non-finite values
};

// Each case with each of its bad values in place of "$", read as JSON: exactly one error, on the
// case's field, naming the value and the allowed range.
inline void expect_each_out_of_range_refused(const std::vector<FieldCase>& cases) {
  for (const FieldCase& c : cases)
    for (const std::string& value : c.bad) {
      SCOPED_TRACE(c.field + " = " + value);
      expect_one_error(errors_of(spec::parse_json, replace_value(c.json, value)), c.field,
                       {value, c.allowed});
    }
}

// Each real case with JSON's non-finite strings ("NaN", "Infinity", "-Infinity") in place of
// "$": exactly one error, on the case's field, saying "is not a finite number" and the range.
inline void expect_json_non_finite_refused(const std::vector<FieldCase>& cases) {
  for (const FieldCase& c : cases) {
    if (!c.real) continue;
    for (const std::string value : {"\"NaN\"", "\"Infinity\"", "\"-Infinity\""}) {
      SCOPED_TRACE(c.field + " = " + value);
      expect_one_error(errors_of(spec::parse_json, replace_value(c.json, value)), c.field,
                       {"is not a finite number", c.allowed});
    }
  }
}

// Each real case with each of `values` (YAML's special floats) in place of "$", read as YAML:
// exactly one error, on the case's field, saying "is not a finite number" and the allowed range.
inline void expect_yaml_non_finite_refused(const std::vector<FieldCase>& cases,
                                           const std::vector<std::string>& values) {
  for (const FieldCase& c : cases) {
    if (!c.real) continue;
    for (const std::string& value : values) {
      SCOPED_TRACE(c.field + " = " + value);
      expect_one_error(yaml_errors(replace_value(c.json, value)), c.field,
                       {"is not a finite number", c.allowed});
    }
  }
}

inline v1::JobSpec finalized_json(const std::string& json) {
  return spec::finalize(spec::parse_json(json));
}

}  // namespace mdem::testing
