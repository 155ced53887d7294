// Nanoparticle contacts (model.md §5): the NP–CNT and NP–NP laws against every check value of
// model.md §5, their gradients against finite differences, their momentum balances and
// continuity; an NP beside a 201-segment tube rests at 3.462 nm, two NPs at a 0.4287 nm gap;
// energy conservation with NPs; the NP dashpots; the per-kind-pair table with the real 8 nm
// NP–NP model; and `mdem probe --model np-cnt|np-np`.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "mdem/cli.h"
#include "mdem/core/cnt.h"
#include "mdem/core/np.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/contact/np_cnt_contact.h"
#include "mdem/force/contact/np_np_contact.h"
#include "mdem/force/damping/np_contact_damping.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/integrate/system.h"
#include "mdem/job/tensile_job.h"
#include "mdem/scene/nanoparticle.h"
#include "mdem/scene/tube_builder.h"
#include "support.h"

using namespace mdem;

namespace {

constexpr double kT = cnt::kSegmentLength;

void expect_rel(double actual, double expected, double rel, const std::string& what) {
  EXPECT_NEAR(actual, expected, rel * std::abs(expected)) << what;
}

Vec3 random_unit(std::mt19937_64& g) {
  std::normal_distribution<double> n;
  return Vec3(n(g), n(g), n(g)).normalized();
}

// An NP and a segment as elements, in the given order (NP first or second).
Elements np_and_segment(const Vec3& x_np, const Vec3& x_seg, const Vec3& axis, bool np_first) {
  Elements el;
  if (np_first) el.add(nanoparticle(x_np));
  el.add(cnt_segment(x_seg, quat_from_axis(axis), 0, 0));
  if (!np_first) el.add(nanoparticle(x_np));
  return el;
}

template <class K>
PairForces eval(const K& k, const Elements& el) {
  PairForces r;
  if (!k.pair(el, 0, 1, el.x[1] - el.x[0], r)) r = PairForces{};
  return r;
}

// A straight tube of n segments along x centred at the origin, bonded by hand (cnt_segment +
// make_bond), so the test does not depend on a scene builder's signature.
std::unique_ptr<ParallelBond> add_tube(Elements& el, int n, const Vec3& centre, int tube_id) {
  auto bonds = std::make_unique<ParallelBond>();
  const std::size_t first = el.size();
  for (int k = 0; k < n; ++k)
    el.add(
        cnt_segment(centre + Vec3((k - (n - 1) / 2.0) * kT, 0, 0), Quat::Identity(), tube_id, k));
  for (int k = 0; k + 1 < n; ++k)
    bonds->add(make_bond(el, static_cast<std::uint32_t>(first + k),
                         static_cast<std::uint32_t>(first + k + 1), cnt_bond_stiffness()));
  return bonds;
}

// Golden-section search for the minimum of f on [a, b].
double golden_min(const std::function<double(double)>& f, double a, double b, double tol) {
  const double r = (std::sqrt(5.0) - 1) / 2;
  double c = b - r * (b - a), d = a + r * (b - a);
  double fc = f(c), fd = f(d);
  while (b - a > tol) {
    if (fc < fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - r * (b - a);
      fc = f(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + r * (b - a);
      fd = f(d);
    }
  }
  return 0.5 * (a + b);
}

double term(const System& sys, EnergyTerm t) {
  return sys.energy().potential.stored[static_cast<int>(t)];
}

}  // namespace

// ---- model.md §5 check values ------------------------------------------------------------

TEST(NpCntContact, CheckValuesOfModelMd) {
  struct Row {
    Vec3 axis, x;
    double U;
    Vec3 F, tau;
  };
  const Row rows[] = {
      {Vec3::UnitX(), {0, 3.462, 0}, -3.778492e-01, {0, 5.172833e-01, 0}, Vec3::Zero()},
      {Vec3::UnitX(), {0, 4.8, 0}, -4.012346e-02, {0, -1.457517e-01, 0}, Vec3::Zero()},
      {Vec3::UnitX(), {3, 3, 0}, -2.619222e-02, {9.915835e-01, 3.569611, 0}, {0, 0, -7.734082}},
      {Vec3::UnitX(), {5, 0, 0}, 3.360163, {33.62395, 0, 0}, Vec3::Zero()},
      {Vec3::UnitX(), {0, 2.5, 0}, 2.905771e+02, {0, 8.270128e+02, 0}, Vec3::Zero()},
      {Vec3(1, 2, 2) / 3,
       {1, -2, 2.5},
       -7.072486e-02,
       {0.9658235, -2.873642, 2.532308},
       {-2.119489, 0.1177494, 0.9419950}},
  };
  const NpCntKernel k;
  for (const Row& r : rows) {
    const std::string at = "NP at (" + std::to_string(r.x.x()) + ", " + std::to_string(r.x.y()) +
                           ", " + std::to_string(r.x.z()) + ")";
    const PairForces p = k.evaluate(r.x, Vec3::Zero(), r.axis);
    expect_rel(p.energy, r.U, 1e-6, at + " U");
    const double scale = std::max(r.F.norm(), r.tau.norm());
    for (int a = 0; a < 3; ++a) {
      EXPECT_NEAR(p.f1[a], r.F[a], 1e-6 * scale) << at << " F_NP " << a;
      EXPECT_NEAR(p.t2[a], r.tau[a], 1e-6 * scale) << at << " tau_seg " << a;
    }
    EXPECT_EQ(p.t1, Vec3::Zero()) << at;
    // The same through the driver's pair() with the elements in either order.
    for (const bool np_first : {true, false}) {
      const Elements el = np_and_segment(r.x, Vec3::Zero(), r.axis, np_first);
      const PairForces q = eval(k, el);
      const Vec3 f_np = np_first ? q.f1 : q.f2, t_seg = np_first ? q.t2 : q.t1,
                 t_np = np_first ? q.t1 : q.t2;
      EXPECT_NEAR(q.energy, r.U, 1e-6 * std::abs(r.U)) << at;
      EXPECT_LT((f_np - r.F).norm(), 1e-6 * scale) << at << " np_first " << np_first;
      EXPECT_LT((t_seg - r.tau).norm(), 1e-6 * scale) << at << " np_first " << np_first;
      EXPECT_EQ(t_np, Vec3::Zero());
    }
  }
}

TEST(NpCntContact, DashpotStiffnessIsTheSideOnCurvatureAtTheMinimum) {
  // D0 = (αA/(βB))^{1/(α−β)} = 1.5906581 (tensile.md §2.3), R0 = ρ_NC (D0 + 2); the curvature of
  // U along the side-on line there, by central differences of the law itself.
  const NpCntKernel k;
  const double R0 = 0.98623 * (1.5906581 + 2), h = 1e-4;
  auto U = [&](double R) { return k.evaluate(Vec3(0, R, 0), Vec3::Zero(), Vec3::UnitX()).energy; };
  const double fd = (U(R0 + h) - 2 * U(R0) + U(R0 - h)) / (h * h);
  EXPECT_NEAR(k.equilibrium_stiffness(), fd, 1e-5 * fd);
  EXPECT_NEAR(k.equilibrium_stiffness(), 4.4545, 1e-4);
  EXPECT_LT(std::abs(k.evaluate(Vec3(0, R0, 0), Vec3::Zero(), Vec3::UnitX()).f1.y()), 1e-6);
  // The dashpots take the contacts' cutoffs, and this curvature when asked to.
  EXPECT_EQ(np_cnt_dashpot().params().cutoff, 4 * kT);
  EXPECT_EQ(np_np_dashpot().params().cutoff, 8.0);
  EXPECT_EQ(np_cnt_dashpot(0.03, {}, k.equilibrium_stiffness()).params().stiffness,
            k.equilibrium_stiffness());
  EXPECT_EQ(np_cnt_dashpot().owner(), "np_cnt_contact");
  EXPECT_EQ(np_np_dashpot().owner(), "np_np_contact");
}

TEST(NpContactDamping, DefaultCoefficientsAreTensileMdSection34s) {
  // tensile.md §3.4: ψ = 0.03, k = 100 eV/nm² on every contact, m the pair's reduced mass, so
  // c = 2.22 eV·ps/nm² (CNT–CNT), 3.11 (NP–CNT), 14.2 (NP–NP).
  const double m_seg = cnt_segment(Vec3::Zero(), Quat::Identity(), 0, 0).mass;
  const NpDampingParams cnt = np_cnt_dashpot().params(), npnp = np_np_dashpot().params();
  EXPECT_EQ(cnt.stiffness, 100.0);
  EXPECT_EQ(npnp.stiffness, 100.0);
  EXPECT_NEAR(dashpot_coefficient(0.03, m_seg, m_seg, 100.0), 2.22, 0.005);
  EXPECT_NEAR(dashpot_coefficient(cnt.ratio, np::kMass, m_seg, cnt.stiffness), 3.11, 0.005);
  EXPECT_NEAR(dashpot_coefficient(npnp.ratio, np::kMass, np::kMass, npnp.stiffness), 14.2, 0.05);
}

// The NP dashpots' shear option against Eq. 33-34 by hand (as DashpotShear's CNT-CNT test): an NP
// and a segment 4 nm apart along x, and two NPs 5 nm apart, moving apart along the centre line at
// 0.3 nm/ps and sliding across it at (0.4, -0.1) nm/ps. c = 2ψ√(m_eff k), m_eff the reduced
// mass; normal-only: F_2 = −c·0.3 x̂; with shear F_2 = −c·(0.3, 0.4, −0.1); F_1 = −F_2.
TEST(NpContactDamping, ShearOptionDampsSlidingByHand) {
  const Vec3 u(0.3, 0.4, -0.1);
  for (const bool np_np : {false, true}) {
    Elements el;
    el.add(nanoparticle(Vec3::Zero()));
    if (np_np)
      el.add(nanoparticle(Vec3(5, 0, 0)));
    else
      el.add(cnt_segment(Vec3(4, 0, 0), Quat::Identity(), 0, 0));
    el.v[0] = Vec3(0.1, -0.2, 0.05);
    el.v[1] = el.v[0] + u;
    const double m_eff = el.mass[0] * el.mass[1] / (el.mass[0] + el.mass[1]);
    const double c = 2 * 0.03 * std::sqrt(m_eff * 100.0);
    for (const bool shear : {false, true}) {
      const NpDashpotKernel k =
          np_np ? np_np_dashpot(0.03, {}, 100.0, shear) : np_cnt_dashpot(0.03, {}, 100.0, shear);
      EXPECT_EQ(k.params().shear, shear);
      PairForces out;
      ASSERT_TRUE(k.pair(el, 0, 1, el.x[1] - el.x[0], out));
      const Vec3 expected = shear ? Vec3(-c * u) : Vec3(-c * 0.3, 0, 0);
      EXPECT_LT((out.f2 - expected).norm(), 1e-14 * c) << "np-np " << np_np << " shear " << shear;
      EXPECT_EQ(out.f1, -out.f2);
      EXPECT_LT(out.f2.dot(u), 0.0);
    }
  }
}

// The tensile job's laws.dashpot_shear reaches every contact dashpot of its system.
TEST(NpContactDamping, TheFilmsShearLawReachesTheNpDashpots) {
  for (const bool shear : {false, true}) {
    Elements el;
    el.add(nanoparticle(Vec3::Zero()));
    el.add(cnt_segment(Vec3(4, 0, 0), Quat::Identity(), 0, 0));
    FilmLaws laws;
    laws.dashpot_shear = shear;
    const auto sys = tensile_film_system(std::move(el), IntegratorSettings{}, 0.03, nullptr, laws);
    int np_dashpots = 0;
    for (const auto& m : sys->models())
      if (const auto* d = dynamic_cast<const NpContactDamping*>(m.get())) {
        EXPECT_EQ(d->params().shear, shear) << d->name();
        ++np_dashpots;
      }
    EXPECT_EQ(np_dashpots, 2);
    ASSERT_NE(sys->find<ViscousContactDamping>(), nullptr);
    EXPECT_EQ(sys->find<ViscousContactDamping>()->kernel().params().shear, shear);
  }
}

TEST(NpNpContact, CheckValuesOfModelMd) {
  struct Row {
    double R, U, F;  // F_x on NP 2
  };
  const Row rows[] = {{5.1, 592.5782, 3267.991},
                      {6.0, -0.3537376, -1.365298},
                      {7.0, -2.154910e-02, -4.474684e-02},  // tensile.md §2.5
                      {7.5, -4.244751e-03, -1.985447e-02}};
  const NpNpKernel k;
  for (const Row& r : rows) {
    PairForces p;
    ASSERT_TRUE(k.evaluate(Vec3(r.R, 0, 0), p));
    expect_rel(p.energy, r.U, 1e-6, "U at R = " + std::to_string(r.R));
    expect_rel(p.f2.x(), r.F, 1e-6, "F at R = " + std::to_string(r.R));
    EXPECT_EQ(p.f1.x(), -p.f2.x());
    EXPECT_EQ(p.f2.y(), 0.0);
  }
  // The minimum: U = −4.228354 eV, F = 0 (to the 8 digits of the check position: |F| < U''·1e-7).
  PairForces p;
  ASSERT_TRUE(k.evaluate(Vec3(5.4287267, 0, 0), p));
  expect_rel(p.energy, -4.228354, 1e-6, "U at the minimum");
  EXPECT_LT(std::abs(p.f2.x()), 556.0 * 1e-7);
  // The dashpot's stiffness: the curvature at the minimum, 555.92 eV/nm² (tensile.md §2.5).
  EXPECT_NEAR(k.equilibrium_stiffness(), 555.92, 0.01);
  EXPECT_NEAR(k.equilibrium_distance(), 5.4287267, 1e-7);
}

TEST(NpNpContact, EquilibriumGapAndWellDepthByMinimising) {
  const NpNpKernel k;
  const double R = golden_min([&](double r) { return k.energy(r); }, 5.2, 6.0, 1e-9);
  EXPECT_NEAR(R, 5.4287267, 2e-7);
  EXPECT_NEAR(R - 2 * np::kRadius, 0.4287267, 2e-7);  // the gap
  expect_rel(k.energy(R), -4.2283537, 1e-6, "well depth");
  std::printf("NP-NP minimum at R = %.7f nm (gap %.7f nm), U = %.7f eV\n", R, R - 5.0, k.energy(R));
}

// ---- gradients, balances, continuity ------------------------------------------------------

TEST(NpCntContact, ForcesAndSegmentTorqueAreTheExactGradient) {
  const NpCntKernel k;
  std::mt19937_64 g(21);
  struct Band {
    const char* name;
    double lo, hi;
  };
  // The linear branch (D < 0.8: R < 2.76 δ nm), the well, and the f_c ramp (3T..4T).
  const Band bands[] = {{"linear", 1.2, 2.7}, {"well", 3.0, 4.0}, {"ramp", 3 * kT, 4 * kT}};
  const double h = 1e-6;
  for (const Band& b : bands) {
    std::uniform_real_distribution<double> R(b.lo, b.hi);
    int linear = 0, ramp = 0;
    for (int s = 0; s < 40; ++s) {
      const Vec3 axis = random_unit(g), xs(0.4, -1.1, 0.7);
      const Vec3 xn = xs + R(g) * random_unit(g);
      const bool np_first = s % 2 == 0;
      const Elements el = np_and_segment(xn, xs, axis, np_first);
      const std::size_t inp = np_first ? 0 : 1, iseg = 1 - inp;
      const PairForces r = eval(k, el);
      ASSERT_NE(r.energy, 0.0) << b.name;
      const double dist = (xn - xs).norm();
      double delta = 1.0;
      {
        const double c = std::abs(axis.dot((xn - xs) / dist));
        delta = vdw_delta(VdwParams{}, std::acos(std::min(c, 1.0)));
      }
      if (dist / (0.98623 * delta) - 2 < 0.8) ++linear;
      if (dist > 3 * kT) ++ramp;
      const Vec3 f[2] = {r.f1, r.f2}, t[2] = {r.t1, r.t2};
      const double scale = std::max({r.f1.norm(), r.t1.norm(), r.t2.norm(), 1e-4});
      for (int a = 0; a < 3; ++a) {
        for (std::size_t i = 0; i < 2; ++i) {
          Elements p = el, m = el;
          p.x[i][a] += h;
          m.x[i][a] -= h;
          const double fd = -(eval(k, p).energy - eval(k, m).energy) / (2 * h);
          EXPECT_NEAR(f[i][a], fd, 1e-6 * scale) << b.name << " force on " << i << " axis " << a;
        }
        Vec3 e = Vec3::Zero();
        e[a] = h;
        Elements p = el, m = el;
        p.q[iseg] = (quat_exp(e) * el.q[iseg]).normalized();
        m.q[iseg] = (quat_exp(-e) * el.q[iseg]).normalized();
        const double td = -(eval(k, p).energy - eval(k, m).energy) / (2 * h);
        EXPECT_NEAR(t[iseg][a], td, 1e-6 * scale) << b.name << " segment torque axis " << a;
        // The NP's orientation does not enter U, and it gets no torque.
        p = el;
        p.q[inp] = (quat_exp(100 * e) * el.q[inp]).normalized();
        EXPECT_EQ(eval(k, p).energy, r.energy);
      }
      EXPECT_EQ(t[inp], Vec3::Zero()) << b.name;
      // Newton's third law and the pair's angular momentum (about the origin).
      EXPECT_LT((r.f1 + r.f2).norm(), 1e-13 * scale) << b.name;
      const Vec3 L = el.x[0].cross(r.f1) + el.x[1].cross(r.f2) + r.t1 + r.t2;
      EXPECT_LT(L.norm(), 1e-12 * scale * (el.x[0].norm() + el.x[1].norm() + 1)) << b.name;
    }
    if (std::string(b.name) == "linear") {
      EXPECT_GT(linear, 20);
    }
    if (std::string(b.name) == "ramp") {
      EXPECT_EQ(ramp, 40);
    }
  }
}

TEST(NpCntContact, ContinuousAtTheCutoffAndAtTheLinearBranch) {
  const NpCntKernel k;
  std::mt19937_64 g(5);
  for (int s = 0; s < 20; ++s) {
    const Vec3 axis = random_unit(g), n = random_unit(g);
    const double cut = 4 * kT;
    const PairForces in = k.evaluate(cut * (1 - 1e-7) * n, Vec3::Zero(), axis);
    const PairForces at = k.evaluate(cut * (1 + 1e-12) * n, Vec3::Zero(), axis);
    const PairForces mid = k.evaluate(0.8 * cut * n, Vec3::Zero(), axis);
    EXPECT_LT(std::abs(in.energy), 1e-10 * std::abs(mid.energy) + 1e-14);
    EXPECT_LT(in.f1.norm(), 1e-5 * std::max(mid.f1.norm(), 1e-3));
    EXPECT_EQ(at.energy, 0.0);
    EXPECT_EQ(at.f1, Vec3::Zero());
  }
  // Across D = 0.8 on the side-on line (R = 2.761 nm, F ≈ 827 eV/nm): U and F continuous (C¹),
  // U changing by the slope times the step, F by less than the curvature (≈ 1e5 eV/nm²) times it.
  const double R08 = 0.98623 * 2.8, step = 2e-9;
  const PairForces lo = k.evaluate(Vec3(0, R08 - step / 2, 0), Vec3::Zero(), Vec3::UnitX());
  const PairForces hi = k.evaluate(Vec3(0, R08 + step / 2, 0), Vec3::Zero(), Vec3::UnitX());
  EXPECT_GT(lo.f1.y(), 800.0);
  EXPECT_NEAR(lo.energy - hi.energy, lo.f1.y() * step, 1e-3 * lo.f1.y() * step);
  EXPECT_NEAR(lo.f1.y(), hi.f1.y(), 1e6 * step);
  // Coincident centres: finite energy, no force.
  const PairForces c = k.evaluate(Vec3::Zero(), Vec3::Zero(), Vec3::UnitX());
  EXPECT_TRUE(std::isfinite(c.energy));
  EXPECT_GT(c.energy, 0.0);
  EXPECT_EQ(c.f1, Vec3::Zero());
}

TEST(NpNpContact, CentralGradientAndContinuity) {
  const NpNpKernel k;
  std::mt19937_64 g(9);
  std::uniform_real_distribution<double> R(4.0, 8.0);  // linear branch (R < 5.25), well, ramp
  const double h = 1e-6;
  for (int s = 0; s < 60; ++s) {
    const Vec3 d = R(g) * random_unit(g);
    PairForces r;
    ASSERT_TRUE(k.evaluate(d, r));
    for (int a = 0; a < 3; ++a) {
      Vec3 e = Vec3::Zero();
      e[a] = h;
      PairForces p, m;
      k.evaluate(d + e, p);
      k.evaluate(d - e, m);
      EXPECT_NEAR(r.f2[a], -(p.energy - m.energy) / (2 * h), 1e-6 * std::max(r.f2.norm(), 1e-3));
    }
    EXPECT_EQ(r.f1, -r.f2);
    EXPECT_LT(r.f2.cross(d).norm(), 1e-12 * r.f2.norm() * d.norm() + 1e-300);  // central
    EXPECT_EQ(r.t1, Vec3::Zero());
    EXPECT_EQ(r.t2, Vec3::Zero());
  }
  PairForces in, at;
  k.evaluate(Vec3(8.0 * (1 - 1e-7), 0, 0), in);
  EXPECT_LT(std::abs(in.energy), 1e-12);
  EXPECT_FALSE(k.evaluate(Vec3(8.0, 0, 0), at));
  // Across D = 0.1 (R = 5.25): C¹.
  PairForces lo, hi;
  k.evaluate(Vec3(5.25 - 1e-9, 0, 0), lo);
  k.evaluate(Vec3(5.25 + 1e-9, 0, 0), hi);
  EXPECT_NEAR(lo.energy, hi.energy, 1e-5);
  EXPECT_NEAR(lo.f2.x(), hi.f2.x(), 1e-3);
}

TEST(NpContacts, StiffnessBoundsCoverTheCurvature) {
  // The critical-step bounds are at least the curvature of U along the centre line (central
  // differences of the law), for both kernels over their whole reach, linear branches included;
  // the NP gets no rotational stiffness.
  std::mt19937_64 g(31);
  const NpCntKernel kc;
  const NpNpKernel kn;
  const double h = 1e-4;
  for (int s = 0; s < 200; ++s) {
    const Vec3 n = random_unit(g), axis = random_unit(g);
    {
      const double R = std::uniform_real_distribution<double>(1.5, 4 * kT - 2 * h)(g);
      const Elements el = np_and_segment(R * n, Vec3::Zero(), axis, s % 2 == 0);
      const std::size_t inp = s % 2 == 0 ? 0 : 1;
      StiffnessSums sums;
      sums.reset(2);
      kc.stiffness(el, 0, 1, el.x[1] - el.x[0], sums);
      auto U = [&](double r) { return kc.evaluate(r * n, Vec3::Zero(), axis).energy; };
      const double curv = std::abs(U(R + h) - 2 * U(R) + U(R - h)) / (h * h);
      EXPECT_GE(sums.kt[0], curv * (1 - 1e-4)) << "NP-CNT at R = " << R;
      EXPECT_EQ(sums.kt[0], sums.kt[1]);
      EXPECT_EQ(sums.kr[inp], 0.0);
      EXPECT_GE(sums.kr[1 - inp], 0.0);
    }
    {
      const double R = std::uniform_real_distribution<double>(4.5, 8.0 - 2 * h)(g);
      Elements el;
      el.add(nanoparticle(Vec3::Zero()));
      el.add(nanoparticle(R * n));
      StiffnessSums sums;
      sums.reset(2);
      kn.stiffness(el, 0, 1, el.x[1] - el.x[0], sums);
      const double curv =
          std::abs(kn.energy(R + h) - 2 * kn.energy(R) + kn.energy(R - h)) / (h * h);
      EXPECT_GE(sums.kt[0], curv * (1 - 1e-4)) << "NP-NP at R = " << R;
      EXPECT_EQ(sums.kr[0] + sums.kr[1], 0.0);
    }
  }
  // A system of NPs and a tube gets a finite critical step from them.
  System sys = [] {
    Elements el;
    el.add(nanoparticle(Vec3::Zero()));
    el.add(nanoparticle(Vec3(5.3, 0, 0)));
    el.add(cnt_segment(Vec3(0, 3.0, 0), Quat::Identity(), 0, 0));
    System s(std::move(el));
    s.add(std::make_unique<NpCntContact>());
    s.add(std::make_unique<NpNpContact>());
    s.initialize();
    return s;
  }();
  EXPECT_TRUE(std::isfinite(sys.critical_dt()));
  std::printf("critical step of 2 NPs and a segment in contact: %.1f fs\n",
              sys.critical_dt() * 1000);
  EXPECT_GT(sys.critical_dt(), 0.03);  // above the CNT bonds' (the thesis ran 30 fs)
}

TEST(NpContacts, BadParametersAreRefusedNamingTheParameter) {
  auto message = [](auto make) {
    try {
      make();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  NpCntParams c;
  c.rho = -1;
  EXPECT_NE(message([&] { NpCntKernel k(c); }).find("rho must be finite and > 0"),
            std::string::npos);
  c = {};
  c.epsilon = 0;
  EXPECT_NE(message([&] { NpCntKernel k(c); }).find("NP-CNT contact epsilon"), std::string::npos);
  NpNpParams n;
  n.alpha = 4.0;  // < beta
  EXPECT_NE(message([&] { NpNpKernel k(n); }).find("alpha must be finite and > beta"),
            std::string::npos);
  EXPECT_NE(message([] { np_np_dashpot(-0.1); }).find("np_np_damping ratio"), std::string::npos);
  EXPECT_NE(message([] { nanoparticle(Vec3(NAN, 0, 0)); }).find("position must be finite"),
            std::string::npos);
}

// ---- the element ----------------------------------------------------------------------------

TEST(Nanoparticle, ElementOfModelMd) {
  const ElementInit e = nanoparticle(Vec3(1, 2, 3));
  EXPECT_EQ(e.kind, ElementKind::Nanoparticle);
  EXPECT_EQ(e.radius, 2.5);
  // 108 691 amu; 1 amu = 1.66053907e-27 kg = 1.0364270e-2 eV·ps²/nm².
  EXPECT_NEAR(e.mass, 108691 * 1.66053906660e-27 / 1.602176634e-19 * 1e6, 1e-9 * e.mass);
  EXPECT_NEAR(e.inertia.x(), 0.4 * e.mass * 6.25, 1e-12 * e.inertia.x());
  EXPECT_EQ(e.inertia.x(), e.inertia.y());
  EXPECT_EQ(e.inertia.x(), e.inertia.z());
  // About 41 segment masses (tensile.md §1).
  EXPECT_NEAR(e.mass / cnt::kMass, 41.03, 0.01);
}

// ---- an NP beside a long tube ---------------------------------------------------------------

TEST(NpCntContact, NpBesideA201SegmentTubeRestsAt3462) {
  Elements el;
  auto bonds = add_tube(el, 201, Vec3::Zero(), 0);
  const std::size_t inp = el.add(nanoparticle(Vec3(0, 3.6, 0)));
  System sys(std::move(el));
  sys.add(std::move(bonds));
  sys.add(std::make_unique<NpCntContact>());  // the NP–segment vdW only
  sys.initialize();
  auto energy_at = [&](double h) {
    sys.elements().x[inp] = Vec3(0, h, 0);
    sys.refresh();
    return sys.energy().potential.total_stored();
  };
  const double h = golden_min(energy_at, 3.2, 3.8, 1e-8);
  const double U = energy_at(h);
  std::printf("NP beside a 201-segment tube: rest %.6f nm, U = %.7f eV\n", h, U);
  EXPECT_NEAR(h, 3.462, 0.002);
  EXPECT_NEAR(h, 3.462002, 2e-6);  // model.md §5's figure
  expect_rel(U, -1.811767, 1e-4, "well depth");
  // All of it is NP–CNT energy (the straight tube's bonds are at rest), and at rest the NP feels
  // no force.
  EXPECT_NEAR(term(sys, EnergyTerm::NpCnt), U, 1e-12);
  EXPECT_LT(sys.elements().f[inp].norm(), 1e-4);
  // The energy profile U(h) beside the tube (NP in the plane of a segment centre) of tensile.md
  // §2.4, computed there with the printed ε0 = 0.005407 eV: U is proportional to ε0, so ten times
  // those values (7 digits).
  const double profile[][2] = {{3.0, 1.5071322},  {3.2, 0.0320042},  {3.3, -0.1260430},
                               {3.4, -0.1754986}, {3.5, -0.1796287}, {3.6, -0.1659486},
                               {3.8, -0.1257179}, {4.0, -0.0880996}, {4.5, -0.0247773},
                               {5.0, -0.0029115}};
  for (const auto& row : profile)
    EXPECT_NEAR(energy_at(row[0]), 10 * row[1], 10 * 6e-8) << "h = " << row[0];
  EXPECT_EQ(energy_at(5.5), 0.0);
  energy_at(h);
  // The NP's sub-list holds at least every segment within 4T of it.
  const auto in_reach =
      static_cast<std::size_t>(std::floor(std::sqrt(std::pow(4 * kT, 2) - h * h) / kT));
  EXPECT_GE(sys.neighbors(*sys.find<NpCntContact>())->pair_count(), 2 * in_reach + 1);
}

// ---- dynamics ---------------------------------------------------------------------------------

namespace {

// A 20-segment tube along x with three NPs beside it and near each other, random velocities.
System np_scene(bool damped, std::uint64_t seed, IntegratorSettings s = {}) {
  Elements el;
  auto bonds = add_tube(el, 20, Vec3::Zero(), 0);
  for (const Vec3& x : {Vec3(-6, 3.6, 0), Vec3(0, 3.5, 0.8), Vec3(6, 0.5, 3.6)})
    el.add(nanoparticle(x));
  std::mt19937_64 g(seed);
  // Segments at about 800 K (σ = √(kT/m), √(kT/I)); NPs faster (≈ 0.7 eV each) so they roam
  // their wells, and spinning slowly (no law acts on an NP's spin).
  std::normal_distribution<double> vs(0.0, 0.05), vn(0.0, 0.02), ws(0.0, 0.07), wn(0.0, 0.005);
  for (std::size_t i = 0; i < el.size(); ++i) {
    const bool isnp = el.kind[i] == ElementKind::Nanoparticle;
    el.v[i] = isnp ? Vec3(vn(g), vn(g), vn(g)) : Vec3(vs(g), vs(g), vs(g));
    el.w[i] = isnp ? Vec3(wn(g), wn(g), wn(g)) : Vec3(ws(g), ws(g), ws(g));
  }
  System sys(std::move(el), s);
  sys.add(std::move(bonds));
  sys.add(std::make_unique<AnisotropicVdw>());
  sys.add(std::make_unique<NpCntContact>());
  sys.add(std::make_unique<NpNpContact>());
  if (damped) {
    sys.add(std::make_unique<NpContactDamping>(np_cnt_dashpot()));
    sys.add(std::make_unique<NpContactDamping>(np_np_dashpot()));
  }
  sys.initialize();
  return sys;
}

}  // namespace

TEST(NpContacts, NveEnergyConservationWithNanoparticles) {
  // No damping, the default (auto) step: the linear trend of the total energy is < 1e-3 of the
  // kinetic energy scale (the engine's NVE criterion, test_cnt_bundle).
  System sys = np_scene(false, 7);
  const long steps = 20'000, every = 200;
  std::vector<double> t, e;
  double ke = 0, np_cnt = 0, np_np = 0;
  for (long k = 0; k < steps / every; ++k) {
    sys.run(every);
    t.push_back(sys.time());
    e.push_back(sys.energy().total());
    ke += sys.energy().kinetic();
    np_cnt = std::min(np_cnt, term(sys, EnergyTerm::NpCnt));
    np_np = std::min(np_np, term(sys, EnergyTerm::NpNp));
  }
  ke /= static_cast<double>(t.size());
  const double drift = std::abs(mdem::testing::linear_trend(t, e));
  std::printf(
      "NVE with NPs: %ld steps at dt %.2f fs, trend %.3g eV, kinetic scale %.4g eV (%.2e)\n", steps,
      sys.dt() * 1000, drift, ke, drift / ke);
  EXPECT_LT(drift, 1e-3 * ke);
  // Both NP terms took part.
  EXPECT_LT(np_cnt, -0.1);
  EXPECT_LT(np_np, -0.01);
  EXPECT_LT(sys.energy_balance_error(), 5e-2);
}

TEST(NpContacts, DashpotsActOnNpPairsOnlyAndDissipate) {
  System sys = np_scene(true, 8);
  const Elements& el = sys.elements();
  // Which elements are in an NP pair within reach.
  std::vector<bool> in_np_pair(el.size(), false);
  for (std::size_t i = 0; i < el.size(); ++i)
    for (std::size_t j = i + 1; j < el.size(); ++j) {
      const bool any_np =
          el.kind[i] == ElementKind::Nanoparticle || el.kind[j] == ElementKind::Nanoparticle;
      const double reach = el.kind[i] == el.kind[j] ? 8.0 : 4 * kT;
      if (any_np && (el.x[j] - el.x[i]).norm() < reach) in_np_pair[i] = in_np_pair[j] = true;
    }
  int damped = 0;
  Vec3 total = Vec3::Zero();
  double power = 0;
  for (std::size_t i = 0; i < el.size(); ++i) {
    total += sys.damping_forces()[i];
    power += sys.damping_forces()[i].dot(el.v[i]);
    if (!in_np_pair[i])
      EXPECT_EQ(sys.damping_forces()[i].norm(), 0.0) << "dashpot on " << i;
    else if (sys.damping_forces()[i].norm() > 0)
      ++damped;
  }
  EXPECT_GE(damped, 6);
  EXPECT_LT(total.norm(), 1e-12 * (1 + damped));  // momentum conserved
  EXPECT_LT(power, 0.0);                          // dissipates
  // Over a run: linear momentum is conserved, energy leaves through the dashpots and the balance
  // closes.
  auto momentum = [&] {
    Vec3 p = Vec3::Zero();
    for (std::size_t i = 0; i < el.size(); ++i) p += el.mass[i] * el.v[i];
    return p;
  };
  const Vec3 p0 = momentum();
  const double e0 = sys.energy().total();
  sys.run(5000);
  const double e1 = sys.energy().total();
  std::printf("NP dashpots: total energy %.4f -> %.4f eV, dissipated %.4f eV\n", e0, e1,
              sys.energy().dissipated);
  EXPECT_LT(e1, e0);
  EXPECT_GT(sys.energy().dissipated, 0.0);
  EXPECT_LT((momentum() - p0).norm(), 1e-9 * (1 + p0.norm()));
  EXPECT_LT(std::abs(sys.energy().balance_residual()), 0.05 * sys.energy().dissipated);
}

// ---- the per-kind-pair table -----------------------------------------------------------------

TEST(NpContacts, EightNanometreNpNpModelDoesNotEnlargeTheCntList) {
  // Two bundled tubes and NPs: the CNT–CNT sub-list with the real 8 nm NP–NP model present
  // equals the one without it, and the NP–NP and NP–CNT lists hold exactly their kinds.
  auto build = [](bool with_np) {
    Elements el;
    auto b0 = add_tube(el, 30, Vec3::Zero(), 0);
    auto b1 = add_tube(el, 30, Vec3(0, 1.75, 0), 1);
    for (const Vec3& x : {Vec3(-10, 5, 0), Vec3(-4, 5.3, 1), Vec3(3, -4, 0), Vec3(10, 3, 4)})
      el.add(nanoparticle(x));
    IntegratorSettings s;
    s.dt = 0.002;
    System sys(std::move(el), s);
    sys.add(std::make_unique<AnisotropicVdw>());
    if (with_np) {
      sys.add(std::make_unique<NpCntContact>());
      sys.add(std::make_unique<NpNpContact>());
      sys.add(std::make_unique<NpContactDamping>(np_np_dashpot()));
    }
    sys.initialize();
    return sys;
  };
  const System a = build(false), b = build(true);
  const auto* la = a.neighbors(*a.find<AnisotropicVdw>());
  const auto* lb = b.neighbors(*b.find<AnisotropicVdw>());
  ASSERT_TRUE(la && lb);
  EXPECT_EQ(la->pair_count(), lb->pair_count());
  EXPECT_EQ(la->neighbors(), lb->neighbors());
  const std::string d = b.pair_table().describe();
  EXPECT_NE(d.find("np_np_contact + np_np_damping, cutoff 8 nm"), std::string::npos) << d;
  const auto* nn = b.neighbors(*b.find<NpNpContact>());
  const auto& el = b.elements();
  std::size_t np_pairs = 0;
  for (std::size_t i = 0; i < el.size(); ++i)
    for (std::uint32_t m = nn->offsets()[i]; m < nn->offsets()[i + 1]; ++m) {
      EXPECT_EQ(el.kind[i], ElementKind::Nanoparticle);
      EXPECT_EQ(el.kind[nn->neighbors()[m]], ElementKind::Nanoparticle);
      ++np_pairs;
    }
  EXPECT_GE(np_pairs, 1u);  // (−10,5,0)–(−4,5.3,1) are 6.1 nm apart: beyond 4T, within 8 nm
  // NP–NP energy booked under np_np, not under vdw.
  EXPECT_LT(term(b, EnergyTerm::NpNp), 0.0);
  EXPECT_EQ(term(a, EnergyTerm::NpNp), 0.0);
  EXPECT_NEAR(term(a, EnergyTerm::Vdw), term(b, EnergyTerm::Vdw), 1e-12);
}

// ---- mdem probe ------------------------------------------------------------------------------

namespace {

struct ProbeRun {
  int code;
  std::string out, err;
};

ProbeRun probe(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  const int code = cli::probe(args, out, err);
  return {code, out.str(), err.str()};
}

}  // namespace

TEST(NpProbe, NpCntCurveBesideATubeHasItsMinimumAt3462) {
  const ProbeRun r =
      probe({"--model", "np-cnt", "--x2", "0,3.462,0", "--tube", "201", "--scan", "3.2:3.8:601"});
  ASSERT_EQ(r.code, cli::kOk) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["model"], "np-cnt");
  expect_rel(j["energy_eV"].get<double>(), -1.811767, 1e-4, "U at 3.462 beside the tube");
  const auto& curve = j["curve"];
  ASSERT_EQ(curve.size(), 601u);
  double best = 1e300, at = 0;
  for (const auto& p : curve)
    if (p["energy_eV"].get<double>() < best) {
      best = p["energy_eV"].get<double>();
      at = p["R_nm"].get<double>();
    }
  EXPECT_NEAR(at, 3.462, 0.001);
  EXPECT_NEAR(j["minimum"]["R_nm"].get<double>(), 3.462, 0.001);
  expect_rel(best, -1.811767, 1e-4, "curve minimum");
}

TEST(NpProbe, PrintedEpsilonIsAParameter) {
  // ε0 = 0.005407 eV, the thesis's printed value: the same rest distance, a tenth of the depth
  // (tensile.md §2.4: −0.1811767 eV).
  const ProbeRun r = probe({"--model", "np-cnt", "--x2", "0,3.5,0", "--tube", "201", "--scan",
                            "3.3:3.7:41", "--epsilon", "0.005407"});
  ASSERT_EQ(r.code, cli::kOk) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["np_cnt"]["epsilon_eV"].get<double>(), 0.005407);
  EXPECT_NEAR(j["minimum"]["R_nm"].get<double>(), 3.462002, 1e-6);
  expect_rel(j["minimum"]["energy_eV"].get<double>(), -0.1811767, 1e-6, "printed-eps depth");
}

TEST(NpProbe, SinglePairsMatchTheCheckValues) {
  ProbeRun r = probe({"--model", "np-cnt", "--x2", "3,3,0"});
  ASSERT_EQ(r.code, cli::kOk) << r.err;
  auto j = nlohmann::json::parse(r.out);
  expect_rel(j["energy_eV"].get<double>(), -2.619222e-02, 1e-6, "np-cnt U");
  expect_rel(j["element2"]["force_eV_per_nm"][1].get<double>(), 3.569611, 1e-6, "np-cnt F_NP");
  expect_rel(j["element1"]["torque_eV"][2].get<double>(), -7.734082, 1e-6, "np-cnt tau");
  r = probe({"--model", "np-np", "--x2", "6,0,0", "--scan", "5.2:6.0:801"});
  ASSERT_EQ(r.code, cli::kOk) << r.err;
  j = nlohmann::json::parse(r.out);
  expect_rel(j["energy_eV"].get<double>(), -0.3537376, 1e-6, "np-np U");
  expect_rel(j["element2"]["force_eV_per_nm"][0].get<double>(), -1.365298, 1e-6, "np-np F");
  EXPECT_NEAR(j["minimum"]["R_nm"].get<double>(), 5.4287, 0.001);
  expect_rel(j["minimum"]["energy_eV"].get<double>(), -4.2283537, 1e-5, "np-np depth");
}

TEST(NpProbe, BadModelAndFlagsAreRefused) {
  ProbeRun r = probe({"--model", "np-foo", "--x2", "0,3,0"});
  EXPECT_EQ(r.code, cli::kUsage);
  EXPECT_NE(r.err.find("unknown model 'np-foo'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("np-cnt"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("np-np"), std::string::npos) << r.err;
  r = probe({"--model", "np-cnt", "--x2", "0,3,0", "--scan", "4:3:10"});
  EXPECT_EQ(r.code, cli::kUsage);
  EXPECT_NE(r.err.find("--scan"), std::string::npos) << r.err;
  r = probe({"--model", "vdw", "--x2", "0,3,0", "--tube", "5"});
  EXPECT_EQ(r.code, cli::kUsage);
  EXPECT_NE(r.err.find("--tube"), std::string::npos) << r.err;
  r = probe({"--model", "np-cnt", "--x2", "0,3,0", "--tube", "0"});
  EXPECT_EQ(r.code, cli::kUsage);
}
