#include "mdem/force/damping/viscous_contact_damping.h"

#include <omp.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "mdem/neighbor/neighbor_list.h"

namespace mdem {

ViscousContactDamping::ViscousContactDamping(ContactDampingParams p) : p_(p) {
  if (!std::isfinite(p.ratio) || p.ratio < 0 || p.ratio > 10)
    throw std::invalid_argument("contact damping ratio must be finite and in [0, 10], got " +
                                std::to_string(p.ratio));
  if (!std::isfinite(p.stiffness) || p.stiffness <= 0)
    throw std::invalid_argument("contact damping stiffness must be finite and > 0");
  if (!std::isfinite(p.cutoff) || p.cutoff <= 0)
    throw std::invalid_argument("contact damping cutoff must be finite and > 0");
  if (p.intra_tube_exclusion < 0)
    throw std::invalid_argument("contact damping intra-tube exclusion must be >= 0");
}

bool ViscousContactDamping::excludes(const Elements& el, std::size_t i, std::size_t j) const {
  return el.cnt_pair_excluded(i, j, p_.intra_tube_exclusion);
}

double ViscousContactDamping::coefficient(const Elements& el, std::size_t i, std::size_t j) const {
  const double m_eff = el.mass[i] * el.mass[j] / (el.mass[i] + el.mass[j]);
  return 2.0 * p_.ratio * std::sqrt(m_eff * p_.stiffness);
}

void ViscousContactDamping::compute(const Elements& el, const NeighborList* pairs,
                                    ForceSink& sink) const {
  if (!pairs || p_.ratio == 0) return;
  const auto& off = pairs->offsets();
  const auto& nb = pairs->neighbors();
  const double rc2 = p_.cutoff * p_.cutoff;
  const long n = static_cast<long>(el.size());
#pragma omp parallel num_threads(sink.threads()) if (n >= kParallelMinItems)
  {
    const int tid = omp_get_thread_num();
    Vec3* fd = sink.damping_force(tid);
#pragma omp for schedule(static, 64)
    for (long i = 0; i < n; ++i) {
      for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
        const std::uint32_t j = nb[k];
        const Vec3 d = el.x[j] - el.x[i];
        const double r2 = d.squaredNorm();
        if (r2 >= rc2 || r2 == 0) continue;
        // Along the centre line only: a rigid motion of the pair (translation or rotation) has
        // no relative velocity along it, so it is not damped.
        const Vec3 n = d / std::sqrt(r2);
        const Vec3 f = -coefficient(el, i, j) * n.dot(el.v[j] - el.v[i]) * n;  // on j
        fd[j] += f;
        fd[i] -= f;
      }
    }
  }
}

void ViscousContactDamping::add_stiffness(const Elements& el, const NeighborList* pairs,
                                          StiffnessSums& s) const {
  if (!pairs) return;
  const auto& off = pairs->offsets();
  const auto& nb = pairs->neighbors();
  const double rc2 = p_.cutoff * p_.cutoff;
  for (std::size_t i = 0; i < el.size(); ++i) {
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
      const std::uint32_t j = nb[k];
      if ((el.x[j] - el.x[i]).squaredNorm() >= rc2) continue;
      const double c = coefficient(el, i, j);
      s.c[i] += c;
      s.c[j] += c;
    }
  }
}

}  // namespace mdem
