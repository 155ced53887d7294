#include "mdem/force/damping/np_contact_damping.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "mdem/core/limits.h"

namespace mdem {

NpDashpotKernel::NpDashpotKernel(std::string_view name, std::string_view owner, KindPairs kinds,
                                 NpDampingParams p, DashpotEvaluation e)
    : name_(name), owner_(owner), kinds_(kinds), p_(p), eval_(e) {
  const std::string who(name);
  if (!std::isfinite(p.ratio) || p.ratio < 0 || p.ratio > limits::kMaxDashpotRatio)
    throw std::invalid_argument(who + " ratio must be finite and in [0, " +
                                std::to_string(static_cast<int>(limits::kMaxDashpotRatio)) +
                                "] (critical damping), got " + std::to_string(p.ratio));
  if (!std::isfinite(p.stiffness) || p.stiffness <= 0)
    throw std::invalid_argument(who + " stiffness must be finite and > 0 (eV/nm²), got " +
                                std::to_string(p.stiffness));
  if (!std::isfinite(p.cutoff) || p.cutoff <= 0)
    throw std::invalid_argument(who + " cutoff must be finite and > 0 (nm), got " +
                                std::to_string(p.cutoff));
}

NpDashpotKernel np_cnt_dashpot(double ratio, const NpCntParams& contact, double stiffness,
                               bool shear) {
  const NpCntKernel k(contact);
  return NpDashpotKernel("np_cnt_damping", k.name(),
                         KindPairs::of(ElementKind::Nanoparticle, ElementKind::CntSegment),
                         {ratio, stiffness, contact.cutoff(), shear});
}

NpDashpotKernel np_np_dashpot(double ratio, const NpNpParams& contact, double stiffness,
                              bool shear) {
  const NpNpKernel k(contact);
  return NpDashpotKernel("np_np_damping", k.name(),
                         KindPairs::of(ElementKind::Nanoparticle, ElementKind::Nanoparticle),
                         {ratio, stiffness, contact.cutoff(), shear});
}

template class PairModel<NpDashpotKernel>;

}  // namespace mdem
