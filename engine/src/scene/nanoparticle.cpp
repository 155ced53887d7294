#include "mdem/scene/nanoparticle.h"

#include <stdexcept>

#include "mdem/core/np.h"

namespace mdem {

ElementInit nanoparticle(const Vec3& x) {
  if (!x.allFinite()) throw std::invalid_argument("nanoparticle position must be finite");
  ElementInit e;
  e.kind = ElementKind::Nanoparticle;
  e.x = x;
  e.mass = np::kMass;
  e.inertia = Vec3::Constant(np::kInertia);
  e.radius = np::kRadius;
  return e;
}

}  // namespace mdem
