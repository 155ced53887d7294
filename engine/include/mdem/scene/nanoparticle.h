#pragma once
// The Si nanoparticle element (model.md §2, §5): a sphere of radius 2.5 nm, 3870 Si atoms
// (108 691 amu), inertia 2/5·m·r².
#include "mdem/core/elements.h"

namespace mdem {

// One NP at x. Throws std::invalid_argument for a non-finite position.
ElementInit nanoparticle(const Vec3& x);

}  // namespace mdem
