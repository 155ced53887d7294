#include "mdem/scene/bundle_scene.h"

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/scene/film_builder.h"
#include "mdem/scene/tube_builder.h"

namespace mdem {

void randomize_motion(Elements& el, double speed_rms, double spin_rms, unsigned seed) {
  std::mt19937_64 rng(seed);
  // Box–Muller on the library-independent unit_interval mapping.
  auto normal = [&] {
    const double u1 = 1.0 - unit_interval(rng());  // (0, 1]
    const double u2 = unit_interval(rng());
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  };
  for (std::size_t i = 0; i < el.size(); ++i) {
    for (int k = 0; k < 3; ++k) el.v[i][k] = speed_rms * normal();
    for (int k = 0; k < 3; ++k) el.w[i][k] = spin_rms * normal();
  }
}

System make_bundle_system(const BundleSpec& spec, IntegratorSettings settings) {
  if (spec.tubes != 1 && spec.tubes != 7)
    throw std::invalid_argument("bundle tubes must be 1 or 7, got " + std::to_string(spec.tubes));
  if (spec.segments < 2)
    throw std::invalid_argument("bundle segments must be >= 2, got " +
                                std::to_string(spec.segments));
  if (!std::isfinite(spec.spacing) || spec.spacing <= 0)
    throw std::invalid_argument("bundle spacing must be finite and > 0 nm");
  for (double v : {spec.speed, spec.spin, spec.bundle_spin})
    if (!std::isfinite(v) || v < 0)
      throw std::invalid_argument("bundle speed, spin and bundle spin must be finite and >= 0");
  Elements el;
  if (spec.tubes == 7)
    add_seven_tube_bundle(el, spec.segments, spec.spacing);
  else
    add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), spec.segments, 0);
  // Bonds at rest in the built tubes (randomize_motion below sets velocities only).
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  randomize_motion(el, spec.speed, spec.spin, spec.seed);
  // Rigid rotation Ω about the rope axis (x through the origin): v += Ω × x, ω += Ω.
  const Vec3 omega(spec.bundle_spin, 0, 0);
  for (std::size_t i = 0; i < el.size(); ++i) {
    el.v[i] += omega.cross(el.x[i]);
    el.w[i] += omega;
  }
  System sys(std::move(el), settings);
  sys.add(std::move(bonds));
  sys.add(std::make_unique<AnisotropicVdw>());
  return sys;
}

}  // namespace mdem
