// The tensile and cyclic grip protocol and the grip stress (tensile.md §3.5–3.6): kinematics
// against the closed forms, grip selection on hand-built elements, the quasi-static balance and
// modulus of a bonded tube against kn·A by hand, the elastic loop, checkpoints and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "mdem/core/cnt.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/integrate/system.h"
#include "mdem/io/state_io.h"
#include "mdem/observe/cycle_analysis.h"
#include "mdem/observe/grip_bridges.h"
#include "mdem/observe/grip_stress.h"
#include "mdem/observe/stress_strain.h"
#include "mdem/protocol/tensile_protocol.h"
#include "mdem/scene/nanoparticle.h"
#include "mdem/scene/tube_builder.h"

namespace mdem {
namespace {

constexpr int kSegments = 60;
constexpr double kDt = 0.02;      // ps, well below the bonded tube's critical step
constexpr double kWidth = 10.0;   // W (nm) of the notional film the tube stands for
constexpr double kHeight = 11.0;  // H (nm)
const double kL0 = kSegments * cnt::kSegmentLength;  // nominal length: the tube's

// A straight bonded (10,10) tube of 60 segments along x from the origin; `heavy` segments
// (a run inside the free part, left of the middle) get 4× the mass and inertia, so the film
// between the grips is not mirror-symmetric and F_L + F_R does not vanish by symmetry alone.
Elements tube(bool heavy = false) {
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), kSegments, 0);
  if (heavy)
    for (int k = 14; k < 24; ++k) {
      el.mass[k] *= 4;
      el.inv_mass[k] /= 4;
      el.inertia[k] *= 4;
    }
  return el;
}

System tube_system(Elements el, double local_damping = 0) {
  IntegratorSettings s;
  s.dt = kDt;
  s.threads = 1;
  s.local_damping = local_damping;
  System sys(std::move(el), s);
  sys.add(ParallelBond::from_topology(sys.elements(), BondType::Cnt, cnt_bond_stiffness()));
  return sys;
}

TensileLoading monotonic(double rate = 1e-4, double ramp = 600, double target = 0.02) {
  TensileLoading l;
  l.length = kL0;
  l.monotonic = {rate, ramp, target};
  return l;
}

TensileLoading cyclic(double period, int cycles, double amplitude = 0.01) {
  TensileLoading l;
  l.mode = TensileMode::Cyclic;
  l.length = kL0;
  l.cyclic.amplitude = amplitude;
  l.cyclic.period = period;
  l.cyclic.cycles = cycles;
  return l;
}

long steps_for(double ps) { return std::lround(ps / kDt); }

// --- closed forms ---------------------------------------------------------------------------

TEST(TensileKinematics, StrainTableOfTensileMd) {
  const TensileProtocol p(monotonic(1e-4, 600));
  // tensile.md §3.5's table: 1 % at 374 ps and 2 % at 497 ps, at 0.68 and 0.92 of the target rate.
  EXPECT_NEAR(p.strain_after(374), 0.01, 5e-5);
  EXPECT_NEAR(p.strain_after(497), 0.02, 5e-5);
  EXPECT_NEAR(p.time_to_strain(0.01), 374, 0.5);
  EXPECT_NEAR(p.time_to_strain(0.02), 497, 0.5);
  EXPECT_NEAR(p.strain_rate_after(374) / 1e-4, 0.68, 0.005);
  EXPECT_NEAR(p.strain_rate_after(497) / 1e-4, 0.92, 0.005);
  // The ramp alone reaches ½ ε̇ t_a = 3 %; then the strain grows at ε̇.
  EXPECT_NEAR(p.strain_after(600), 0.03, 1e-15);
  EXPECT_NEAR(p.strain_after(700), 0.04, 1e-15);
  EXPECT_NEAR(p.time_to_strain(0.04), 700, 1e-9);
  EXPECT_NEAR(p.strain_after(p.time_to_strain(0.0123)), 0.0123, 1e-14);
  // The strain rate is the derivative of the strain (central differences).
  for (double s : {10.0, 200.0, 599.0, 601.0, 900.0}) {
    const double h = 1e-3;
    EXPECT_NEAR((p.strain_after(s + h) - p.strain_after(s - h)) / (2 * h), p.strain_rate_after(s),
                1e-10);
  }
  EXPECT_EQ(p.phase(100), "ramp");
  EXPECT_EQ(p.phase(700), "straining");
}

TEST(TensileKinematics, CyclicWaveform) {
  TensileLoading l = cyclic(0, 6);
  l.cyclic.period = 0;
  l.cyclic.mean_rate = 1.32e-4;  // /ps = 1.32e-7 /fs
  const TensileProtocol p(l);
  EXPECT_NEAR(p.period(), 151.5, 0.05);  // tensile.md §3.6's table
  EXPECT_DOUBLE_EQ(p.duration(), 6 * p.period());
  EXPECT_NEAR(p.strain_after(0.5 * p.period()), -0.01, 1e-15);
  EXPECT_NEAR(p.strain_after(p.period()), 0, 1e-15);
  // Mean |dε/dt| over a half cycle is ε̇_avg: the strain falls by ε_a over P/2.
  EXPECT_NEAR(0.01 / (0.5 * p.period()), 1.32e-4, 1e-15);
  EXPECT_EQ(p.phase(10), "cycle 1/6");
  EXPECT_EQ(p.phase(2.5 * p.period()), "cycle 3/6");
  EXPECT_EQ(p.phase(6.1 * p.period()), "done");
}

// --- kinematics of a run ----------------------------------------------------------------------

// Runs the tube under `p` to time t_end and checks every grip element's displacement against
// ±½L0·ε(t) to 1e-9 relative, its y and z unmoved.
void expect_grips_on_closed_form(const TensileLoading& l, double t_end) {
  Elements el = tube();
  const GripSelection g = select_grips(el);
  const Elements start = el;
  System sys = tube_system(std::move(el));
  auto p = std::make_shared<TensileProtocol>(l);
  sys.add_updater(p);
  sys.run(steps_for(t_end));
  const double u = p->grip_displacement(sys.time());
  ASSERT_GT(std::abs(u), 1e-3);
  const Elements& now = sys.elements();
  for (const auto& [ids, sign] : {std::pair{g.left, -1.0}, std::pair{g.right, 1.0}})
    for (std::size_t i : ids) {
      const Vec3 d = now.x[i] - start.x[i];
      EXPECT_NEAR(d.x(), sign * u, 1e-9 * std::abs(u)) << "element " << i;
      EXPECT_EQ(d.y(), 0.0);
      EXPECT_EQ(d.z(), 0.0);
      EXPECT_EQ(now.w[i].norm(), 0.0);
    }
}

TEST(TensileKinematics, RampGripsFollowTheClosedForm) {
  expect_grips_on_closed_form(monotonic(1e-4, 600), 300);  // inside the ramp
  expect_grips_on_closed_form(monotonic(1e-4, 100), 160);  // past a shorter ramp
}

TEST(TensileKinematics, CyclicGripsFollowTheClosedForm) {
  expect_grips_on_closed_form(cyclic(100, 2), 137);  // in the second cycle
}

TEST(TensileKinematics, StartOnASystemThatHasRun) {
  // A loading started after 40 ps of an unloaded run (a relaxation) counts its strain from there.
  Elements el = tube();
  const GripSelection g = select_grips(el);
  System sys = tube_system(std::move(el));
  sys.run(steps_for(40));
  const double x0 = sys.elements().x[g.right.front()].x();
  auto p = std::make_shared<TensileProtocol>(monotonic(1e-4, 100));
  p->start(sys);
  EXPECT_DOUBLE_EQ(p->start_time(), sys.time());
  sys.add_updater(p);
  sys.run(steps_for(60));
  const double u = sys.elements().x[g.right.front()].x() - x0;
  EXPECT_NEAR(u, 0.5 * kL0 * p->strain_after(p->elapsed(sys.time())), 1e-9 * std::abs(u));
  EXPECT_NEAR(p->elapsed(sys.time()), 60, 1e-9);
  EXPECT_EQ(p->phase(sys.time()), "ramp");
}

// The protocol keeps its grips' element indices from step to step: they must follow the
// elements when the system reorders them mid-run (the grip elements, found by tag, stay on the
// closed form and the others stay free), and a protocol moved to a system whose elements are in
// another order must clamp that system's grip elements, not the old indices.
TEST(TensileKinematics, GripsFollowReorderedElementsAndAnotherSystem) {
  const TensileLoading l = monotonic(1e-4, 100);
  Elements el = tube();
  select_grips(el);
  const Elements start = el;
  auto expect_on_closed_form = [&](const System& sys, const TensileProtocol& p, double t_run) {
    const Elements& now = sys.elements();
    const double u = p.grip_displacement(sys.time());
    ASSERT_GT(std::abs(u), 1e-4);
    std::size_t clamped = 0;
    for (const auto& [group, sign] : {std::pair{kGripLeft, -1.0}, std::pair{kGripRight, 1.0}})
      for (std::uint64_t tag : now.groups.get(group)) {
        const std::size_t i = now.index_of(tag), i0 = start.index_of(tag);
        const Vec3 d = now.x[i] - start.x[i0];
        EXPECT_NEAR(d.x(), sign * u, 1e-9 * std::abs(u)) << "tag " << tag << " at " << t_run;
        EXPECT_EQ(d.y(), 0.0);
        EXPECT_EQ(now.w[i].norm(), 0.0);
      }
    for (std::size_t i = 0; i < now.size(); ++i)
      clamped += now.dof[i][0] == DofMode::Prescribed && now.dof[i][3] == DofMode::Fixed;
    EXPECT_EQ(clamped, now.groups.get(kGripLeft).size() + now.groups.get(kGripRight).size());
  };
  // Reversed order: every grip index moves.
  std::vector<std::uint32_t> reversed(el.size());
  for (std::size_t k = 0; k < el.size(); ++k)
    reversed[k] = static_cast<std::uint32_t>(el.size() - 1 - k);

  System sys = tube_system(el);
  auto p = std::make_shared<TensileProtocol>(l);
  sys.add_updater(p);
  sys.run(steps_for(60));
  sys.reorder_elements(reversed);
  sys.run(steps_for(60));
  expect_on_closed_form(sys, *p, 120);

  // A protocol that has clamped the reordered system, moved to a fresh one in the built order.
  System sys2 = tube_system(el);
  auto p2 = std::make_shared<TensileProtocol>(l);
  p2->apply(sys, sys.time());  // p2 holds sys's (reversed) indices first
  sys2.add_updater(p2);
  p2->start(sys2);
  sys2.run(steps_for(60));
  expect_on_closed_form(sys2, *p2, 60);
}

TEST(TensileKinematics, VelocityIsC1AcrossTheRampEnd) {
  const double rate = 1e-4, ta = 100;
  Elements el = tube();
  const GripSelection g = select_grips(el);
  System sys = tube_system(std::move(el));
  auto p = std::make_shared<TensileProtocol>(monotonic(rate, ta));
  sys.add_updater(p);
  const std::size_t r = g.right.front();
  sys.run(steps_for(ta) - 50);
  std::vector<double> v;  // the grip's velocity over each step, as the integrator moved it
  for (int k = 0; k < 100; ++k) {
    sys.step();
    v.push_back(sys.elements().v[r].x());
  }
  // The acceleration changes by at most |jerk|·dt between steps; the jerk of the smoothstep ramp
  // is at most 6·(½ε̇L0)/t_a². A linear ramp would jump by ½ε̇L0/t_a at t_a.
  const double vmax = 0.5 * rate * kL0, jerk = 6 * vmax / (ta * ta);
  double worst = 0;
  for (std::size_t k = 2; k < v.size(); ++k) {
    const double a1 = (v[k] - v[k - 1]) / kDt, a0 = (v[k - 1] - v[k - 2]) / kDt;
    worst = std::max(worst, std::abs(a1 - a0));
  }
  EXPECT_LE(worst, 1.01 * jerk * kDt);
  EXPECT_LT(worst, 2e-3 * vmax / ta);         // a linear ramp: vmax/ta
  EXPECT_NEAR(v.back(), vmax, 1e-12 * vmax);  // at the target rate after the ramp
}

// --- grip selection ---------------------------------------------------------------------------

// 200 segments at x = 0, 1, …, 199 (no bonds) and three NPs at x = 10, 100, 190: P0.5 = 0.995 and
// P99.5 = 198.005, so the 15 nm grips hold segments 0–15 and 184–199 plus one NP each.
Elements grip_test_elements(int extra_nps = 0) {
  Elements el;
  for (int k = 0; k < 200; ++k) el.add(cnt_segment(Vec3(k, 0, 0), Quat::Identity(), k, 0));
  for (double x : {10.0, 100.0, 190.0}) el.add(nanoparticle(Vec3(x, 5, 0)));
  for (int k = 0; k < extra_nps; ++k) el.add(nanoparticle(Vec3(100, 10 + k, 0)));
  return el;
}

TEST(TensileGrips, SelectionByTheRuleOfSection35) {
  Elements el = grip_test_elements();
  const GripSelection g = select_grips(el);
  EXPECT_NEAR(g.x_lo, 0.995, 1e-12);
  EXPECT_NEAR(g.x_hi, 198.005, 1e-12);
  ASSERT_EQ(g.left.size(), 17u);
  ASSERT_EQ(g.right.size(), 17u);
  for (int k = 0; k < 16; ++k) {
    EXPECT_EQ(g.left[k], static_cast<std::size_t>(k));
    EXPECT_EQ(g.right[k], static_cast<std::size_t>(184 + k));
  }
  EXPECT_EQ(g.left.back(), 200u);   // the NP at x = 10
  EXPECT_EQ(g.right.back(), 202u);  // the NP at x = 190
  EXPECT_TRUE(el.groups.has(kGripLeft));
  EXPECT_TRUE(el.groups.has(kGripRight));
  EXPECT_EQ(el.group_indices(kGripLeft), g.left);
  EXPECT_EQ(el.group_indices(kGripRight), g.right);
  // Declared once: a second selection on the same elements is refused.
  EXPECT_THROW(select_grips(el), std::invalid_argument);
}

TEST(TensileGrips, TooFewElementsInAGripIsAnError) {
  // 203 + 3400 elements: each grip's 17 are 0.47 % of 3603 (< 0.5 %); with 3100 extra NPs they
  // are 0.51 % of 3303 and pass.
  Elements ok = grip_test_elements(3100);
  EXPECT_NO_THROW(select_grips(ok));
  Elements el = grip_test_elements(3400);
  try {
    select_grips(el);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("left grip holds 17 of 3603"), std::string::npos) << m;
    EXPECT_NE(m.find("min_fraction"), std::string::npos) << m;
  }
  EXPECT_FALSE(el.groups.has(kGripLeft));  // nothing declared
}

// --- quasi-static balance and modulus ---------------------------------------------------------

// Bonds that stretch between the grips: from the last left-grip segment to the first right one.
double free_bonds(const GripSelection& g) {
  return static_cast<double>(g.right.front() - g.left.back());
}

TEST(TensileGripStress, QuasiStaticBalanceAndTheTubeModulus) {
  Elements el = tube(/*heavy=*/true);
  const GripSelection g = select_grips(el);
  // The piece both grips hold and the modulus it alone would give (grip_bridges.h), taken before
  // the test: here the whole film, so the test must measure it.
  const GripBridges bridge =
      grip_bridges(el, g.left, g.right, cnt::kBondKn * cnt::kBondArea * cnt::kSegmentLength,
                   {kL0, kWidth, kHeight});
  System sys = tube_system(std::move(el), /*local_damping=*/0.1);
  auto p = std::make_shared<TensileProtocol>(monotonic(1e-4, 600));
  auto s = std::make_shared<GripStressSampler>([p](double t) { return p->strain(t); },
                                               GripStressSettings{kWidth, kHeight, 1.0});
  sys.add_updater(p);
  sys.add_updater(s);
  sys.run(steps_for(p->time_to_strain(0.035)));

  // Quasi-static: the slope of σ(ε) over 1–2 % is the free chain's axial stiffness per film
  // cross-section, kn·A·L0/(n_free·W·H), n_free bonds in series stretched by ε·L0 in all.
  const double n = free_bonds(g);
  const double E_hand = units::to_GPa(cnt::kBondKn * cnt::kBondArea * kL0 / (n * kWidth * kHeight));
  const LineFit fit = modulus_fit(s->strains(), s->stresses());
  EXPECT_NEAR(fit.slope / E_hand, 1.0, 0.02) << "E = " << fit.slope << " GPa, by hand " << E_hand;
  EXPECT_EQ(bridge.pieces, 1u);
  EXPECT_NEAR(fit.slope / bridge.affine_modulus, 1.0, 0.02)
      << "E = " << fit.slope << " GPa, affine bridging modulus " << bridge.affine_modulus;
  EXPECT_NEAR(fit.intercept, 0, 0.01 * E_hand * 0.01);
  // F_L + F_R → 0 against |F_L|: after the first 100 ps (the grips' start sets the chain ringing)
  // the imbalance stays below 1e-3 |F_L|.
  double worst = 0;
  for (const GripSample& f : s->samples()) {
    if (f.t < 100) continue;
    worst = std::max(worst, std::abs(f.f_left + f.f_right) / std::abs(f.f_left));
  }
  EXPECT_LT(worst, 1e-3);
  EXPECT_GT(s->samples().back().f_left, 0);  // the left grip is pulled towards +x: tension
  // One sample per ps of system time, from the first evaluation (t = 0), each with ε(t).
  for (std::size_t k = 0; k < s->samples().size(); ++k) {
    EXPECT_NEAR(s->samples()[k].t, static_cast<double>(k), 1e-6);
    EXPECT_EQ(s->samples()[k].strain, p->strain(s->samples()[k].t));
  }
  std::printf("tube modulus %.4f GPa (hand %.4f), max |F_L+F_R|/|F_L| after 100 ps %.3g\n",
              fit.slope, E_hand, worst);
}

// --- cyclic loops -----------------------------------------------------------------------------

std::vector<CycleResult> cycle_loop(double local_damping, double period) {
  Elements el = tube();
  select_grips(el);
  System sys = tube_system(std::move(el), local_damping);
  auto p = std::make_shared<TensileProtocol>(cyclic(period, 2));
  auto s = std::make_shared<GripStressSampler>([p](double t) { return p->strain(t); },
                                               GripStressSettings{kWidth, kHeight, 1.0});
  sys.add_updater(p);
  sys.add_updater(s);
  sys.run(steps_for(p->duration()) + 2);
  CycleSettings cs;
  cs.period = period;
  return analyse_cycles(s->times(), s->strains(), s->stresses(), cs);
}

// σ_peak·ε_a of a cycle: the scale of the loop area.
double loop_scale(const CycleResult& c) {
  return std::max(c.peak_tension, -c.peak_compression) * 0.01;
}

TEST(TensileGripStress, ElasticLoopEnclosesNoAreaAndDampingOpensIt) {
  // Undamped: the purely elastic tube returns all the work of a cycle (P = 200 ps against an
  // axial wave transit of about 2.5 ps): |∮σ dε| < 1e-6 σ_peak·ε_a.
  const auto elastic = cycle_loop(0.0, 200);
  ASSERT_EQ(elastic.size(), 2u);
  double worst = 0;
  for (const CycleResult& c : elastic) {
    std::printf("undamped cycle %d: loop area %.3g GPa, sigma_peak*eps_a %.3g GPa\n", c.cycle,
                c.loop_area, loop_scale(c));
    EXPECT_LT(std::abs(c.loop_area), 1e-6 * loop_scale(c));
    worst = std::max(worst, std::abs(c.loop_area));
  }
  // PFC local damping 0.3 on the free segments dissipates: the area is positive and stands well
  // clear of the undamped loop's (100x). It stays small, since the quasi-static chain carries
  // little unbalanced force for the damping to act on.
  const auto damped = cycle_loop(0.3, 200);
  ASSERT_EQ(damped.size(), 2u);
  for (const CycleResult& c : damped) {
    std::printf("damped cycle %d: loop area %.3g GPa, sigma_peak*eps_a %.3g GPa\n", c.cycle,
                c.loop_area, loop_scale(c));
    EXPECT_GT(c.loop_area, 0);
    EXPECT_GT(c.loop_area, 100 * worst);
  }
}

// --- checkpoints ------------------------------------------------------------------------------

struct Rig {
  System sys;
  std::shared_ptr<TensileProtocol> p;
  std::shared_ptr<GripStressSampler> s;
};

Rig rig() {
  Elements el = tube(true);
  select_grips(el);
  Rig r{tube_system(std::move(el), 0.05), nullptr, nullptr};
  r.p = std::make_shared<TensileProtocol>(monotonic(1e-4, 600));
  auto p = r.p;
  r.s = std::make_shared<GripStressSampler>([p](double t) { return p->strain(t); },
                                            GripStressSettings{kWidth, kHeight, 1.0});
  r.sys.add_updater(r.p);
  r.sys.add_updater(r.s);
  return r;
}

TEST(TensileGripStress, ASamplerOfFreeGripsSeesTheForcesOfItsStep) {
  // The sampler says it reads forces only when its next call samples (Updater::reads_forces):
  // at the other steps the integrator's fused passes need not store them. Here the grips are
  // free (no protocol) and the tube rings, so a forces array left a step behind shows: samples
  // every 0.1 ps over 3 ps must be those of runs of one step each (whose last step always
  // stores the forces), bit for bit.
  auto make = [] {
    Elements el = tube();
    select_grips(el);
    for (std::size_t i = 0; i < el.size(); ++i) {
      const double k = static_cast<double>(i);
      el.v[i] = Vec3(0.02 * std::sin(0.7 * k), 0.03 * std::cos(0.3 * k), 0.01 * std::sin(1.1 * k));
    }
    Rig r{tube_system(std::move(el)), nullptr, nullptr};
    r.s = std::make_shared<GripStressSampler>([](double) { return 0.0; },
                                              GripStressSettings{kWidth, kHeight, 0.1});
    r.sys.add_updater(r.s);
    return r;
  };
  const long n = steps_for(3.0);
  Rig whole = make();
  whole.sys.run(n);
  Rig stepwise = make();
  for (long k = 0; k < n; ++k) stepwise.sys.run(1);
  const auto& a = whole.s->samples();
  const auto& b = stepwise.s->samples();
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GE(a.size(), 25u);
  long differing = 0;
  double largest = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    differing += a[k].t != b[k].t || a[k].f_left != b[k].f_left || a[k].f_right != b[k].f_right;
    largest = std::max(largest, std::abs(b[k].f_left));
  }
  EXPECT_EQ(differing, 0);
  EXPECT_GT(largest, 0.0);  // the grips feel the ringing tube
}

TEST(TensileCheckpoint, MidRampRunContinuesBitIdentically) {
  Rig a = rig();
  a.sys.run(steps_for(150));
  StateWriter w;
  a.sys.save_state(w);
  a.p->save_state(w);
  a.s->save_state(w);
  a.sys.run(steps_for(50));

  Rig b = rig();
  StateReader r(w.bytes());
  b.sys.load_state(r);
  b.p->load_state(r);
  b.s->load_state(r);
  r.expect_end();
  b.sys.run(steps_for(50));

  EXPECT_EQ(a.sys.time(), b.sys.time());
  for (std::size_t i = 0; i < a.sys.elements().size(); ++i) {
    EXPECT_EQ(a.sys.elements().x[i], b.sys.elements().x[i]) << i;
    EXPECT_EQ(a.sys.elements().v[i], b.sys.elements().v[i]) << i;
  }
  ASSERT_EQ(a.s->samples().size(), b.s->samples().size());
  for (std::size_t k = 0; k < a.s->samples().size(); ++k) {
    EXPECT_EQ(a.s->samples()[k].t, b.s->samples()[k].t);
    EXPECT_EQ(a.s->samples()[k].stress, b.s->samples()[k].stress);
  }
  // Another loading refuses the checkpoint.
  Rig c = rig();
  c.p = std::make_shared<TensileProtocol>(monotonic(2e-4, 600));
  StateReader r2(w.bytes());
  c.sys.load_state(r2);
  EXPECT_THROW(c.p->load_state(r2), CheckpointError);
}

// --- bad input --------------------------------------------------------------------------------

void expect_error(const TensileLoading& l, const std::string& field) {
  try {
    TensileProtocol p(l);
    FAIL() << "expected an error naming " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("must be"), std::string::npos) << e.what();
  }
}

TEST(TensileBadInput, ErrorsNameTheFieldAndRange) {
  const double nan = std::nan(""), inf = INFINITY;
  for (double bad : {nan, inf, -1e-4, 0.0}) {
    expect_error(monotonic(bad), "strain_rate");
    expect_error(monotonic(1e-4, bad), "ramp_time");
    expect_error(monotonic(1e-4, 600, bad), "target_strain");
    TensileLoading l = monotonic();
    l.length = bad;
    expect_error(l, "length");
    expect_error(cyclic(100, 2, bad), "amplitude");
  }
  for (double bad : {nan, inf, -100.0}) expect_error(cyclic(bad, 2), "period");
  TensileLoading both = cyclic(100, 2);
  both.cyclic.mean_rate = 1e-4;
  expect_error(both, "exactly one of mean_rate");
  expect_error(cyclic(0, 2), "exactly one of mean_rate");
  for (int bad : {0, -3}) expect_error(cyclic(100, bad), "cycles");
  // A grip width larger than the film.
  Elements el = tube();
  GripSettings gs;
  gs.width = 50;  // the tube spans 80 nm
  try {
    select_grips(el, gs);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("grip width must be < half"), std::string::npos)
        << e.what();
  }
  for (double bad : {nan, -1.0, 0.0}) {
    gs.width = bad;
    EXPECT_THROW(select_grips(el, gs), std::invalid_argument);
  }
  EXPECT_THROW(GripStressSampler([](double) { return 0.0; }, GripStressSettings{0, 11, 1}),
               std::invalid_argument);
  EXPECT_THROW(GripStressSampler([](double) { return 0.0; }, GripStressSettings{10, nan, 1}),
               std::invalid_argument);
  EXPECT_THROW(GripStressSampler([](double) { return 0.0; }, GripStressSettings{10, 11, -1}),
               std::invalid_argument);
}

}  // namespace
}  // namespace mdem
