#pragma once
// One table for every unit conversion in mdem (model.md §1).
//
// Internal system: length nm, time ps, energy eV, angle rad. Mass is then in eV·ps²/nm²,
// force in eV/nm, torque and moment in eV, stiffness of a bond ring in eV/nm⁴, pressure in eV/nm³.
// Only mass, force, moment and pressure need converting from the user-facing units
// (amu, nN, nN·nm, GPa); lengths, times and energies are already internal.
namespace mdem::units {

// Exact SI definitions used to derive the table below.
inline constexpr double kElectronVoltJ = 1.602176634e-19;  // J
inline constexpr double kAmuKg = 1.66053906660e-27;        // kg (the dalton, not the proton mass)

// amu -> eV·ps²/nm²: 1 amu·nm²/ps² = 1.66053906660e-27 kg·1e-18 m² / 1e-24 s² in eV.
inline constexpr double kAmu = kAmuKg * 1e-18 / 1e-24 / kElectronVoltJ;  // 1.036426966e-2
// nN -> eV/nm: 1 nN·1 nm = 1e-18 J.
inline constexpr double kNanoNewton = 1e-18 / kElectronVoltJ;  // 6.241509074
// nN·nm -> eV (same number as nN -> eV/nm).
inline constexpr double kNanoNewtonNm = kNanoNewton;
// GPa -> eV/nm³: 1e9 Pa · 1e-27 m³ = 1e-18 J.
inline constexpr double kGigaPascal = 1e-18 / kElectronVoltJ;  // 6.241509074
// g/cm³ -> amu/nm³ (for grain densities): 1 g/cm³ = 1e-3 kg / 1e21 nm³.
inline constexpr double kGramPerCm3InAmuPerNm3 = 1e-3 / 1e21 / kAmuKg;  // 602.2140762
// Strain rate: 1 /fs = 1e3 /ps.
inline constexpr double kPerFemtosecond = 1e3;
// Time: 1 fs = 1e-3 ps.
inline constexpr double kFemtosecond = 1e-3;
// Boltzmann constant in eV/K (CODATA 2018, exact: 1.380649e-23 J/K over e).
inline constexpr double kBoltzmann = 1.380649e-23 / kElectronVoltJ;  // 8.617333e-5

// Convenience converters, user unit -> internal.
constexpr double amu(double m) { return m * kAmu; }
constexpr double nN(double f) { return f * kNanoNewton; }
constexpr double nNnm(double m) { return m * kNanoNewtonNm; }
constexpr double GPa(double p) { return p * kGigaPascal; }
// internal -> user unit.
constexpr double to_amu(double m) { return m / kAmu; }
constexpr double to_nN(double f) { return f / kNanoNewton; }
constexpr double to_nNnm(double m) { return m / kNanoNewtonNm; }
constexpr double to_GPa(double p) { return p / kGigaPascal; }

}  // namespace mdem::units
