// parse_yaml: YAML -> JSON text (guided by the message schema where keys match) -> JSON mapping.
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <utility>
#include <vector>

#include "input.h"
#include "mdem/spec.h"

namespace mdem::spec {

namespace {

using google::protobuf::Descriptor;
using google::protobuf::FieldDescriptor;

using detail::kMaxDepth;

std::string location(const YAML::Mark& mark) {
  return "line " + std::to_string(mark.line + 1) + ", column " + std::to_string(mark.column + 1);
}

[[noreturn]] void fail(const YAML::Mark& mark, const std::string& message) {
  throw SpecError({{"yaml", mark.line < 0 ? message : location(mark) + ": " + message}});
}

// A problem with the value at `path`, "" for the document.
[[noreturn]] void fail_at(const std::string& path, const YAML::Mark& mark,
                          const std::string& message) {
  if (path.empty()) fail(mark, message);
  throw SpecError({{"yaml", path + " (" + location(mark) + "): " + message}});
}

std::string json_string(std::string_view s) {
  std::string out = "\"";
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += ch;
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

bool is_quoted_or_str(const YAML::Node& n) {
  return n.Tag() == "!" || n.Tag() == "tag:yaml.org,2002:str";
}

// YAML 1.2 core-schema special floats, as the JSON mapping's strings; "" if s is not one.
std::string special_float(const std::string& s) {
  for (const char* nan : {".nan", ".NaN", ".NAN"})
    if (s == nan) return "\"NaN\"";
  for (const char* inf : {".inf", ".Inf", ".INF"}) {
    if (s == inf || s == std::string("+") + inf) return "\"Infinity\"";
    if (s == std::string("-") + inf) return "\"-Infinity\"";
  }
  return "";
}

// A YAML decimal number, [-+]?[0-9]*(.[0-9]*)?([eE][-+]?[0-9]+)? with a digit before or after
// the point, as JSON number text ("+.5" -> "0.5", "007" -> "7", "1." -> "1"); "" if s is not a
// number. The digits are kept as written, so 64-bit integers stay exact. Read by hand: a
// std::regex recurses per character and overflows the stack on a long scalar.
std::string json_number(const std::string& s) {
  std::size_t i = 0;
  const auto digits = [&] {
    const std::size_t start = i;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
    return s.substr(start, i - start);
  };
  const bool negative = i < s.size() && s[i] == '-';
  if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
  const std::string whole = digits();
  std::string fraction;
  const bool point = i < s.size() && s[i] == '.';
  if (point) {
    ++i;
    fraction = digits();
  }
  if (whole.empty() && fraction.empty()) return "";
  std::string exponent;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    const std::size_t start = i++;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) ++i;
    if (digits().empty()) return "";
    exponent = s.substr(start);
  }
  if (i != s.size()) return "";
  std::string out = negative ? "-" : "";
  const std::size_t first = whole.find_first_not_of('0');
  out += first == std::string::npos ? "0" : whole.substr(first);
  if (!fraction.empty()) out += "." + fraction;
  return out + exponent;
}

std::string plain_scalar(const std::string& s) {
  if (s == "true" || s == "True" || s == "TRUE") return "true";
  if (s == "false" || s == "False" || s == "FALSE") return "false";
  if (std::string special = special_float(s); !special.empty()) return special;
  if (std::string number = json_number(s); !number.empty()) return number;
  return json_string(s);
}

// Where a value sits in the schema: the message type its keys belong to, and whether it is text.
struct Slot {
  const Descriptor* message = nullptr;
  bool text = false;
};

Slot slot_of(const Descriptor* message, const std::string& key) {
  if (message == nullptr) return {};
  const FieldDescriptor* field = detail::field_named(*message, key);
  if (field == nullptr) return {};  // the JSON mapping reports the unknown field
  const bool text =
      field->type() == FieldDescriptor::TYPE_STRING || field->type() == FieldDescriptor::TYPE_BYTES;
  return {field->message_type(), text};
}

// The JSON text of a YAML document, and where in the YAML each key and value of it came from,
// so that check_json's findings (duplicate keys among them) point into the YAML.
class YamlToJson {
 public:
  std::string convert(const YAML::Node& root) {
    if (root.IsNull()) fail(root.Mark(), "the document is empty (expected e.g. twist: {})");
    if (!root.IsMap()) fail(root.Mark(), "the document is not a mapping of spec fields");
    value(root, {mdem::v1::JobSpec::descriptor(), false}, "", 0);
    return std::move(out_);
  }

  // "line L, column C" in the YAML of the JSON text's byte `offset`.
  std::string locate(std::size_t offset) const {
    auto after = std::upper_bound(
        marks_.begin(), marks_.end(), offset,
        [](std::size_t o, const std::pair<std::size_t, YAML::Mark>& m) { return o < m.first; });
    if (after == marks_.begin()) return location(YAML::Mark());
    return location(std::prev(after)->second);
  }

 private:
  void value(const YAML::Node& n, const Slot& slot, const std::string& path, int depth) {
    if (depth > kMaxDepth)
      fail_at(path, n.Mark(),
              "nested deeper than " + std::to_string(kMaxDepth) + " levels (allowed: at most " +
                  std::to_string(kMaxDepth) + ")");
    if (out_.size() > kMaxSpecBytes)  // aliases can repeat a node exponentially often
      fail_at(path, n.Mark(),
              "expands to more than " + std::to_string(kMaxSpecBytes >> 20) +
                  " MiB of JSON (through aliases)");
    marks_.emplace_back(out_.size(), n.Mark());
    switch (n.Type()) {
      case YAML::NodeType::Map:
        return map(n, slot.message, path, depth);
      case YAML::NodeType::Sequence:
        return sequence(n, slot, path, depth);
      case YAML::NodeType::Scalar:
        return scalar(n, slot);
      default:
        out_ += "null";
    }
  }

  // Duplicate keys are left in for check_json, which finds them by field (either spelling).
  void map(const YAML::Node& n, const Descriptor* message, const std::string& path, int depth) {
    out_ += '{';
    bool first = true;
    for (auto it = n.begin(); it != n.end(); ++it) {
      if (!it->first.IsScalar())
        fail_at(path, it->first.Mark(), "a key must be a plain name (allowed: field names)");
      const std::string key = it->first.Scalar();
      if (!first) out_ += ',';
      first = false;
      marks_.emplace_back(out_.size(), it->first.Mark());
      out_ += json_string(key) + ':';
      value(it->second, slot_of(message, key), path.empty() ? key : path + "." + key, depth + 1);
    }
    out_ += '}';
  }

  void sequence(const YAML::Node& n, const Slot& slot, const std::string& path, int depth) {
    out_ += '[';
    for (std::size_t i = 0; i < n.size(); ++i) {
      if (i > 0) out_ += ',';
      value(n[i], slot, path + "[" + std::to_string(i) + "]", depth + 1);
    }
    out_ += ']';
  }

  void scalar(const YAML::Node& n, const Slot& slot) {
    if (slot.text || is_quoted_or_str(n))
      out_ += json_string(n.Scalar());
    else
      out_ += plain_scalar(n.Scalar());
  }

  std::string out_;
  std::vector<std::pair<std::size_t, YAML::Mark>> marks_;  // JSON offset -> YAML mark, ascending
};

std::vector<YAML::Node> load_documents(std::string_view text) {
  try {
    return YAML::LoadAll(std::string(text));
  } catch (const YAML::DeepRecursion& e) {  // whose own message says "bad file"
    fail(e.mark, "nested too deeply (" + std::to_string(e.depth()) + " levels)");
  } catch (const YAML::ParserException& e) {
    fail(e.mark, e.msg);
  } catch (const YAML::Exception& e) {
    fail(e.mark, e.msg);
  }
}

}  // namespace

mdem::v1::JobSpec parse_yaml(std::string_view text) {
  detail::check_size(text.size(), "yaml", "the spec");
  const std::vector<YAML::Node> docs = load_documents(text);
  if (docs.empty())
    fail(YAML::Mark::null_mark(), "the document is empty (expected e.g. twist: {})");
  if (docs.size() > 1)
    fail(docs[1].Mark(), std::to_string(docs.size()) + " documents found (allowed: one)");
  YamlToJson converter;
  const std::string json = converter.convert(docs[0]);
  return detail::parse_json_as(
      json, "yaml", [&converter](std::size_t offset) { return converter.locate(offset); });
}

}  // namespace mdem::spec
