#pragma once
// Limits the engine enforces on its own settings, and the one place they are written: the job
// spec's rules (proto/include/mdem/spec_rules.h) read them, so validation, the CLI's flag help
// and the engine's checks agree.
namespace mdem::limits {

// Worker threads of one System (IntegratorSettings::threads, 0 = all cores).
inline constexpr int kMaxThreads = 256;

// Inner steps per outer step of multiple time stepping (IntegratorSettings::respa_k, 1 = off).
inline constexpr int kMaxRespaK = 16;

// Largest damping ratio of a contact or bond dashpot (ViscousContactDamping, GrainDashpots):
// critical damping. The critical time step assumes an under-damped dashpot; above 1 the explicit
// damping term's own stability limit, dt < 1 / (ratio x omega), would undercut it.
inline constexpr double kMaxDashpotRatio = 1.0;

// Neighbour-list rebuilds between two reorderings of the elements along a space-filling curve
// (IntegratorSettings::memory_order_every).
inline constexpr int kMaxReorderEvery = 1000000;

}  // namespace mdem::limits
