// Ranges as text, and the error collector every kind's validation writes to.
#include "rules.h"

#include <charconv>
#include <cmath>

namespace mdem::spec {

bool contains(const Range& r, double v) {
  if (!std::isfinite(v)) return false;
  const bool lo_ok = r.lo_open ? v > r.lo : v >= r.lo;
  const bool hi_ok = r.hi_open ? v < r.hi : v <= r.hi;
  return lo_ok && hi_ok;
}

std::string number_text(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

std::string allowed(const Range& r) {
  std::string s = "(allowed: ";
  s += r.lo_open ? "> " : ">= ";
  s += number_text(r.lo);
  s += r.hi_open ? " and < " : " and <= ";
  s += number_text(r.hi);
  if (!r.unit.empty()) s.append(" ").append(r.unit);
  if (!r.note.empty()) s.append("; ").append(r.note);
  return s + ")";
}

std::string interval_text(const Range& r) {
  std::string s = r.lo_open ? "(" : "[";
  s += number_text(r.lo) + ", " + number_text(r.hi);
  s += r.hi_open ? ")" : "]";
  if (!r.unit.empty()) s.append(" ").append(r.unit);
  return s;
}

void Checks::add(std::string field, std::string message) {
  errors_.push_back({std::move(field), std::move(message)});
}

void Checks::real(const std::string& field, bool has, double v, const Range& range) {
  if (!has) return;
  if (!std::isfinite(v))
    add(field, number_text(v) + " is not a finite number " + allowed(range));
  else if (!contains(range, v))
    add(field, number_text(v) + " is out of range " + allowed(range));
}

void Checks::integer(const std::string& field, bool has, long long v, const Range& range) {
  if (has && !contains(range, static_cast<double>(v)))
    add(field, std::to_string(v) + " is out of range " + allowed(range));
}

}  // namespace mdem::spec
