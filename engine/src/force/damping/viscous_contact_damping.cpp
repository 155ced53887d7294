#include "mdem/force/damping/viscous_contact_damping.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "mdem/core/limits.h"

namespace mdem {

ContactDampingKernel::ContactDampingKernel(ContactDampingParams p, DashpotEvaluation e)
    : p_(p), eval_(e) {
  if (!std::isfinite(p.ratio) || p.ratio < 0 || p.ratio > limits::kMaxDashpotRatio)
    throw std::invalid_argument("contact damping ratio must be finite and in [0, " +
                                std::to_string(static_cast<int>(limits::kMaxDashpotRatio)) +
                                "] (critical damping), got " + std::to_string(p.ratio));
  if (!std::isfinite(p.stiffness) || p.stiffness <= 0)
    throw std::invalid_argument("contact damping stiffness must be finite and > 0");
  if (!std::isfinite(p.cutoff) || p.cutoff <= 0)
    throw std::invalid_argument("contact damping cutoff must be finite and > 0");
  if (p.intra_tube_exclusion < 0)
    throw std::invalid_argument("contact damping intra-tube exclusion must be >= 0");
}

template class PairModel<ContactDampingKernel>;

}  // namespace mdem
