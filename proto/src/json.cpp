// JSON in and out through Protobuf's JSON mapping.
#include <google/protobuf/util/json_util.h>

#include "input.h"
#include "mdem/spec.h"

namespace mdem::spec {

namespace {

// Protobuf's message, should check_json have let a problem through: its first line (the rest
// repeats the text around the error), "(twist.layers): invalid value ..." read as
// "twist.layers: invalid value ...".
std::string protobuf_message(const std::string& message) {
  std::string line = message.substr(0, message.find('\n'));
  if (line.rfind(": ", 0) == 0) line = line.substr(2);
  if (line.rfind('(', 0) == 0) {
    const std::size_t close = line.find(')');
    if (close != std::string::npos) line = line.substr(1, close - 1) + line.substr(close + 1);
  }
  return line;
}

}  // namespace

namespace detail {

void check_size(std::size_t bytes, const std::string& field, const std::string& what) {
  if (bytes <= kMaxSpecBytes) return;
  throw SpecError({{field, what + " is " + std::to_string(bytes) + " bytes (allowed: at most " +
                               std::to_string(kMaxSpecBytes >> 20) + " MiB)"}});
}

mdem::v1::JobSpec parse_json_as(std::string_view json, const std::string& field,
                                const Locate& locate) {
  check_size(json.size(), field, "the spec");
  check_json(json, field, locate);
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  mdem::v1::JobSpec spec;
  const auto status = google::protobuf::util::JsonStringToMessage(
      google::protobuf::StringPiece(json.data(), json.size()), &spec, options);
  if (!status.ok()) throw SpecError({{field, protobuf_message(std::string(status.message()))}});
  return spec;
}

}  // namespace detail

mdem::v1::JobSpec parse_json(std::string_view text) {
  return detail::parse_json_as(
      text, "json", [text](std::size_t offset) { return detail::text_location(text, offset); });
}

std::string to_json(const mdem::v1::JobSpec& spec, bool pretty) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = pretty;
  options.preserve_proto_field_names = true;
  // Optional scalars have presence, so every set field is printed, zeros and false included;
  // always_print_primitive_fields would add empty lists and an unspecified enum.
  options.always_print_primitive_fields = false;
  std::string out;
  const auto status = google::protobuf::util::MessageToJsonString(spec, &out, options);
  // Printing fails only for malformed messages (invalid UTF-8 in a string field).
  if (!status.ok()) throw SpecError({{"json", std::string(status.message())}});
  return out;
}

}  // namespace mdem::spec
