#pragma once
// Constants of the (10,10) single-walled CNT segment (model.md §2-3), in internal units.
#include "mdem/core/units.h"

namespace mdem::cnt {

inline constexpr double kRadius = 0.678;                 // nm
inline constexpr double kSegmentLength = 2.0 * kRadius;  // T = 2r, bond rest length (nm)
inline constexpr double kWall = 0.336;                   // nm
inline constexpr double kMassAmu = 2648.8;               // 220.5 C atoms
inline constexpr double kMass = kMassAmu * units::kAmu;  // eV·ps²/nm²
// Thin hoop, isotropic: I = m r².
inline constexpr double kInertia = kMass * kRadius * kRadius;
// PFC-compatible alternative 2/5 m r².
inline constexpr double kInertiaPfc = 0.4 * kMass * kRadius * kRadius;

// Parallel bond ring (Table 2-1).
inline constexpr double kBondArea = 1.427;      // nm²
inline constexpr double kBondI = 0.348;         // nm⁴
inline constexpr double kBondJ = 2.0 * kBondI;  // nm⁴
inline constexpr double kBondKn = 4740.0;       // eV/nm⁴ (normal stiffness per area)
inline constexpr double kBondKs = 2110.0;       // eV/nm⁴ (shear stiffness per area)

}  // namespace mdem::cnt
