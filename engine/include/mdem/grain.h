#pragma once
// Grains of a nanocrystalline particle (model.md §2, §6): rigid spheres, mass ρ·(4/3)πR³,
// inertia 2/5·m·R²; and the rigid flat platens (ElementKind::Wall) that load them.
#include "mdem/elements.h"

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

}  // namespace mdem
