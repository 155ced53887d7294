// The integrator's fast path (engine/src/integrate/step_kernels.h): elements with all six DOFs
// free and isotropic inertia take the same arithmetic compiled without the per-DOF branches.
// It must give the general path's results bit for bit on any scene, whatever mixes of elements,
// constraints changed by protocols between steps, loads, damping, multiple time stepping and
// threads; and, on its own, the exact solution of a body under a constant load.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include "hwy/targets.h"
#include "mdem/core/cnt.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/integrate/system.h"
#include "mdem/scene/tube_builder.h"
#include "step_scenes.h"

using namespace mdem;

namespace {

struct Case {
  bool dashpots = true;  // the model dampers write fd/td (else local damping starts from zero)
  int respa_k = 1;       // 2: the slow dashpots' held forces enter local damping (RespaSplit)
  int threads = 1;
  bool big = false;  // a film above the threading threshold (2048 elements) instead of three tubes
  // 16 free isotropic spheres apart from the rest, spinning 0.12-0.3 rad per step: their drift
  // leaves the series branch (above 0.1 rad), which the lanes hand back to the scalar kernels.
  bool spinners = false;
};

struct Marked {
  std::size_t fixed, prescribed, partial, loaded, toggled, anisotropic;
  std::vector<std::size_t> clamped;  // translation prescribed, rotation fixed: a tensile grip's
};

// Three bonded 12-segment tubes at the vdW contact distance (or a 2400-segment film), with ~300 K
// random velocities and spins, and one element of every class: fixed; translation and rotation
// prescribed; one translation prescribed and one rotation fixed; free under an external force and
// torque; free but held prescribed by a protocol for a while and released; an anisotropic free
// body (a grain, which no model acts on) spinning about a non-principal axis. And clamped
// elements (translation prescribed at a velocity the protocol changes every step, rotation
// fixed, as a tensile grip's; the lanes run them): in a chunk with free ones, and (film) runs of
// them, within and across chunks.
System mixed_scene(const Case& cs, bool fast, Marked& mk) {
  Elements el;
  if (cs.big) {
    mdem::testing::add_step_film(el);
  } else {
    add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 12, 0);
    add_straight_tube(el, Vec3(0.4, 1.7, 0.0), Vec3(1, 0.05, 0).normalized(), 12, 1);
    add_straight_tube(el, Vec3(0.2, 0.85, 1.5), Vec3(1, -0.04, 0.02).normalized(), 12, 2);
  }
  mdem::testing::thermal_kick(el, 11);
  // A small load on every element, so that the work books have terms in every pass and lane.
  for (std::size_t i = 0; i < el.size(); ++i) {
    el.f_ext[i] = Vec3(0.05, -0.1, 0.02) * static_cast<double>(1 + i % 3);
    el.t_ext[i] = Vec3(-0.01, 0.005, 0.015) * static_cast<double>(1 + i % 5);
  }
  mk = {0, 11, 17, 20, 30, 0, {}};
  if (cs.big) {
    for (std::size_t i = 100; i < 140; ++i) mk.clamped.push_back(i);
    for (std::size_t i : {205, 213, 1000, 1001, 2390}) mk.clamped.push_back(i);
  } else {
    mk.clamped = {25, 26};  // in the chunk of elements 24-31, with the toggled element
  }
  for (std::size_t i : mk.clamped)
    for (int k = 0; k < 3; ++k) {
      el.dof[i][k] = DofMode::Prescribed;
      el.dof[i][k + 3] = DofMode::Fixed;
    }
  el.fix_all(mk.fixed);
  for (int k = 0; k < 6; ++k) el.dof[mk.prescribed][k] = DofMode::Prescribed;
  el.v_prescribed[mk.prescribed] = Vec3(0.01, -0.02, 0.005);
  el.w_prescribed[mk.prescribed] = Vec3(0.0, 0.03, -0.01);
  el.dof[mk.partial][0] = DofMode::Prescribed;
  el.v_prescribed[mk.partial] = Vec3(-0.015, 0, 0);
  el.dof[mk.partial][4] = DofMode::Fixed;
  ElementInit grain;
  grain.kind = ElementKind::Grain;
  grain.x = Vec3(0, -30, 0);
  grain.mass = el.mass[0];
  grain.inertia = Vec3(1.0, 2.0, 3.5) * el.inertia[0].x();
  grain.radius = 0.7;
  grain.w = Vec3(0.02, 0.05, -0.03);
  mk.anisotropic = el.add(grain);
  const double dt = cs.big ? 0.002 : 0.005;
  for (int k = 0; cs.spinners && k < 16; ++k) {
    ElementInit ball = grain;
    ball.x = Vec3(3.0 * k, -40, 0);
    ball.inertia = Vec3::Constant(el.inertia[0].x());
    ball.w = Vec3(0.12 + 0.01 * k, -0.05, 0.02 * (k % 3)) / dt;
    ball.v = Vec3(0.01, 0.02 * k, -0.01);
    el.add(ball);
  }

  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  IntegratorSettings s;
  s.dt = dt;
  s.threads = cs.threads;
  s.local_damping = 0.3;
  s.respa_k = cs.respa_k;
  s.guard_every = 50;  // the guard's unfused passes inside each run() below
  s.free_isotropic_fast_path = fast;
  System sys(std::move(el), s);
  sys.add(std::move(bonds));
  sys.add(std::make_unique<AnisotropicVdw>());
  if (cs.dashpots) sys.add(std::make_unique<ViscousContactDamping>(ContactDampingParams{}));
  // A protocol: a load that varies with time, and an element held (prescribed) from 0.1 to 0.3 ps
  // then released, so an element changes class between steps of one run().
  const Marked m = mk;
  sys.add_updater([m](System& sy, double t) {
    Elements& e = sy.elements();
    e.f_ext[m.loaded] = Vec3(0.3 * std::sin(20 * t), -0.2, 0.1);
    e.t_ext[m.loaded] = Vec3(0.0, 0.05 * std::cos(15 * t), 0.02);
    const bool held = t >= 0.1 && t < 0.3;
    for (int k = 0; k < 3; ++k) e.dof[m.toggled][k] = held ? DofMode::Prescribed : DofMode::Free;
    e.v_prescribed[m.toggled] = Vec3(0.02, 0.0, -0.01);
    for (std::size_t i : m.clamped)
      e.v_prescribed[i] = Vec3(0.03 * std::sin(12 * t) * (i % 2 ? 1.0 : -1.0),
                               0.01 * std::cos(9 * t), -0.02 * std::sin(7 * t));
  });
  return sys;
}

std::uint64_t bits(double x) { return std::bit_cast<std::uint64_t>(x); }

// Every element's state, forces and damping forces, and the books, bit for bit.
void expect_identical(const System& a, const System& b) {
  const Elements &A = a.elements(), &B = b.elements();
  ASSERT_EQ(A.size(), B.size());
  long differing = 0;
  for (std::size_t i = 0; i < A.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const bool same = bits(A.x[i][k]) == bits(B.x[i][k]) && bits(A.v[i][k]) == bits(B.v[i][k]) &&
                        bits(A.w[i][k]) == bits(B.w[i][k]) && bits(A.f[i][k]) == bits(B.f[i][k]) &&
                        bits(A.t[i][k]) == bits(B.t[i][k]) &&
                        bits(A.q[i].coeffs()[k]) == bits(B.q[i].coeffs()[k]) &&
                        bits(a.damping_forces()[i][k]) == bits(b.damping_forces()[i][k]);
      differing += !same;
    }
  EXPECT_EQ(differing, 0);
  for (std::size_t i = 0; i < A.size(); ++i) EXPECT_EQ(bits(A.q[i].w()), bits(B.q[i].w())) << i;
  const EnergyLedger &L = a.energy(), &M = b.energy();
  EXPECT_EQ(bits(L.kinetic_translational), bits(M.kinetic_translational));
  EXPECT_EQ(bits(L.kinetic_rotational), bits(M.kinetic_rotational));
  EXPECT_EQ(bits(L.external_work), bits(M.external_work));
  EXPECT_EQ(bits(L.dissipated), bits(M.dissipated));
  EXPECT_EQ(bits(L.potential.total_stored()), bits(M.potential.total_stored()));
}

void compare_paths(const Case& cs, long steps) {
  Marked mk{};
  System fast = mixed_scene(cs, true, mk);
  System general = mixed_scene(cs, false, mk);
  ASSERT_TRUE(fast.settings().free_isotropic_fast_path);
  ASSERT_FALSE(general.settings().free_isotropic_fast_path);
  // Runs of several lengths: the fused pass, the unfused first and last passes of a run(), and
  // the guard's step.
  for (long done = 0, len = 1; done < steps; done += len, len = len % 9 + 1) {
    fast.run(len);
    general.run(len);
  }
  const Elements& E = fast.elements();
  // The scene holds every class: some elements free and isotropic (the fast path's), the others
  // not; the held element was released again.
  std::size_t free_isotropic = 0;
  for (std::size_t i = 0; i < E.size(); ++i) {
    bool all_free = true;
    for (DofMode d : E.dof[i]) all_free = all_free && d == DofMode::Free;
    free_isotropic += all_free && E.is_isotropic(i);
  }
  // fixed, prescribed, partial, anisotropic, clamped
  EXPECT_EQ(free_isotropic, E.size() - 4 - mk.clamped.size());
  for (std::size_t i : mk.clamped) {
    EXPECT_EQ(E.w[i].norm(), 0.0) << i;
    EXPECT_NE(E.v[i].x(), 0.0) << i;
  }
  for (std::size_t i = E.size() - (cs.spinners ? 16 : 0); i < E.size(); ++i)
    EXPECT_GT(E.w[i].norm() * fast.dt(), 0.1) << i;
  EXPECT_FALSE(E.is_isotropic(mk.anisotropic));
  EXPECT_GT(fast.time(), 0.3);
  // The run moved everything that is free (the comparison is not between two still states).
  EXPECT_GT(fast.energy().dissipated, 0.0);
  EXPECT_NE(fast.energy().external_work, 0.0);
  expect_identical(fast, general);
}

}  // namespace

TEST(StepFastPath, EqualsTheGeneralPathBitForBitOnAMixedScene) { compare_paths({}, 90); }

TEST(StepFastPath, EqualsTheGeneralPathWithoutModelDampers) {
  Case cs;
  cs.dashpots = false;
  compare_paths(cs, 90);
}

TEST(StepFastPath, EqualsTheGeneralPathUnderMultipleTimeStepping) {
  Case cs;
  cs.respa_k = 2;
  compare_paths(cs, 90);
}

TEST(StepFastPath, EqualsTheGeneralPathOnTwoThreads) {
  // 2401 elements: the passes run threaded (at least 2048 items).
  Case cs;
  cs.big = true;
  cs.threads = 2;
  compare_paths(cs, 160);
}

TEST(StepFastPath, EqualsTheGeneralPathWithFastSpinningElements) {
  Case cs;
  cs.spinners = true;
  compare_paths(cs, 90);
  cs.big = true;
  cs.threads = 2;
  compare_paths(cs, 160);
}

// The fast path runs chunks of free isotropic elements in SIMD lanes (integrate/step_simd.h),
// compiled for every instruction set and dispatched at run time: each one, forced in turn, must
// give the general path's results bit for bit.
TEST(StepFastPath, LanesOfEveryInstructionSetEqualTheGeneralPath) {
  const std::vector<std::int64_t> targets = hwy::SupportedAndGeneratedTargets();
  EXPECT_GE(targets.size(), 2u);  // at least a vector set and the plain C++ fallback
  for (std::int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    EXPECT_STREQ(step_simd_target(), hwy::TargetName(target));
    SCOPED_TRACE(hwy::TargetName(target));
    compare_paths({}, 90);
    Case cs;
    cs.dashpots = false;
    cs.spinners = true;
    compare_paths(cs, 60);
    cs.big = true;
    cs.threads = 2;
    cs.dashpots = true;
    compare_paths(cs, 160);
  }
  hwy::SetSupportedTargetsForTest(0);
}

// The body the constant-load tests load: free, isotropic, moving and spinning.
ElementInit moving_body() {
  ElementInit e;
  e.mass = 2.0;
  e.inertia = Vec3::Constant(0.5);
  e.radius = 1.0;
  e.v = Vec3(0.1, -0.2, 0.05);
  e.w = Vec3(0.01, 0.02, -0.03);
  return e;
}

TEST(StepFastPath, ConstantLoadIsIntegratedExactly) {
  // A free isotropic body (the fast path's class) under a constant force F and torque T: velocity
  // Verlet is exact for a constant force, so v = v0 + F t/m, x = x0 + v0 t + F t²/(2m),
  // ω = ω0 + T t/I; the work booked (trapezoidal F·Δx) equals the kinetic energy gained.
  const ElementInit e = moving_body();
  Elements el;
  el.add(e);
  const Vec3 F(0.3, 0.1, -0.2), T(0.002, -0.001, 0.003);
  el.f_ext[0] = F;
  el.t_ext[0] = T;
  IntegratorSettings s;
  s.dt = 0.01;
  System sys(std::move(el), s);
  sys.run(400);
  const double t = sys.time();
  const Elements& E = sys.elements();
  const Vec3 v = e.v + F * t / e.mass, x = e.v * t + F * t * t / (2 * e.mass);
  const Vec3 w = e.w + T * t / e.inertia.x();
  EXPECT_LT((E.v[0] - v).norm(), 1e-13);
  EXPECT_LT((E.x[0] - x).norm(), 1e-12);
  EXPECT_LT((E.w[0] - w).norm(), 1e-13);
  const double gained = 0.5 * e.mass * (v.squaredNorm() - e.v.squaredNorm()) +
                        0.5 * e.inertia.x() * (w.squaredNorm() - e.w.squaredNorm());
  EXPECT_NEAR(sys.energy().external_work, gained, 1e-12 * std::abs(gained));
  EXPECT_LT(sys.energy_balance_error(), 1e-12);
}

// 64 free isotropic bodies (8 chunks of AVX-512 lanes) under a constant force F and torque T
// from `from` on (0: from the start, the loads set before the run; dt/2: from the first step's
// second half kick, the loads set by an updater in the run), run 400 steps: v = v0 + F (t −
// from)/m, ω = ω0 + T (t − from)/I, and the work booked is the kinetic energy gained, but for a
// first kick at dt/2, whose book takes the velocity before the kick: h F·v for ½m(|v + hF/m|² −
// |v|²), short of h²|F|²/(2m) + h²|T|²/(2I) per body. An observer that applies no loads
// (Updater::applies_loads false) may be installed too.
class NoLoads final : public Updater {
 public:
  void apply(System&, double) override { ++calls; }
  bool applies_loads() const override { return false; }
  int calls = 0;
};

void expect_constant_loads_integrated(bool by_updater, bool with_observer) {
  ElementInit e = moving_body();
  const Vec3 F(0.3, 0.1, -0.2), T(0.002, -0.001, 0.003);
  Elements el;
  for (int k = 0; k < 64; ++k) {
    e.x = Vec3(3.0 * k, 0, 0);
    el.add(e);
    el.f_ext.back() = by_updater ? Vec3::Zero() : F;
    el.t_ext.back() = by_updater ? Vec3::Zero() : T;
  }
  IntegratorSettings s;
  s.dt = 0.01;
  s.threads = 1;
  System sys(std::move(el), s);
  const auto observer = std::make_shared<NoLoads>();
  if (with_observer) sys.add_updater(observer);
  if (by_updater) {
    sys.add_updater([&](System& sy, double) {
      Elements& E = sy.elements();
      for (std::size_t i = 0; i < E.size(); ++i) {
        E.f_ext[i] = F;
        E.t_ext[i] = T;
      }
    });
    sys.initialize();  // applies the updater once, for the forces at t = 0: none at the start
    for (std::size_t i = 0; i < sys.elements().size(); ++i) {
      sys.elements().f_ext[i] = Vec3::Zero();
      sys.elements().t_ext[i] = Vec3::Zero();
    }
  }
  sys.run(400);
  if (with_observer) {
    EXPECT_GE(observer->calls, 400);
  }
  const double h = 0.5 * s.dt.value();
  const double t = sys.time() - (by_updater ? h : 0.0);
  const Elements& E = sys.elements();
  const Vec3 v = e.v + F * t / e.mass, w = e.w + T * t / e.inertia.x();
  double gained = 0;
  for (std::size_t i = 0; i < E.size(); ++i) {
    ASSERT_LT((E.v[i] - v).norm(), 1e-13) << "element " << i;
    ASSERT_LT((E.w[i] - w).norm(), 1e-13) << "element " << i;
    gained += 0.5 * e.mass * (E.v[i].squaredNorm() - e.v.squaredNorm()) +
              0.5 * e.inertia.x() * (E.w[i].squaredNorm() - e.w.squaredNorm());
  }
  const double first =
      by_updater ? h * h * (F.squaredNorm() / (2 * e.mass) + T.squaredNorm() / (2 * e.inertia.x()))
                 : 0.0;
  EXPECT_NEAR(sys.energy().external_work + 64 * first, gained, 1e-11 * std::abs(gained));
}

TEST(StepFastPath, LoadsSetBeforeTheRunAreIntegratedInLanes) {
  expect_constant_loads_integrated(false, false);
  expect_constant_loads_integrated(false, true);
}

TEST(StepFastPath, LoadsAnUpdaterSetsDuringTheRunAreIntegratedInLanes) {
  expect_constant_loads_integrated(true, false);
  expect_constant_loads_integrated(true, true);
}
