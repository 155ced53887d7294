#pragma once
// Constants of the Si nanoparticle (NP) element (model.md §2, §5), in internal units.
#include "mdem/core/units.h"

namespace mdem::np {

inline constexpr double kRadius = 2.5;                   // r_NP (nm)
inline constexpr double kMassAmu = 108691.0;             // 3870 Si atoms
inline constexpr double kMass = kMassAmu * units::kAmu;  // eV·ps²/nm²
// Solid sphere: I = 2/5 m r².
inline constexpr double kInertia = 0.4 * kMass * kRadius * kRadius;

}  // namespace mdem::np
