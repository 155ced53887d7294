#include "flags.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <system_error>

#include "mdem/suggest.h"

namespace mdem::cli {

namespace {

std::string_view trim(std::string_view s) {
  const auto space = [](char c) { return c == ' ' || c == '\t'; };
  while (!s.empty() && space(s.front())) s.remove_prefix(1);
  while (!s.empty() && space(s.back())) s.remove_suffix(1);
  return s;
}

std::string allowed_list(const FlagSpec& spec) {
  std::string out;
  for (const auto* names : {&spec.with_value, &spec.switches})
    for (const std::string& n : *names) out += (out.empty() ? "" : ", ") + n;
  return out + (out.empty() ? "" : ", ") + "--help";
}

// "unknown flag 'NAME'; did you mean --X? (allowed: ...)".
std::string unknown_flag(const std::string& name, const FlagSpec& spec) {
  std::vector<std::string> names = spec.with_value;
  names.insert(names.end(), spec.switches.begin(), spec.switches.end());
  names.push_back("--help");
  return "unknown flag '" + name + "'" + did_you_mean(name, names) +
         " (allowed: " + allowed_list(spec) + ")";
}

bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

}  // namespace

std::map<std::string, std::string> parse_flags(const std::vector<std::string>& args,
                                               const FlagSpec& spec) {
  std::map<std::string, std::string> given;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a.rfind("--", 0) != 0) {
      if (!a.empty() && a.front() == '-') throw UsageError(unknown_flag(a, spec));
      throw UsageError("unexpected argument '" + a + "' (allowed: " + allowed_list(spec) + ")");
    }
    const std::size_t eq = a.find('=');
    const std::string name = a.substr(0, eq);
    const bool is_switch = contains(spec.switches, name);
    if (!is_switch && !contains(spec.with_value, name)) throw UsageError(unknown_flag(name, spec));
    if (given.count(name)) throw UsageError(name + ": given more than once");
    if (is_switch) {
      if (eq != std::string::npos) throw UsageError(name + ": takes no value");
      given[name] = "";
      continue;
    }
    std::string value;
    if (eq != std::string::npos) {
      value = a.substr(eq + 1);
    } else {
      if (i + 1 >= args.size() || args[i + 1].rfind("--", 0) == 0)
        throw UsageError(name + ": missing value");
      value = args[++i];
    }
    if (value.empty()) throw UsageError(name + ": missing value");
    given[name] = value;
  }
  return given;
}

double parse_number(const std::string& flag, std::string_view text, const char* expected) {
  const std::string_view t = trim(text);
  std::string_view digits = t;
  if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
  double value = 0;
  const auto [ptr, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (digits.empty() || ptr != digits.data() + digits.size() || ec == std::errc::invalid_argument)
    throw UsageError(flag + ": '" + std::string(t) + "' is not a number (expected " + expected +
                     ")");
  if (ec == std::errc::result_out_of_range) {
    // Overflow is refused; underflow rounds to the nearest representable value.
    const std::string copy(digits);
    value = std::strtod(copy.c_str(), nullptr);
    if (!std::isfinite(value) || std::abs(value) >= 1e300)
      throw UsageError(flag + ": '" + std::string(t) + "' is out of range (expected " + expected +
                       ")");
  }
  if (!std::isfinite(value))
    throw UsageError(flag + ": '" + std::string(t) + "' is not finite (expected " + expected +
                     "; NaN and Inf are not allowed)");
  return value;
}

double parse_in_range(const std::string& flag, std::string_view text, double lo, double hi,
                      const char* unit) {
  std::ostringstream allowed;
  allowed << "a number in [" << lo << ", " << hi << "]" << (*unit ? " " : "") << unit;
  const std::string expected = allowed.str();
  const double v = parse_number(flag, text, expected.c_str());
  if (v < lo || v > hi)
    throw UsageError(flag + ": " + std::string(trim(text)) +
                     " is out of range (allowed: " + expected + ")");
  return v;
}

long parse_integer(const std::string& flag, std::string_view text, long lo, long hi) {
  const std::string_view t = trim(text);
  long value = 0;
  const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
  const std::string allowed =
      "a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  if (t.empty() || ptr != t.data() + t.size() || ec == std::errc::invalid_argument)
    throw UsageError(flag + ": '" + std::string(t) +
                     "' is not a whole number (allowed: " + allowed + ")");
  if (ec == std::errc::result_out_of_range || value < lo || value > hi)
    throw UsageError(flag + ": " + std::string(t) + " is out of range (allowed: " + allowed + ")");
  return value;
}

std::vector<double> parse_list(const std::string& flag, const std::string& text, std::size_t n,
                               const char* expected) {
  std::vector<std::string_view> parts;
  std::string_view rest = text;
  while (true) {
    const std::size_t comma = rest.find(',');
    parts.push_back(rest.substr(0, comma));
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  if (parts.size() != n) {
    std::ostringstream msg;
    msg << flag << ": expected " << n << " comma-separated numbers (" << expected << "), got "
        << parts.size() << " in '" << text << "'";
    throw UsageError(msg.str());
  }
  std::vector<double> values;
  for (const std::string_view part : parts) values.push_back(parse_number(flag, part, expected));
  return values;
}

namespace {

bool takes_value(const FlagSpec& spec, const std::string& arg) {
  return arg.find('=') == std::string::npos &&
         std::find(spec.with_value.begin(), spec.with_value.end(), arg) != spec.with_value.end();
}

}  // namespace

std::pair<std::string, std::map<std::string, std::string>> parse_id_and_flags(
    const std::vector<std::string>& args, const FlagSpec& spec) {
  std::vector<std::string> ids, rest;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a.size() > 1 && a.front() == '-') {
      rest.push_back(a);
      if (takes_value(spec, a) && i + 1 < args.size() && args[i + 1].rfind("--", 0) != 0)
        rest.push_back(args[++i]);
    } else {
      ids.push_back(a);
    }
  }
  auto given = parse_flags(rest, spec);
  if (ids.empty()) throw UsageError("missing the job ID (see `mdem ls`)");
  if (ids.size() > 1) throw UsageError("unexpected argument '" + ids[1] + "' (give one job ID)");
  if (ids.front().empty()) throw UsageError("the job ID is empty");
  return {ids.front(), std::move(given)};
}

bool wants_help(const std::vector<std::string>& args) {
  return std::any_of(args.begin(), args.end(),
                     [](const std::string& a) { return a == "--help" || a == "-h"; });
}

void write_json(std::ostream& os, const json& j, int indent) {
  if (!j.is_object()) {
    os << j.dump();
    return;
  }
  const std::string pad(indent + 2, ' ');
  os << "{\n";
  std::size_t k = 0;
  for (const auto& [key, value] : j.items()) {
    os << pad << json(key).dump() << ": ";
    write_json(os, value, indent + 2);
    os << (++k < j.size() ? ",\n" : "\n");
  }
  os << std::string(indent, ' ') << "}";
}

json parse_or_text(const std::string& text) {
  if (text.empty()) return nullptr;
  json j = json::parse(text, nullptr, false);
  return j.is_discarded() ? json(text) : j;
}

void print_table(std::ostream& os, const std::vector<std::vector<std::string>>& rows) {
  std::vector<std::size_t> width(rows.front().size(), 0);
  for (const auto& row : rows)
    for (std::size_t c = 0; c < row.size(); ++c) width[c] = std::max(width[c], row[c].size());
  for (const auto& row : rows) {
    std::string line;
    for (std::size_t c = 0; c < row.size(); ++c)
      line += c + 1 < row.size() ? row[c] + std::string(width[c] - row[c].size() + 2, ' ') : row[c];
    while (!line.empty() && line.back() == ' ') line.pop_back();
    os << line << '\n';
  }
}

}  // namespace mdem::cli
