// System::timers(): the wall time of run()'s parts (step_timers.h). Not a speed test: the parts
// must add up to no more than the run's own wall time and cover most of it, and each part that
// runs must have been charged.
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <thread>

#include "mdem/core/cnt.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/integrate/system.h"
#include "mdem/scene/film_builder.h"

using namespace mdem;

namespace {

System bundle(int threads) {
  Elements el;
  add_seven_tube_bundle(el, 20, 1.8);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  IntegratorSettings s;
  s.threads = threads;
  s.local_damping = 0.1;
  System sys(std::move(el), s);
  sys.add(std::move(bonds));
  sys.add(std::make_unique<AnisotropicVdw>());
  return sys;
}

double seconds_of(const std::function<void()>& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

TEST(StepTimers, PartsAddUpToAtMostTheRunsWallTimeAndEachRunningPartIsCharged) {
  for (int threads : {1, 2}) {
    System sys = bundle(threads);
    // An updater that takes a known 2 ms once: it must land in updaters_s, not elsewhere.
    int calls = 0;
    sys.add_updater([&calls](System&, double) {
      if (calls++ == 10) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    });
    sys.initialize();
    EXPECT_EQ(sys.timers().total(), 0.0) << "initialize() is not a run";
    const double wall = seconds_of([&] { sys.run(300); });
    const StepTimers& t = sys.timers();
    EXPECT_GT(t.pair_s, 0.0);
    EXPECT_GT(t.neighbor_s, 0.0);
    EXPECT_GT(t.integrate_s, 0.0);
    EXPECT_GE(t.updaters_s, 0.002);
    EXPECT_LE(t.total(), wall);
    // The clock reads cover the whole step (only loop control is outside them).
    EXPECT_GT(t.total(), 0.5 * wall);
    // They accumulate over runs.
    const StepTimers before = t;
    const double wall2 = seconds_of([&] { sys.run(50); });
    EXPECT_GT(sys.timers().pair_s, before.pair_s);
    EXPECT_GT(sys.timers().integrate_s, before.integrate_s);
    EXPECT_LE(sys.timers().total() - before.total(), wall2);
  }
}

// A system without pair models still times its (empty) neighbour update, at no more than the
// clock's own cost, and charges its bonds to the force evaluation.
TEST(StepTimers, BondsOnlySystemChargesForceEvaluation) {
  Elements el;
  add_seven_tube_bundle(el, 10, 1.8);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  el.v[0] = Vec3(0.5, 0, 0);
  System sys(std::move(el));
  sys.add(std::move(bonds));
  const double wall = seconds_of([&] { sys.run(200); });  // initializes first
  EXPECT_EQ(sys.neighbors(), nullptr);
  EXPECT_GT(sys.timers().pair_s, 0.0);
  EXPECT_LE(sys.timers().total(), wall);
}

}  // namespace
