#pragma once
// Helpers shared by the system-level tests.
#include <algorithm>
#include <cmath>

#include "mdem/system.h"

namespace mdem::testing {

// Largest unbalanced force (eV/nm) and moment (eV) on free DOFs: internal + external.
inline double max_unbalanced(const System& sys) {
  const Elements& el = sys.elements();
  double m = 0;
  for (std::size_t i = 0; i < el.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      if (el.dof[i][k] == DofMode::Free) m = std::max(m, std::abs(el.f[i][k] + el.f_ext[i][k]));
      if (el.dof[i][k + 3] == DofMode::Free) m = std::max(m, std::abs(el.t[i][k] + el.t_ext[i][k]));
    }
  return m;
}

// Runs a damped system in chunks until the unbalanced force falls below tol and the kinetic
// energy below ke_tol (static equilibrium), or max_steps pass. Returns the steps taken.
inline long relax(System& sys, double tol, double ke_tol, long max_steps, long chunk = 2000) {
  long done = 0;
  while (done < max_steps) {
    sys.run(chunk);
    done += chunk;
    if (max_unbalanced(sys) < tol && sys.energy().kinetic() < ke_tol) break;
  }
  return done;
}

}  // namespace mdem::testing
