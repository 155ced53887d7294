// The step takes each element's per-thread force sums in its integrator pass
// (ForceSink::take, engine/src/integrate/step_kernels.h) instead of a separate reduction pass.
// Every thread's contribution must arrive (the undamped film's energy shows a lost or doubled
// one), the sums must be those of ForceSink::reduce bit for bit, and a run must repeat bit for bit
// at a fixed thread count and agree with one thread to round-off.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>

#include "mdem/core/cnt.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/integrate/system.h"
#include "step_scenes.h"

using namespace mdem;

namespace {

// A 2400-segment film (above the threading threshold of 2048 items) with bonds and vdW, ~300 K
// random velocities and spins; dashpots optional; no local damping.
System film(int threads, bool dashpots) {
  Elements el;
  mdem::testing::add_step_film(el);
  mdem::testing::thermal_kick(el, 3);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  IntegratorSettings s;
  s.dt = 0.002;
  s.threads = threads;
  s.local_damping = 0;
  System sys(std::move(el), s);
  sys.add(std::move(bonds));
  sys.add(std::make_unique<AnisotropicVdw>());
  if (dashpots) sys.add(std::make_unique<ViscousContactDamping>(ContactDampingParams{}));
  return sys;
}

std::uint64_t bits(double x) { return std::bit_cast<std::uint64_t>(x); }

Vec3 momentum(const Elements& E) {
  Vec3 p = Vec3::Zero();
  for (std::size_t i = 0; i < E.size(); ++i) p += E.mass[i] * E.v[i];
  return p;
}

}  // namespace

TEST(StepForceSums, UndampedFilmConservesEnergyAndMomentum) {
  // Bonds and vdW are conservative internal forces: the undamped film keeps its total energy (to
  // velocity Verlet's O(dt²) error) and its momentum. A thread's sums lost or taken twice in the
  // pass leave each thread's own contributions balanced (Σ f = 0 and the momentum still hold:
  // every bond and pair adds +f and −f to one thread's buffer) but make the forces
  // non-conservative, which the energy shows.
  System sys = film(2, false);
  sys.initialize();
  const Vec3 p0 = momentum(sys.elements());
  double p_scale = 0;
  for (std::size_t i = 0; i < sys.elements().size(); ++i)
    p_scale += sys.elements().mass[i] * sys.elements().v[i].norm();
  for (int k = 0; k < 5; ++k) sys.run(9);  // fused passes, and each run()'s unfused last step
  const Elements& E = sys.elements();
  Vec3 sum = Vec3::Zero();
  double scale = 0;
  for (std::size_t i = 0; i < E.size(); ++i) {
    sum += E.f[i];
    scale += E.f[i].norm();
  }
  ASSERT_GT(scale, 0.0);
  EXPECT_LT(sum.norm(), 1e-12 * scale);
  EXPECT_LT((momentum(E) - p0).norm(), 1e-12 * p_scale);
  // 1.2e-4 here; with thread 1's sums dropped from the pass (a mutation tried once), 0.097.
  EXPECT_LT(sys.energy_balance_error(), 1e-3);
}

TEST(StepForceSums, TakenForcesAreTheReducedOnesBitForBit) {
  // After a run the elements hold the forces the integrator's pass took at the last step's
  // positions; refresh() evaluates the same positions again and sums them by ForceSink::reduce.
  for (int threads : {1, 2}) {
    System sys = film(threads, true);
    sys.initialize();
    sys.run(6);
    const Elements& E = sys.elements();
    const std::vector<Vec3> f = E.f, t = E.t;
    sys.refresh();
    long differing = 0;
    for (std::size_t i = 0; i < E.size(); ++i)
      for (int k = 0; k < 3; ++k)
        differing += bits(f[i][k]) != bits(E.f[i][k]) || bits(t[i][k]) != bits(E.t[i][k]);
    EXPECT_EQ(differing, 0) << threads << " threads";
  }
}

TEST(StepForceSums, RunsRepeatBitForBitAndTwoThreadsMatchOne) {
  // With dashpots: the damping sums are taken in the pass too.
  auto run = [](int threads) {
    System sys = film(threads, true);
    sys.initialize();
    for (int k = 0; k < 4; ++k) sys.run(10);
    return sys;
  };
  const System a = run(2), b = run(2), one = run(1);
  const Elements &A = a.elements(), &B = b.elements(), &O = one.elements();
  long differing = 0;
  double dx = 0, dv = 0, vmax = 0;
  for (std::size_t i = 0; i < A.size(); ++i) {
    for (int k = 0; k < 3; ++k)
      differing += bits(A.x[i][k]) != bits(B.x[i][k]) || bits(A.v[i][k]) != bits(B.v[i][k]) ||
                   bits(A.f[i][k]) != bits(B.f[i][k]) ||
                   bits(a.damping_forces()[i][k]) != bits(b.damping_forces()[i][k]);
    dx = std::max(dx, (A.x[i] - O.x[i]).norm());
    dv = std::max(dv, (A.v[i] - O.v[i]).norm());
    vmax = std::max(vmax, O.v[i].norm());
  }
  EXPECT_EQ(differing, 0);
  EXPECT_EQ(bits(a.energy().dissipated), bits(b.energy().dissipated));
  EXPECT_GT(a.energy().dissipated, 0.0);
  // One thread sums in another order: round-off only.
  EXPECT_LT(dx, 1e-11);
  EXPECT_LT(dv, 1e-9 * vmax);
}

TEST(StepForceSums, DashpotsWithoutTorquesLeaveTheDampingTorquesZero) {
  // No dashpot writes torques, so the sink holds damping force buffers only and the pass takes
  // zero damping torques (the scalar take and the lanes alike): with no local damping the
  // damping torques must stay exactly zero while the dashpots dissipate, on 1 and 2 threads.
  for (int threads : {1, 2}) {
    System sys = film(threads, true);
    sys.initialize();
    sys.run(20);
    long nonzero = 0;
    for (const Vec3& td : sys.damping_torques()) nonzero += td != Vec3::Zero();
    EXPECT_EQ(nonzero, 0) << threads << " threads";
    EXPECT_GT(sys.energy().dissipated, 0.0);
  }
}

namespace {

// Every bit of the forces, torques and damping forces and torques the system holds, in one
// running hash (FNV-1a over the doubles' bits).
std::uint64_t force_hash(const System& sys) {
  std::uint64_t h = 1469598103934665603ull;
  auto add = [&](const std::vector<Vec3>& a) {
    for (const Vec3& v : a)
      for (int k = 0; k < 3; ++k) h = (h ^ bits(v[k])) * 1099511628211ull;
  };
  add(sys.elements().f);
  add(sys.elements().t);
  add(sys.damping_forces());
  add(sys.damping_torques());
  return h;
}

// Records force_hash at every call; says whether it reads forces as it is told.
class ForceRecorder final : public Updater {
 public:
  explicit ForceRecorder(bool reads) : reads_(reads) {}
  void apply(System& sys, double) override { seen.push_back(force_hash(sys)); }
  bool reads_forces() const override { return reads_; }
  std::vector<std::uint64_t> seen;

 private:
  bool reads_;
};

}  // namespace

TEST(StepForceSums, AnUpdaterThatReadsForcesSeesEachStepsOwn) {
  // A run's fused passes keep the forces they kick with in registers when no updater reads them
  // (Updater::reads_forces): an updater that does must see, before each evaluation, the forces
  // of the one before, as it does when every step is a run's last (run(1), whose last step
  // always stores them). With local damping on (it writes fd, td in the pass), with and without
  // dashpots; 2 threads. The trajectory must not depend on it either.
  for (bool dashpots : {false, true}) {
    auto film_run = [&](bool reads, bool one_at_a_time) {
      System sys = film(2, dashpots);
      sys.set_local_damping(0.2);
      auto rec = std::make_shared<ForceRecorder>(reads);
      sys.add_updater(rec);
      sys.initialize();
      rec->seen.clear();
      if (one_at_a_time)
        for (int k = 0; k < 24; ++k) sys.run(1);
      else
        sys.run(24);
      return std::pair{std::move(rec->seen), sys.elements()};
    };
    const auto [stepwise, e1] = film_run(true, true);
    const auto [reader, e2] = film_run(true, false);
    const auto [blind, e3] = film_run(false, false);
    ASSERT_EQ(stepwise.size(), 24u);
    EXPECT_EQ(reader, stepwise) << "dashpots " << dashpots;
    // The updater that says it does not read them sees old forces at some steps (else the
    // fused passes stored them anyway and nothing was spared).
    long stale = 0;
    for (std::size_t k = 0; k < blind.size(); ++k) stale += blind[k] != stepwise[k];
    EXPECT_GT(stale, 0) << "dashpots " << dashpots;
    long differing = 0;
    for (std::size_t i = 0; i < e1.size(); ++i)
      for (int k = 0; k < 3; ++k)
        differing += bits(e1.x[i][k]) != bits(e2.x[i][k]) || bits(e1.x[i][k]) != bits(e3.x[i][k]) ||
                     bits(e1.v[i][k]) != bits(e3.v[i][k]) || bits(e1.f[i][k]) != bits(e3.f[i][k]);
    EXPECT_EQ(differing, 0) << "dashpots " << dashpots;
  }
}
