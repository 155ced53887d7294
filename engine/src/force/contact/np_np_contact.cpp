// Nanoparticle–nanoparticle contact (model.md §5): a central force from U(R) = f_c(R) V(R/r − 2).
#include "mdem/force/contact/np_np_contact.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace mdem {

namespace {

constexpr double kCoincident2 = 1e-24;  // R² below which the centres count as coincident (nm²)

void require_positive(double v, const char* field) {
  if (!std::isfinite(v) || !(v > 0))
    throw std::invalid_argument(std::string("NP-NP contact ") + field +
                                " must be finite and > 0 (nm), got " + std::to_string(v));
}

}  // namespace

NpNpKernel::NpNpKernel(NpNpParams p)
    : p_(p),
      fc_{p.taper_start, p.taper_width},
      v_("NP-NP contact", p.epsilon, p.A, p.B, p.alpha, p.beta, p.d_min) {
  require_positive(p.radius, "radius");
  require_positive(p.taper_start, "taper_start");
  require_positive(p.taper_width, "taper_width");
}

bool NpNpKernel::evaluate(const Vec3& d, PairForces& out) const {
  const double R2 = d.squaredNorm();
  const double cut = p_.cutoff();
  if (!(R2 < cut * cut)) return false;  // (a NaN fails this test and propagates below)
  if (R2 < kCoincident2) {
    out.energy = v_(-2.0);
    return true;
  }
  const double R = std::sqrt(R2);
  const double a = 1.0 / p_.radius;  // ∂D/∂R
  double v, dv, fc, dfc;
  v_(R * a - 2.0, v, dv);
  fc_(R, fc, dfc);
  out.energy = fc * v;
  const double dU = dfc * v + fc * dv * a;
  out.f2 = (-dU / R) * d;
  out.f1 = -out.f2;
  return true;
}

double NpNpKernel::energy(double R) const {
  PairForces r;
  evaluate(Vec3(R, 0, 0), r);
  return r.energy;
}

void NpNpKernel::stiffness(const Elements&, std::size_t i, std::size_t j, const Vec3& d,
                           StiffnessSums& s) const {
  const double R = d.norm();
  if (!(R < p_.cutoff())) return;
  const double a = 1.0 / p_.radius;
  s.add_pair(i, j, vdw_shape::radial_stiffness_bound(fc_, v_, R, R * a - 2.0, a), 0.0, 0.0);
}

double NpNpKernel::equilibrium_stiffness() const {
  return v_.second(v_.minimum()) / (p_.radius * p_.radius);
}

double NpNpKernel::equilibrium_distance() const { return p_.radius * (v_.minimum() + 2.0); }

template class PairModel<NpNpKernel>;

}  // namespace mdem
