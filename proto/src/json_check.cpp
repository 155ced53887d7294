// check_json: spec JSON read against JobSpec's schema before protobuf's JSON mapping reads it, so
// that nothing is merged or dropped silently (protobuf merges a list or message given twice) and
// every refusal names the field path the user wrote, where it is and what is allowed.
#include <google/protobuf/descriptor.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "input.h"
#include "mdem/spec.h"
#include "mdem/suggest.h"

namespace mdem::spec::detail {

namespace {

using google::protobuf::Descriptor;
using google::protobuf::FieldDescriptor;

// A forward iterator over the text that records how far the parser has read, so the handler
// can tell where the key it is given starts.
class TrackedChars {
 public:
  using iterator_category = std::forward_iterator_tag;
  using value_type = char;
  using difference_type = std::ptrdiff_t;
  using pointer = const char*;
  using reference = const char&;

  TrackedChars(const char* at, const char** read) : at_(at), read_(read) {}
  reference operator*() const { return *at_; }
  TrackedChars& operator++() {
    *read_ = ++at_;
    return *this;
  }
  TrackedChars operator++(int) {
    TrackedChars before = *this;
    ++*this;
    return before;
  }
  bool operator==(const TrackedChars& other) const { return at_ == other.at_; }
  bool operator!=(const TrackedChars& other) const { return at_ != other.at_; }

 private:
  const char* at_;
  const char** read_;
};

std::vector<std::string> field_list(const Descriptor& message) {
  std::vector<std::string> names;
  for (int i = 0; i < message.field_count(); ++i) names.push_back(message.field(i)->name());
  return names;
}

std::string field_names(const Descriptor& message) {
  std::string names;
  for (int i = 0; i < message.field_count(); ++i)
    names += (i ? ", " : "") + message.field(i)->name();
  return names;
}

// Where a value goes: the field (nullptr for the document), the fields from the document down
// to it, its path as written ("twist.missing_tubes[2]") and the offset of the key naming it.
struct Slot {
  const FieldDescriptor* field = nullptr;
  std::vector<const FieldDescriptor*> chain;
  bool element = false;  // an entry of a list
  std::string path;
  std::size_t offset = 0;
};

struct Frame {
  bool list = false;
  Slot slot;                            // the slot this object or list fills
  const Descriptor* message = nullptr;  // an object's type
  struct Seen {
    std::string key;
    std::size_t offset;
  };
  std::map<int, Seen> seen;  // field number -> first key naming it
  std::size_t next_index = 0;
  Slot pending;  // the slot of the last key read
};

bool is_integer(const FieldDescriptor& f) {
  switch (f.cpp_type()) {
    case FieldDescriptor::CPPTYPE_INT32:
    case FieldDescriptor::CPPTYPE_INT64:
    case FieldDescriptor::CPPTYPE_UINT32:
    case FieldDescriptor::CPPTYPE_UINT64:
      return true;
    default:
      return false;
  }
}

bool is_real(const FieldDescriptor& f) {
  return f.cpp_type() == FieldDescriptor::CPPTYPE_DOUBLE ||
         f.cpp_type() == FieldDescriptor::CPPTYPE_FLOAT;
}

// The integer type's limits as long doubles (exact for 64 bits).
std::pair<long double, long double> integer_limits(const FieldDescriptor& f) {
  switch (f.cpp_type()) {
    case FieldDescriptor::CPPTYPE_INT32:
      return {std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::max()};
    case FieldDescriptor::CPPTYPE_UINT32:
      return {0, std::numeric_limits<std::uint32_t>::max()};
    case FieldDescriptor::CPPTYPE_INT64:
      return {std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max()};
    default:
      return {0, std::numeric_limits<std::uint64_t>::max()};
  }
}

std::string integer_text(long double v) {
  return v < 0 ? std::to_string(static_cast<long long>(v))
               : std::to_string(static_cast<unsigned long long>(v));
}

// The "(allowed: ...)" text validate gives for the field at the end of `chain`: validate is
// shown a spec holding only that field, set beyond every range, so the rules stay in one place.
// "" when validate has no range for the field.
std::string validated_range(const std::vector<const FieldDescriptor*>& chain) {
  mdem::v1::JobSpec probe;
  google::protobuf::Message* m = &probe;
  std::string path;
  for (std::size_t i = 0; i < chain.size(); ++i) {
    const FieldDescriptor* f = chain[i];
    path += (path.empty() ? "" : ".") + f->name() + (f->is_repeated() ? "[0]" : "");
    const google::protobuf::Reflection* r = m->GetReflection();
    if (i + 1 < chain.size()) {
      m = f->is_repeated() ? r->AddMessage(m, f) : r->MutableMessage(m, f);
      continue;
    }
    const bool rep = f->is_repeated();
    switch (f->cpp_type()) {
      case FieldDescriptor::CPPTYPE_INT32: {
        const auto v = std::numeric_limits<std::int32_t>::max();
        rep ? r->AddInt32(m, f, v) : r->SetInt32(m, f, v);
        break;
      }
      case FieldDescriptor::CPPTYPE_INT64: {
        const auto v = std::numeric_limits<std::int64_t>::max();
        rep ? r->AddInt64(m, f, v) : r->SetInt64(m, f, v);
        break;
      }
      case FieldDescriptor::CPPTYPE_UINT32: {
        const auto v = std::numeric_limits<std::uint32_t>::max();
        rep ? r->AddUInt32(m, f, v) : r->SetUInt32(m, f, v);
        break;
      }
      case FieldDescriptor::CPPTYPE_UINT64: {
        const auto v = std::numeric_limits<std::uint64_t>::max();
        rep ? r->AddUInt64(m, f, v) : r->SetUInt64(m, f, v);
        break;
      }
      case FieldDescriptor::CPPTYPE_DOUBLE: {
        const double v = std::numeric_limits<double>::infinity();
        rep ? r->AddDouble(m, f, v) : r->SetDouble(m, f, v);
        break;
      }
      default:
        return "";
    }
  }
  for (const FieldError& e : validate(probe)) {
    if (e.field != path) continue;
    const std::size_t at = e.message.find("(allowed");
    if (at != std::string::npos) return e.message.substr(at);
  }
  return "";
}

// What a value of the slot's field may be.
std::string allowed(const Slot& slot) {
  const FieldDescriptor* f = slot.field;
  if (f == nullptr)
    return "(allowed: an object of spec fields: " + field_names(*mdem::v1::JobSpec::descriptor()) +
           ")";
  if (is_integer(*f) || is_real(*f)) {
    if (std::string range = validated_range(slot.chain); !range.empty()) return range;
    if (is_real(*f)) return "(allowed: a number, or \"NaN\", \"Infinity\", \"-Infinity\")";
    const auto [lo, hi] = integer_limits(*f);
    return "(allowed: a whole number, " + integer_text(lo) + ".." + integer_text(hi) + ")";
  }
  switch (f->cpp_type()) {
    case FieldDescriptor::CPPTYPE_BOOL:
      return "(allowed: true or false)";
    case FieldDescriptor::CPPTYPE_STRING:
      return "(allowed: text in quotes)";
    case FieldDescriptor::CPPTYPE_ENUM: {
      std::string names;
      for (int i = 0; i < f->enum_type()->value_count(); ++i)
        names += (i ? ", " : "") + f->enum_type()->value(i)->name();
      return "(allowed: " + names + ", or their numbers)";
    }
    default:
      return "(allowed: an object of the fields " + field_names(*f->message_type()) +
             (f->is_repeated() ? ", or a list of them)" : ")");
  }
}

// What the field expects, for "invalid value X: not <expected>".
std::string expected(const FieldDescriptor& f) {
  if (is_integer(f)) return "a whole number";
  if (is_real(f)) return "a number";
  switch (f.cpp_type()) {
    case FieldDescriptor::CPPTYPE_BOOL:
      return "true or false";
    case FieldDescriptor::CPPTYPE_STRING:
      return "text";
    case FieldDescriptor::CPPTYPE_ENUM:
      return "a name of " + f.enum_type()->name();
    default:
      return "an object";
  }
}

constexpr std::size_t kShown = 40;

// A number as the message shows it: a long one cut, with its length.
std::string shown_number(const std::string& text) {
  if (text.size() <= kShown) return text;
  return text.substr(0, kShown) + "... (" + std::to_string(text.size()) + " bytes)";
}

// A string as the message shows it, quoted: a long one cut, with its length.
std::string shown_string(const std::string& s) {
  const auto quoted = [](const std::string& text) {
    return nlohmann::json(text).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  };
  if (s.size() <= kShown) return quoted(s);
  std::string cut = quoted(s.substr(0, kShown));
  return cut.insert(cut.size() - 1, "...") + " (" + std::to_string(s.size()) + " bytes)";
}

// A JSON number's text: -?digits[.digits][e[+-]digits].
bool is_number_text(const std::string& s) {
  std::size_t i = s.size() > 0 && s[0] == '-' ? 1 : 0;
  const auto digits = [&] {
    const std::size_t start = i;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
    return i > start;
  };
  if (!digits()) return false;
  if (i < s.size() && s[i] == '.' && (++i, !digits())) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    if (!digits()) return false;
  }
  return i == s.size();
}

class SchemaCheck : public nlohmann::json_sax<nlohmann::json> {
 public:
  SchemaCheck(std::string_view text, const char* const* read, Locate locate)
      : text_(text), read_(read), locate_(std::move(locate)) {}

  bool null() override {
    const Slot slot = next_slot();
    if (slot.field == nullptr) return fail(slot, "the document is null " + allowed(slot));
    if (slot.element) return fail(slot, "null in a list " + allowed(slot));
    return true;  // unset
  }
  bool boolean(bool v) override {
    const Slot slot = next_slot();
    if (slot.field && slot.field->cpp_type() == FieldDescriptor::CPPTYPE_BOOL) return true;
    return wrong(slot, v ? "true" : "false");
  }
  bool number_integer(number_integer_t v) override {
    return whole_number(next_slot(), static_cast<long double>(v), std::to_string(v));
  }
  bool number_unsigned(number_unsigned_t v) override {
    return whole_number(next_slot(), static_cast<long double>(v), std::to_string(v));
  }
  bool number_float(number_float_t v, const string_t& written) override {
    const Slot slot = next_slot();
    const std::string text = shown_number(written);
    if (!slot.field || !(is_real(*slot.field) || is_integer(*slot.field) ||
                         slot.field->cpp_type() == FieldDescriptor::CPPTYPE_ENUM))
      return wrong(slot, text);
    if (is_real(*slot.field)) return true;
    if (std::floor(v) != v)
      return fail(slot, "invalid value " + text + ": not a whole number " + allowed(slot));
    return whole_number(slot, static_cast<long double>(v), text);
  }
  bool string(string_t& s) override {
    const Slot slot = next_slot();
    if (!slot.field) return wrong(slot, shown_string(s));
    const FieldDescriptor& f = *slot.field;
    if (f.cpp_type() == FieldDescriptor::CPPTYPE_STRING) return true;
    if (f.cpp_type() == FieldDescriptor::CPPTYPE_BOOL && (s == "true" || s == "false")) return true;
    if (f.cpp_type() == FieldDescriptor::CPPTYPE_ENUM) {
      if (f.enum_type()->FindValueByName(s)) return true;
      return fail(
          slot, "invalid value " + shown_string(s) + ": not " + expected(f) + " " + allowed(slot));
    }
    if (is_real(f)) {
      if (s == "NaN" || s == "Infinity" || s == "-Infinity") return true;
      if (is_number_text(s)) {
        if (std::isfinite(std::strtod(s.c_str(), nullptr))) return true;
        return fail(slot, "invalid value " + shown_string(s) +
                              ": out of range for a real-number field " + allowed(slot));
      }
    }
    if (is_integer(f) && is_number_text(s) && s.find_first_of(".eE") == std::string::npos)
      return whole_number(slot, std::strtold(s.c_str(), nullptr), shown_string(s));
    return wrong(slot, shown_string(s));
  }
  bool binary(binary_t&) override { return wrong(next_slot(), "binary data"); }

  bool start_object(std::size_t) override {
    const Slot slot = next_slot();
    if (too_deep(slot)) return false;
    const Descriptor* message =
        slot.field == nullptr ? mdem::v1::JobSpec::descriptor() : slot.field->message_type();
    if (message == nullptr) return wrong(slot, "{...}");
    Frame frame;
    frame.slot = slot;
    frame.message = message;
    frames_.push_back(std::move(frame));
    return true;
  }
  bool key(string_t& k) override {
    Frame& top = frames_.back();
    const std::size_t offset = key_offset();
    Slot slot;
    slot.path = top.slot.path.empty() ? k : top.slot.path + "." + k;
    slot.offset = offset;
    slot.field = field_named(*top.message, k);
    if (slot.field == nullptr)
      return fail(slot, "unknown field \"" + k + "\"" + did_you_mean(k, field_list(*top.message)) +
                            " (allowed: " + field_names(*top.message) + ")");
    const auto first = top.seen.find(slot.field->number());
    if (first != top.seen.end()) {
      const std::string as = first->second.key == k ? "" : " as \"" + first->second.key + "\"";
      return fail(slot, "duplicate key \"" + k + "\", the field is already given" + as + " at " +
                            locate_(first->second.offset) + " (allowed: each field once)");
    }
    if (const auto* oneof = slot.field->real_containing_oneof()) {
      for (const auto& [number, seen] : top.seen)
        if (top.message->FindFieldByNumber(number)->real_containing_oneof() == oneof) {
          std::string members;
          for (int i = 0; i < oneof->field_count(); ++i)
            members += (i ? ", " : "") + oneof->field(i)->name();
          return fail(slot, "\"" + k + "\" and \"" + seen.key + "\" are both given (allowed: one " +
                                oneof->name() + " of " + members + ")");
        }
    }
    top.seen[slot.field->number()] = {k, offset};
    slot.chain = top.slot.chain;
    slot.chain.push_back(slot.field);
    top.pending = std::move(slot);
    return true;
  }
  bool end_object() override {
    frames_.pop_back();
    return true;
  }
  bool start_array(std::size_t) override {
    const Slot slot = next_slot();
    if (too_deep(slot)) return false;
    if (slot.field == nullptr) return wrong(slot, "[...]");
    // A list inside a list is flattened by protobuf, as a bare value fills a list (see tests).
    if (!slot.field->is_repeated()) return wrong(slot, "[...]");
    Frame frame;
    frame.list = true;
    frame.slot = slot;
    frames_.push_back(std::move(frame));
    return true;
  }
  bool end_array() override {
    frames_.pop_back();
    return true;
  }

  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception& e) override {
    const std::string what = e.what();
    if (e.id == 406) {  // number overflow parsing '<text>'
      const std::size_t open = what.find('\'');
      const std::string text = shown_number(what.substr(open + 1, what.rfind('\'') - open - 1));
      const Slot slot = next_slot();
      if (!slot.field || !(is_real(*slot.field) || is_integer(*slot.field)))
        return wrong(slot, text);
      return fail(slot, "invalid value " + text + ": out of range for " +
                            (is_real(*slot.field) ? "a real-number field " : "an integer field ") +
                            allowed(slot));
    }
    // nlohmann's message without its "[json.exception.parse_error.101] " prefix.
    const std::size_t end = what.find("] ");
    message_ = end == std::string::npos ? what : what.substr(end + 2);
    return false;
  }

  std::string message() const { return message_; }

 private:
  // The slot the next value fills.
  Slot next_slot() {
    if (frames_.empty()) return {};
    Frame& top = frames_.back();
    if (!top.list) return top.pending;
    Slot slot = top.slot;
    slot.element = true;
    slot.path.append("[").append(std::to_string(top.next_index++)).append("]");
    return slot;
  }

  bool too_deep(const Slot& slot) {
    if (static_cast<int>(frames_.size()) < kMaxDepth) return false;
    fail(slot, "nested deeper than " + std::to_string(kMaxDepth) + " levels (allowed: at most " +
                   std::to_string(kMaxDepth) + ")");
    return true;
  }

  bool whole_number(const Slot& slot, long double v, const std::string& text) {
    if (!slot.field) return wrong(slot, text);
    const FieldDescriptor& f = *slot.field;
    if (is_real(f)) return true;
    if (f.cpp_type() == FieldDescriptor::CPPTYPE_ENUM) {
      if (v >= std::numeric_limits<std::int32_t>::min() &&
          v <= std::numeric_limits<std::int32_t>::max())
        return true;  // validate names an unknown number
      return fail(slot, "invalid value " + text + ": out of range " + allowed(slot));
    }
    if (!is_integer(f)) return wrong(slot, text);
    const auto [lo, hi] = integer_limits(f);
    if (v >= lo && v <= hi) return true;
    return fail(slot,
                "invalid value " + text + ": out of range for an integer field " + allowed(slot));
  }

  // A value of the wrong kind for its slot.
  bool wrong(const Slot& slot, const std::string& shown) {
    if (slot.field == nullptr)
      return fail(slot, "the document is " + shown + ", not a message object " + allowed(slot));
    const std::string what = slot.field->is_repeated() && !slot.element && shown == "[...]"
                                 ? "a list"
                                 : expected(*slot.field);
    return fail(slot, "invalid value " + shown + ": not " + what + " " + allowed(slot));
  }

  bool fail(const Slot& slot, const std::string& problem) {
    const std::string where = locate_(slot.offset);
    message_ =
        slot.path.empty() ? where + ": " + problem : slot.path + " (" + where + "): " + problem;
    return false;
  }

  // The offset of the opening quote of the key just read: the parser has read up to and
  // including its closing quote.
  std::size_t key_offset() const {
    std::size_t close = static_cast<std::size_t>(*read_ - text_.data()) - 1;
    for (std::size_t i = close; i-- > 0;) {
      if (text_[i] != '"') continue;
      std::size_t backslashes = 0;
      while (backslashes < i && text_[i - 1 - backslashes] == '\\') ++backslashes;
      if (backslashes % 2 == 0) return i;
    }
    return 0;
  }

  std::string_view text_;
  const char* const* read_;
  Locate locate_;
  std::vector<Frame> frames_;
  std::string message_;
};

}  // namespace

const FieldDescriptor* field_named(const Descriptor& message, const std::string& key) {
  if (const FieldDescriptor* field = message.FindFieldByName(key)) return field;
  for (int i = 0; i < message.field_count(); ++i)
    if (message.field(i)->json_name() == key) return message.field(i);
  return nullptr;
}

std::string text_location(std::string_view text, std::size_t offset) {
  std::size_t line = 1;
  std::size_t line_start = 0;
  for (std::size_t i = 0; i < offset && i < text.size(); ++i)
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  return "line " + std::to_string(line) + ", column " + std::to_string(offset - line_start + 1);
}

void check_json(std::string_view json, const std::string& field, const Locate& locate) {
  const char* read = json.data();
  SchemaCheck check(json, &read, locate);
  const TrackedChars begin(json.data(), &read);
  const TrackedChars end(json.data() + json.size(), &read);
  if (!nlohmann::json::sax_parse(begin, end, &check)) throw SpecError({{field, check.message()}});
}

}  // namespace mdem::spec::detail
