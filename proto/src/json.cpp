// JSON in and out through Protobuf's JSON mapping.
#include <google/protobuf/util/json_util.h>

#include <nlohmann/json.hpp>

#include "input.h"
#include "mdem/spec.h"

namespace mdem::spec {

namespace {

// Checks JSON syntax only (no document is built) to report a syntax error with its line and
// column, which protobuf's parser does not give.
class SyntaxCheck : public nlohmann::json_sax<nlohmann::json> {
 public:
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return true; }
  bool key(string_t&) override { return true; }
  bool end_object() override { return true; }
  bool start_array(std::size_t) override { return true; }
  bool end_array() override { return true; }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception& e) override {
    message_ = e.what();
    return false;
  }
  // nlohmann's message without its "[json.exception.parse_error.101] " prefix.
  std::string message() const {
    const std::size_t end = message_.find("] ");
    return end == std::string::npos ? message_ : message_.substr(end + 2);
  }

 private:
  std::string message_;
};

void check_syntax(std::string_view json, const std::string& field) {
  SyntaxCheck check;
  if (!nlohmann::json::sax_parse(json, &check)) throw SpecError({{field, check.message()}});
}

// Protobuf's message: its first line (the rest repeats the text around the error), without the
// ": " it puts first when the error is at the root.
std::string protobuf_message(const std::string& message) {
  std::string line = message.substr(0, message.find('\n'));
  return line.rfind(": ", 0) == 0 ? line.substr(2) : line;
}

}  // namespace

namespace detail {

void check_size(std::size_t bytes, const std::string& field, const std::string& what) {
  if (bytes <= kMaxSpecBytes) return;
  throw SpecError({{field, what + " is " + std::to_string(bytes) + " bytes (allowed: at most " +
                               std::to_string(kMaxSpecBytes >> 20) + " MiB)"}});
}

mdem::v1::JobSpec parse_json_as(std::string_view json, const std::string& field) {
  check_size(json.size(), field, "the spec");
  check_syntax(json, field);
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  mdem::v1::JobSpec spec;
  const auto status = google::protobuf::util::JsonStringToMessage(
      google::protobuf::StringPiece(json.data(), json.size()), &spec, options);
  if (!status.ok()) throw SpecError({{field, protobuf_message(std::string(status.message()))}});
  return spec;
}

}  // namespace detail

mdem::v1::JobSpec parse_json(std::string_view text) { return detail::parse_json_as(text, "json"); }

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
