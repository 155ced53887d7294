#pragma once
// Hand-made CNT scenes for the stability tests (test_stability, test_vdw_stiffness_bound).
#include <memory>
#include <utility>

#include "mdem/core/cnt.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/integrate/system.h"
#include "mdem/scene/tube_builder.h"

namespace mdem::testing {

// The twist job's models (bonds from the topology, anisotropic vdW, its dashpots) on `el`.
inline System cnt_scene_system(Elements el, const IntegratorSettings& s) {
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  System sys(std::move(el), s);
  sys.add(std::move(bonds));
  sys.add(std::make_unique<AnisotropicVdw>());
  sys.add(std::make_unique<ViscousContactDamping>(ContactDampingParams{}));
  return sys;
}

// Two 11-segment tubes crossing through each other at 90° (along x and y): their middle
// segments share a centre (docs/stability.md, crossed overlapping tubes).
inline void add_crossing_tubes(Elements& el) {
  add_straight_tube(el, Vec3(-5 * cnt::kSegmentLength, 0, 0), Vec3::UnitX(), 11, 0);
  add_straight_tube(el, Vec3(0, -5 * cnt::kSegmentLength, 0), Vec3::UnitY(), 11, 1);
}

}  // namespace mdem::testing
