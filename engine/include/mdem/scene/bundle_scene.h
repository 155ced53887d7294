#pragma once
// The bundle scene: one or seven parallel (10,10) tubes with intra-tube bonds and the
// anisotropic vdW contact, set vibrating and spinning with seeded random velocities. It is the
// engine's energy-conservation check in scene form (and `mdem run bundle`).
#include "mdem/integrate/system.h"

namespace mdem {

struct BundleSpec {
  int tubes = 7;          // 1 or 7
  int segments = 50;      // per tube
  double spacing = 1.72;  // nm, centre to centre (the vdW equilibrium is 1.70–1.74 nm)
  // Vibration: random velocities and angular velocities, rms per component. 0.05 nm/ps and
  // 0.08 rad/ps put about kT at 800 K into each degree of freedom of a segment.
  double speed = 0.05;  // nm/ps
  double spin = 0.08;   // rad/ps
  // Rigid spin of the whole bundle about its axis (x), on top of the vibration.
  double bundle_spin = 0.05;  // rad/ps
  unsigned seed = 1;
};

// Seeded normal random velocities and angular velocities (rms per component), drawn with a
// fixed mapping from std::mt19937_64 so the same seed gives the same motion everywhere.
void randomize_motion(Elements& el, double speed_rms, double spin_rms, unsigned seed);

// Builds the scene (bonds + vdW, no damping unless the settings ask for it). Throws
// std::invalid_argument for tubes other than 1 or 7, fewer than 2 segments, or a spacing, speed,
// spin or bundle spin that is not finite and >= 0 (spacing > 0).
System make_bundle_system(const BundleSpec& spec, IntegratorSettings settings = {});

}  // namespace mdem
