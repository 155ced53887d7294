#include "mdem/time_text.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <vector>

namespace mdem {

std::string utc_text(std::chrono::system_clock::time_point t) {
  const std::time_t s = std::chrono::system_clock::to_time_t(t);
  std::tm tm{};
  gmtime_r(&s, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string utc_now_text() { return utc_text(std::chrono::system_clock::now()); }

std::optional<double> epoch_seconds(std::string_view iso) {
  const std::string s(iso);
  std::tm tm{};
  int consumed = 0;
  if (std::sscanf(s.c_str(), "%4d-%2d-%2dT%2d:%2d:%2d%n", &tm.tm_year, &tm.tm_mon, &tm.tm_mday,
                  &tm.tm_hour, &tm.tm_min, &tm.tm_sec, &consumed) != 6 ||
      consumed != 19)
    return std::nullopt;
  double frac = 0;
  std::size_t end = 19;
  if (end < s.size() && s[end] == '.') {
    std::size_t k = end + 1;
    while (k < s.size() && s[k] >= '0' && s[k] <= '9') ++k;
    if (k == end + 1) return std::nullopt;
    frac = std::stod("0" + s.substr(end, k - end));
    end = k;
  }
  if (end + 1 != s.size() || s[end] != 'Z') return std::nullopt;
  tm.tm_year -= 1900;
  tm.tm_mon -= 1;
  return static_cast<double>(timegm(&tm)) + frac;
}

std::string shown_time(std::string_view iso) {
  if (!epoch_seconds(iso)) return std::string(iso);
  return std::string(iso.substr(0, 19)) + "Z";
}

std::string duration_text(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "-";
  const long s = static_cast<long>(seconds);
  char buf[48];
  if (s >= 86400)
    std::snprintf(buf, sizeof buf, "%ld-%02ld:%02ld:%02ld", s / 86400, s % 86400 / 3600,
                  s % 3600 / 60, s % 60);
  else
    std::snprintf(buf, sizeof buf, "%02ld:%02ld:%02ld", s / 3600, s % 3600 / 60, s % 60);
  return buf;
}

const char* time_limit_forms() {
  return "a number with a unit (90s, 15m, 2h, 1.5d), or as Slurm's --time: MM, MM:SS, "
         "HH:MM:SS, D-HH, D-HH:MM, D-HH:MM:SS; above 0 and at most 30 days";
}

namespace {

// A whole number of digits only.
std::optional<long> whole(std::string_view t) {
  if (t.empty() || t.size() > 9) return std::nullopt;
  long n = 0;
  const auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), n);
  if (ec != std::errc() || p != t.data() + t.size() || n < 0) return std::nullopt;
  return n;
}

std::vector<std::string_view> split(std::string_view t, char sep) {
  std::vector<std::string_view> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t k = t.find(sep, start);
    parts.push_back(
        t.substr(start, k == std::string_view::npos ? std::string_view::npos : k - start));
    if (k == std::string_view::npos) return parts;
    start = k + 1;
  }
}

// Slurm's forms: "[D-]..." with 1..3 colon-separated whole numbers. nullopt when malformed.
std::optional<double> slurm_form(std::string_view t) {
  long days = 0;
  bool with_days = false;
  if (const std::size_t dash = t.find('-'); dash != std::string_view::npos) {
    const auto d = whole(t.substr(0, dash));
    if (!d) return std::nullopt;
    days = *d;
    with_days = true;
    t = t.substr(dash + 1);
  }
  const std::vector<std::string_view> parts = split(t, ':');
  if (parts.size() > 3) return std::nullopt;
  std::vector<long> v;
  for (std::string_view p : parts) {
    const auto n = whole(p);
    if (!n) return std::nullopt;
    v.push_back(*n);
  }
  double s = 0;
  if (with_days) {  // D-HH, D-HH:MM, D-HH:MM:SS
    s = v[0] * 3600.0 + (v.size() > 1 ? v[1] * 60.0 : 0) + (v.size() > 2 ? v[2] : 0);
  } else if (v.size() == 1) {  // MM
    s = v[0] * 60.0;
  } else if (v.size() == 2) {  // MM:SS
    s = v[0] * 60.0 + v[1];
  } else {  // HH:MM:SS
    s = v[0] * 3600.0 + v[1] * 60.0 + v[2];
  }
  return days * 86400.0 + s;
}

// "90s", "15m", "2h", "1.5d". nullopt when malformed.
std::optional<double> unit_form(std::string_view t) {
  if (t.size() < 2) return std::nullopt;
  double unit = 0;
  switch (t.back()) {
    case 's':
      unit = 1;
      break;
    case 'm':
      unit = 60;
      break;
    case 'h':
      unit = 3600;
      break;
    case 'd':
      unit = 86400;
      break;
    default:
      return std::nullopt;
  }
  t.remove_suffix(1);
  double x = 0;
  const auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), x);
  if (ec != std::errc() || p != t.data() + t.size()) return std::nullopt;
  return x * unit;
}

}  // namespace

double parse_time_limit(std::string_view text, std::string_view who) {
  auto refuse = [&](const std::string& what) -> double {
    const std::string shown =
        text.size() > 40 ? std::string(text.substr(0, 40)) + "..." : std::string(text);
    throw std::invalid_argument(std::string(who) + ": '" + shown + "' " + what +
                                "; accepted: " + time_limit_forms());
  };
  if (text.empty()) return refuse("is empty");
  if (text.front() == '-' || text.front() == '+')
    return refuse(text.front() == '-' ? "is negative" : "has a sign");
  const bool letters = text.back() >= 'a' && text.back() <= 'z';
  const std::optional<double> s = letters ? unit_form(text) : slurm_form(text);
  if (!s) return refuse("is not a wall-time limit");
  if (!std::isfinite(*s)) return refuse("is not finite");
  if (*s <= 0) return refuse("is zero");
  if (*s > kMaxTimeLimitS) return refuse("is above the maximum");
  return *s;
}

}  // namespace mdem
