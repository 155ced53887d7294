#pragma once
// Shared by the JSON, YAML and file readers.
#include <google/protobuf/descriptor.h>

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>

#include "mdem/spec.h"

namespace mdem::spec::detail {

// Deepest nesting of objects and lists a spec may have (the schema needs 4).
inline constexpr int kMaxDepth = 32;

// "line L, column C" of the user's input for a byte offset of the JSON text being read.
using Locate = std::function<std::string(std::size_t offset)>;

// "line L, column C" of a byte offset of `text` (both counted from 1, columns in bytes).
std::string text_location(std::string_view text, std::size_t offset);

// parse_json, with errors reported under `field` ("json" or "yaml") and placed by `locate`.
mdem::v1::JobSpec parse_json_as(std::string_view json, const std::string& field,
                                const Locate& locate);

// Reads JSON text against JobSpec's schema before protobuf's JSON mapping does: syntax, nesting
// deeper than kMaxDepth, a field given twice (in either spelling), two job kinds, unknown fields,
// values of the wrong kind, whole numbers that are not whole or do not fit their type, numbers
// beyond a double. Throws a SpecError under `field` for the first problem, naming the field path
// as written, where it is (through `locate`), what is wrong and what is allowed.
void check_json(std::string_view json, const std::string& field, const Locate& locate);

// The field a key names, as the JSON mapping reads it: proto name or JSON (lowerCamel) name;
// nullptr for none.
const google::protobuf::FieldDescriptor* field_named(const google::protobuf::Descriptor& message,
                                                     const std::string& key);

// Refuses text over kMaxSpecBytes with a SpecError under `field`.
void check_size(std::size_t bytes, const std::string& field, const std::string& what);

}  // namespace mdem::spec::detail
