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

const MaterialPreset* material_preset(mdem::v1::GrainMaterialKind kind) {
  // scenes.md compression: Au E = 79 GPa, nu = 0.46, 19.3 g/cm3, plastic sigma_y 2-8 GPa;
  // CdS E = 28 GPa, nu = 0.46, 4.82 g/cm3, brittle sigma_f = 4 GPa.
  static constexpr MaterialPreset kGold{79.0, 0.46, 19.3, 8.0, mdem::v1::PLASTIC};
  static constexpr MaterialPreset kCadmiumSulfide{28.0, 0.46, 4.82, 4.0, mdem::v1::BRITTLE};
  switch (kind) {
    case mdem::v1::GOLD:
    case mdem::v1::GRAIN_MATERIAL_UNSPECIFIED:
      return &kGold;
    case mdem::v1::CADMIUM_SULFIDE:
      return &kCadmiumSulfide;
    default:
      return nullptr;
  }
}

}  // namespace mdem::spec::detail
