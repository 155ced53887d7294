// parse_yaml: YAML -> JSON text (guided by the message schema where keys match) -> JSON mapping.
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>
#include <regex>
#include <set>

#include "input.h"
#include "mdem/spec.h"

namespace mdem::spec {

namespace {

using google::protobuf::Descriptor;
using google::protobuf::FieldDescriptor;

constexpr int kMaxDepth = 32;

std::string location(const YAML::Mark& mark) {
  if (mark.line < 0) return "";
  return "line " + std::to_string(mark.line + 1) + ", column " + std::to_string(mark.column + 1) +
         ": ";
}

[[noreturn]] void fail(const YAML::Mark& mark, const std::string& message) {
  throw SpecError({{"yaml", location(mark) + message}});
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
  static const std::regex nan(R"(\.(nan|NaN|NAN))");
  static const std::regex inf(R"([+]?\.(inf|Inf|INF))");
  static const std::regex neg_inf(R"(-\.(inf|Inf|INF))");
  if (std::regex_match(s, nan)) return "\"NaN\"";
  if (std::regex_match(s, inf)) return "\"Infinity\"";
  if (std::regex_match(s, neg_inf)) return "\"-Infinity\"";
  return "";
}

// A YAML decimal number as JSON number text ("+.5" -> "0.5", "007" -> "7", "1." -> "1"); "" if
// s is not a number. The digits are kept as written, so 64-bit integers stay exact.
std::string json_number(const std::string& s) {
  static const std::regex number(R"(([-+]?)([0-9]*)(?:\.([0-9]*))?([eE][-+]?[0-9]+)?)");
  std::smatch m;
  if (!std::regex_match(s, m, number) || (m[2].length() == 0 && m[3].length() == 0)) return "";
  std::string out = m[1] == "-" ? "-" : "";
  const std::string whole = m[2].str();
  const std::size_t first = whole.find_first_not_of('0');
  out += first == std::string::npos ? "0" : whole.substr(first);
  if (m[3].length() > 0) out += "." + m[3].str();
  return out + m[4].str();
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

// The field a key names, as the JSON mapping reads it: proto name or JSON (lowerCamel) name.
const FieldDescriptor* field_named(const Descriptor& message, const std::string& key) {
  if (const FieldDescriptor* field = message.FindFieldByName(key)) return field;
  for (int i = 0; i < message.field_count(); ++i)
    if (message.field(i)->json_name() == key) return message.field(i);
  return nullptr;
}

Slot slot_of(const Descriptor* message, const std::string& key) {
  if (message == nullptr) return {};
  const FieldDescriptor* field = field_named(*message, key);
  if (field == nullptr) return {};  // the JSON mapping reports the unknown field
  const bool text =
      field->type() == FieldDescriptor::TYPE_STRING || field->type() == FieldDescriptor::TYPE_BYTES;
  return {field->message_type(), text};
}

class YamlToJson {
 public:
  std::string convert(const YAML::Node& root) {
    if (root.IsNull()) fail(root.Mark(), "the document is empty (expected e.g. twist: {})");
    if (!root.IsMap()) fail(root.Mark(), "the document is not a mapping of spec fields");
    value(root, {mdem::v1::JobSpec::descriptor(), false}, 0);
    return std::move(out_);
  }

 private:
  void value(const YAML::Node& n, const Slot& slot, int depth) {
    if (depth > kMaxDepth)
      fail(n.Mark(), "nested deeper than " + std::to_string(kMaxDepth) + " levels");
    if (out_.size() > kMaxSpecBytes)  // aliases can repeat a node exponentially often
      fail(n.Mark(), "expands to more than " + std::to_string(kMaxSpecBytes >> 20) +
                         " MiB of JSON (through aliases)");
    switch (n.Type()) {
      case YAML::NodeType::Map:
        return map(n, slot.message, depth);
      case YAML::NodeType::Sequence:
        return sequence(n, slot, depth);
      case YAML::NodeType::Scalar:
        return scalar(n, slot);
      default:
        out_ += "null";
    }
  }

  void map(const YAML::Node& n, const Descriptor* message, int depth) {
    std::set<std::string> keys;
    out_ += '{';
    for (auto it = n.begin(); it != n.end(); ++it) {
      if (!it->first.IsScalar()) fail(it->first.Mark(), "a key must be a plain name");
      const std::string key = it->first.Scalar();
      if (!keys.insert(key).second) fail(it->first.Mark(), "duplicate key \"" + key + "\"");
      if (keys.size() > 1) out_ += ',';
      out_ += json_string(key) + ':';
      value(it->second, slot_of(message, key), depth + 1);
    }
    out_ += '}';
  }

  void sequence(const YAML::Node& n, const Slot& slot, int depth) {
    out_ += '[';
    for (std::size_t i = 0; i < n.size(); ++i) {
      if (i > 0) out_ += ',';
      value(n[i], slot, depth + 1);
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
  return detail::parse_json_as(YamlToJson().convert(docs[0]), "yaml");
}

}  // namespace mdem::spec
