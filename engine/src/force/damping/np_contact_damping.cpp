#include "mdem/force/damping/np_contact_damping.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "mdem/core/limits.h"

namespace mdem {

NpDashpotKernel::NpDashpotKernel(std::string_view name, std::string_view owner, KindPairs kinds,
                                 NpDampingParams p)
    : name_(name), owner_(owner), kinds_(kinds), p_(p) {
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

bool NpDashpotKernel::pair(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                           PairForces& out) const {
  const double r2 = d.squaredNorm();
  if (r2 >= p_.cutoff * p_.cutoff || r2 == 0) return false;
  const double c = dashpot_coefficient(p_.ratio, el.mass[i], el.mass[j], p_.stiffness);
  const Vec3 u = el.v[j] - el.v[i];
  if (p_.shear) {
    out.f2 = -c * u;
  } else {
    const Vec3 n = d / std::sqrt(r2);
    out.f2 = -c * n.dot(u) * n;
  }
  out.f1 = -out.f2;
  return true;
}

void NpDashpotKernel::stiffness(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                                StiffnessSums& s) const {
  if (d.squaredNorm() >= p_.cutoff * p_.cutoff) return;
  const double c = dashpot_coefficient(p_.ratio, el.mass[i], el.mass[j], p_.stiffness);
  s.c[i] += c;
  s.c[j] += c;
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
