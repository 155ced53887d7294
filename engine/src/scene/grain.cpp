// Grains and platens of granular scenes (grain.h, model.md §2, §6).
#include "mdem/scene/grain.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "mdem/core/units.h"

namespace mdem {

namespace {

// g/cm³ -> internal mass per nm³ (eV·ps²/nm⁵).
double density(double g_per_cm3) { return g_per_cm3 * units::kGramPerCm3InAmuPerNm3 * units::kAmu; }

void require_positive(double v, const char* what, const char* field, const char* unit) {
  if (!std::isfinite(v) || !(v > 0))
    throw std::invalid_argument(std::string(what) + " " + field + " must be finite and > 0 " +
                                unit + ", got " + std::to_string(v));
}

}  // namespace

GrainMaterial gold() { return {units::GPa(79.0), 0.46, density(19.3)}; }

GrainMaterial cadmium_sulfide() { return {units::GPa(28.0), 0.46, density(4.82)}; }

ElementInit grain_element(const Vec3& x, double radius, const GrainMaterial& m) {
  require_positive(radius, "grain", "radius", "nm");
  require_positive(m.density, "grain", "density", "(internal mass per nm³)");
  if (!x.allFinite()) throw std::invalid_argument("grain position must be finite");
  ElementInit e;
  e.kind = ElementKind::Grain;
  e.x = x;
  e.radius = radius;
  e.mass = m.density * (4.0 / 3.0) * std::numbers::pi * radius * radius * radius;
  e.inertia = Vec3::Constant(0.4 * e.mass * radius * radius);
  return e;
}

ElementInit platen_element(const Vec3& point, const Vec3& normal, double mass, double radius) {
  if (!point.allFinite()) throw std::invalid_argument("platen point must be finite");
  const double len = normal.norm();
  if (!normal.allFinite() || !(len > 1e-12))
    throw std::invalid_argument("platen normal must be a finite, non-zero vector");
  require_positive(mass, "platen", "mass", "(eV·ps²/nm²)");
  require_positive(radius, "platen", "radius", "nm");
  ElementInit e;
  e.kind = ElementKind::Wall;
  e.x = point;
  e.q = Quat::FromTwoVectors(Vec3::UnitZ(), normal / len).normalized();
  e.mass = mass;
  e.radius = radius;
  // Any positive inertia: a platen never rotates freely.
  e.inertia = Vec3::Constant(mass * radius * radius);
  return e;
}

std::size_t add_platen(Elements& el, const Vec3& point, const Vec3& normal, double mass,
                       double radius) {
  const std::size_t k = el.add(platen_element(point, normal, mass, radius));
  el.fix_all(k);
  return k;
}

double grain_contact_stiffness(double youngs, double ri, double rj, double section_radius) {
  return std::numbers::pi * section_radius * section_radius * (0.5 * youngs) / (ri + rj);
}

double grain_contact_stiffness(double youngs, double ri, double rj) {
  return grain_contact_stiffness(youngs, ri, rj, std::min(ri, rj));
}

double wall_contact_stiffness(double youngs, double radius) {
  return std::numbers::pi * radius * youngs;
}

void PlatenPlanes::update(const Elements& el) {
  if (scanned_ != el.size()) {
    index_.clear();
    for (std::size_t i = 0; i < el.size(); ++i)
      if (el.kind[i] == ElementKind::Wall) index_.push_back(i);
    point_.resize(index_.size());
    normal_.resize(index_.size());
    scanned_ = el.size();
  }
  for (std::size_t w = 0; w < index_.size(); ++w) {
    point_[w] = el.x[index_[w]];
    normal_[w] = (el.q[index_[w]] * Vec3::UnitZ()).normalized();
  }
}

}  // namespace mdem
