#include "rules.h"

#include <charconv>
#include <cmath>

namespace mdem::spec::detail {

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

}  // namespace mdem::spec::detail
