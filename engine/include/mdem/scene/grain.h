#pragma once
// Grains of a nanocrystalline particle (model.md §2, §6): rigid spheres, mass ρ·(4/3)πR³,
// inertia 2/5·m·R²; and the rigid flat platens (ElementKind::Wall) that load them.
#include <vector>

#include "mdem/core/elements.h"

namespace mdem {

// A grain material (model.md §6, scenes.md compression), internal units.
struct GrainMaterial {
  double youngs = 0;   // E (eV/nm³)
  double poisson = 0;  // ν, in [0, 0.5)
  double density = 0;  // ρ (eV·ps²/nm⁵, i.e. internal mass per nm³)
  double shear() const { return youngs / (2.0 * (1.0 + poisson)); }  // G = E/(2(1+ν))
};

// Au (E = 79 GPa, ν = 0.46, ρ = 19.3 g/cm³) and CdS (E = 28 GPa, ν = 0.46, ρ = 4.82 g/cm³).
GrainMaterial gold();
GrainMaterial cadmium_sulfide();

// One grain of radius r (nm) at x. Throws std::invalid_argument for a non-positive or non-finite
// radius or density.
ElementInit grain_element(const Vec3& x, double radius, const GrainMaterial& m);

// A platen through `point` whose unit normal (its body z) is `normal` (normalized here), pointing
// towards the material. Its mass only enters the kinetic energy its prescribed motion carries;
// `radius` is what the run guard compares its per-step motion with; its inertia is mass·radius².
// Throws std::invalid_argument for a non-finite point, a zero or non-finite normal, or a
// non-positive mass or radius. ElementInit carries no DOF modes and Elements::add makes every DOF
// Free: add a platen with add_platen (or call Elements::fix_all on it), so that all its DOFs start
// Fixed until a protocol prescribes them.
ElementInit platen_element(const Vec3& point, const Vec3& normal, double mass, double radius);
// Adds platen_element(point, normal, mass, radius) to el with all six DOFs Fixed; returns its
// index.
std::size_t add_platen(Elements& el, const Vec3& point, const Vec3& normal, double mass,
                       double radius);

// Eq. 36's normal stiffness k_n = π·R_l²·E*/L_l between two grains of one material
// (1/E* = 1/E + 1/E, so E* = E/2): with R_l = min(R1, R2) and L_l = R1 + R2 for a contact, or the
// neck radius of a broken bond for its post-break contact (section_radius).
double grain_contact_stiffness(double youngs, double ri, double rj);
double grain_contact_stiffness(double youngs, double ri, double rj, double section_radius);
// A grain of radius R against a rigid wall, flat or spherical: the rigid limit of Eq. 36's neck,
// k_n = π·R²·E/R = π·R·E (planar_wall.h).
double wall_contact_stiffness(double youngs, double radius);

// The platens (ElementKind::Wall elements) of a system and their planes: the indices are found
// once (again when the element count changes), the planes refreshed by update() without
// allocating, so a force model may call it every evaluation.
class PlatenPlanes {
 public:
  void update(const Elements& el);
  std::size_t size() const { return index_.size(); }
  std::size_t index(std::size_t w) const { return index_[w]; }
  const Vec3& point(std::size_t w) const { return point_[w]; }
  const Vec3& normal(std::size_t w) const { return normal_[w]; }  // towards the material
  // Distance of x from platen w's plane along its normal (negative behind it).
  double height(std::size_t w, const Vec3& x) const { return normal_[w].dot(x - point_[w]); }
  // Calls fn(i), once per platen, for every grain within a diameter of touching it: the grains it
  // meets first as it advances (those behind are shielded by them); the time-step bounds count
  // these.
  template <class Fn>
  void for_each_grain_near(const Elements& el, Fn&& fn) const {
    for (std::size_t w = 0; w < size(); ++w)
      for (std::size_t i = 0; i < el.size(); ++i)
        if (el.kind[i] == ElementKind::Grain && height(w, el.x[i]) < 3.0 * el.radius[i]) fn(i);
  }

 private:
  std::vector<std::size_t> index_;
  std::vector<Vec3> point_, normal_;
  std::size_t scanned_ = static_cast<std::size_t>(-1);
};

}  // namespace mdem
