// Grain bonds (thesis Eq. 37–38, model.md §6): brittle failure loads, the plastic force path,
// energy conservation and the ledger through yield and breaking, a bonded chain as a Timoshenko
// cantilever, dashpots, input validation and checkpoints. Each against an independent analytical
// value.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/core/units.h"
#include "mdem/force/bond/grain_bond.h"
#include "mdem/integrate/system.h"
#include "mdem/io/state_io.h"
#include "mdem/scene/grain.h"
#include "support.h"

namespace mdem {
namespace {

constexpr double kPi = std::numbers::pi;

// Two grains of radius R on the x axis, centre distance L (grain 0 at the origin).
Elements pair_of_grains(const GrainMaterial& m, double R, double L) {
  Elements el;
  el.add(grain_element(Vec3::Zero(), R, m));
  el.add(grain_element(Vec3(L, 0, 0), R, m));
  return el;
}

GrainBondParams params(const GrainMaterial& m, BondBehaviour b, double strength_gpa) {
  GrainBondParams p;
  p.material = m;
  p.behaviour = b;
  p.strength = units::GPa(strength_gpa);
  return p;
}

IntegratorSettings settings(double local_damping = 0.0, int threads = 1) {
  IntegratorSettings s;
  s.local_damping = local_damping;
  s.threads = threads;
  return s;
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

// ------------------------------------------------------------------------------------------
// 1. Brittle failure loads.

enum class Load { Tension, Bending, Twist };

// Grain 0 fixed, grain 1 free under a slowly ramped external force (tension, along the bond) or
// moment (bending about z, twist about the bond axis x), with local damping 0.7 so it follows the
// load quasi-statically. Returns the load applied at the step the bond broke.
double load_at_break(Load load, double analytic) {
  const GrainMaterial cds = cadmium_sulfide();
  const double R = 1.0;
  System sys(pair_of_grains(cds, R, 2 * R), settings(0.7));
  sys.elements().fix_all(0);
  auto* bonds = sys.add(std::make_unique<GrainBond>(params(cds, BondBehaviour::Brittle, 4.0)));
  bonds->add(sys.elements(), 0, 1);
  sys.initialize();
  // Reaches the analytic load in 6000 steps: about 300 periods of the slowest mode.
  const double rate = analytic / (6000 * sys.dt());
  sys.add_updater([&](System& s, double t) {
    Elements& el = s.elements();
    el.f_ext[1].setZero();
    el.t_ext[1].setZero();
    if (load == Load::Tension) el.f_ext[1] = Vec3(rate * t, 0, 0);
    if (load == Load::Bending) el.t_ext[1] = Vec3(0, 0, rate * t);
    if (load == Load::Twist) el.t_ext[1] = Vec3(rate * t, 0, 0);
  });
  while (bonds->broken_count() == 0 && sys.steps() < 12000) sys.run(1);
  EXPECT_EQ(bonds->broken_count(), 1u);
  return rate * sys.time();
}

TEST(GrainBond, BrittleBondBreaksInTensionAtSigmaFTimesA) {
  const double R = 1.0, sf = units::GPa(4.0);
  const double analytic = sf * kPi * R * R;  // F = σ_f·A
  const double sim = load_at_break(Load::Tension, analytic);
  EXPECT_NEAR(sim / analytic, 1.0, 0.02) << "sim " << sim << " analytic " << analytic;
  std::printf("tension: F_break sim %.6g nN, analytic %.6g nN (ratio %.5f)\n", units::to_nN(sim),
              units::to_nN(analytic), sim / analytic);
}

TEST(GrainBond, BrittleBondBreaksInBendingAtPiOver4SigmaFRCubed) {
  const double R = 1.0, sf = units::GPa(4.0);
  const double analytic = 0.25 * kPi * sf * R * R * R;  // M = σ_f·I/R_b
  const double sim = load_at_break(Load::Bending, analytic);
  EXPECT_NEAR(sim / analytic, 1.0, 0.02) << "sim " << sim << " analytic " << analytic;
  std::printf("bending: M_break sim %.6g nN·nm, analytic %.6g nN·nm (ratio %.5f)\n",
              units::to_nNnm(sim), units::to_nNnm(analytic), sim / analytic);
}

TEST(GrainBond, BrittleBondBreaksInTwistAtPiOver2TauFRCubed) {
  const double R = 1.0, tf = 0.5 * units::GPa(4.0);
  const double analytic = 0.5 * kPi * tf * R * R * R;  // M = τ_f·J/R_b
  const double sim = load_at_break(Load::Twist, analytic);
  EXPECT_NEAR(sim / analytic, 1.0, 0.02) << "sim " << sim << " analytic " << analytic;
  std::printf("twist: M_break sim %.6g nN·nm, analytic %.6g nN·nm (ratio %.5f)\n",
              units::to_nNnm(sim), units::to_nNnm(analytic), sim / analytic);
}

// The stresses the bond reports are the header's edge stresses: σ = F_n/A + |M_b|R_b/I,
// τ = |F_s|/A + |M_t|R_b/J, here for a combined displacement of known forces and moments.
TEST(GrainBond, EdgeStressesCombineForceAndMoment) {
  const GrainMaterial au = gold();
  const double R = 1.5, L = 3.0;
  Elements el = pair_of_grains(au, R, L);
  GrainBond b(params(au, BondBehaviour::Elastic, 0.0));
  b.add(el, 0, 1);
  const double un = 0.01, us = 0.02, tb = 0.003, tt = 0.004;
  el.x[1] += Vec3(un, us, 0);
  // Both grains turned by opposite halves of a rotation with a twist (x) and a bending (z) part.
  const Vec3 rot(tt, 0, tb);
  el.q[0] = quat_exp(-0.5 * rot);
  el.q[1] = quat_exp(0.5 * rot);
  const BondDeformation d = bond_deformation(b.bonds()[0].bond, el.x[0], el.q[0], el.x[1], el.q[1]);
  const double A = kPi * R * R, I = kPi * R * R * R * R / 4, J = 2 * I;
  const double kn = au.youngs / L, ks = au.shear() / L;
  const BondStress s = b.stress(el, 0);
  const double fn = kn * A * d.u_n, fs = ks * A * d.u_s.norm();
  const double mb = kn * I * d.theta_b.norm(), mt = ks * J * std::abs(d.theta_t);
  EXPECT_NEAR(s.sigma, fn / A + mb * R / I, 1e-12 * s.sigma);
  EXPECT_NEAR(s.tau, fs / A + mt * R / J, 1e-12 * s.tau);
  EXPECT_GT(mb, 0);
  EXPECT_GT(mt, 0);
}

// ------------------------------------------------------------------------------------------
// 2. Plastic force path.

// Moves grain 1 to (L + ux, uy, 0) and evaluates once.
void place(System& sys, double L, double ux, double uy) {
  sys.elements().x[1] = Vec3(L + ux, uy, 0);
  sys.refresh();
}

TEST(GrainBond, PlasticBondInTensionCapsAtSigmaYTimesAAndKeepsTheSlip) {
  const GrainMaterial au = gold();
  const double R = 1.0, L = 2.0, sy = units::GPa(8.0);
  System sys(pair_of_grains(au, R, L), settings());
  sys.elements().fix_all(0);
  sys.elements().fix_all(1);  // moved by hand
  auto* bonds = sys.add(std::make_unique<GrainBond>(params(au, BondBehaviour::Plastic, 8.0)));
  bonds->add(sys.elements(), 0, 1);
  sys.initialize();

  const double A = kPi * R * R, knA = au.youngs / L * A, cap = sy * A, uy = cap / knA;
  EXPECT_NEAR(knA, bonds->stiffness(0).kn_area, 1e-12 * knA);
  // (displacement, expected force on grain 1 along x (restoring), expected plastic slip)
  struct Point {
    double u, force, slip;
  };
  const std::vector<Point> path = {
      {0.5 * uy, -0.5 * cap, 0},          // elastic, slope kn·A
      {1.0 * uy, -cap, 0},                // at the limit
      {1.5 * uy, -cap, 0.5 * uy},         // capped, flows
      {2.0 * uy, -cap, 1.0 * uy},         // capped, flows
      {1.5 * uy, -0.5 * cap, 1.0 * uy},   // unloads elastically, same slope
      {1.0 * uy, 0.0, 1.0 * uy},          // unloaded: permanent offset = slip
      {0.25 * uy, 0.75 * cap, 1.0 * uy},  // compression, still elastic
      {-0.5 * uy, cap, 0.5 * uy},         // yields in compression: capped at −σ_y·A
      {0.0, 0.5 * cap, 0.5 * uy},         // elastic again
  };
  double released = 0, slip_prev = 0;
  for (const Point& p : path) {
    place(sys, L, p.u, 0);
    const Vec3 f = sys.elements().f[1];
    SCOPED_TRACE("u = " + std::to_string(p.u / uy) + " u_y");
    EXPECT_NEAR(f.x(), p.force, 1e-9 * cap);
    EXPECT_NEAR(f.y(), 0.0, 1e-9 * cap);
    EXPECT_NEAR(f.z(), 0.0, 1e-9 * cap);
    EXPECT_NEAR(bonds->bonds()[0].plastic_normal, p.slip, 1e-9 * uy);
    EXPECT_NEAR(bonds->bonds()[0].plastic_shear.norm(), 0.0, 1e-9 * uy);
    // Stored energy ½ kn·A (u − slip)²; the flow released cap × slip increment.
    const double e = 0.5 * knA * (p.u - p.slip) * (p.u - p.slip);
    EXPECT_NEAR(sys.energy().potential.total_stored(), e, 1e-9 * cap * uy);
    EXPECT_NEAR(sys.energy().potential.released, cap * std::abs(p.slip - slip_prev),
                1e-9 * cap * uy);
    released += sys.energy().potential.released;
    slip_prev = p.slip;
  }
  EXPECT_NEAR(released, cap * 1.5 * uy, 1e-9 * cap * uy);  // slips 1.0 u_y out, 0.5 u_y back
  EXPECT_EQ(bonds->yielded_count(), 1u);
  // Evaluating the same state again changes nothing and releases nothing.
  sys.refresh();
  EXPECT_EQ(sys.energy().potential.released, 0.0);
  EXPECT_NEAR(bonds->bonds()[0].plastic_normal, 0.5 * uy, 1e-9 * uy);
}

TEST(GrainBond, PlasticBondInShearCapsAtTauYTimesAAndKeepsTheSlip) {
  const GrainMaterial au = gold();
  const double R = 1.0, L = 2.0, ty = 0.5 * units::GPa(8.0);
  System sys(pair_of_grains(au, R, L), settings());
  sys.elements().fix_all(0);
  sys.elements().fix_all(1);
  auto* bonds = sys.add(std::make_unique<GrainBond>(params(au, BondBehaviour::Plastic, 8.0)));
  bonds->add(sys.elements(), 0, 1);
  sys.initialize();

  const double A = kPi * R * R, ksA = au.shear() / L * A, cap = ty * A, uy = cap / ksA;
  struct Point {
    double u, force, slip;
  };
  const std::vector<Point> path = {
      {0.5 * uy, -0.5 * cap, 0},
      {1.0 * uy, -cap, 0},
      {1.75 * uy, -cap, 0.75 * uy},
      {2.5 * uy, -cap, 1.5 * uy},
      {2.0 * uy, -0.5 * cap, 1.5 * uy},
      {1.5 * uy, 0.0, 1.5 * uy},
      {0.0, cap, 1.0 * uy},
      {1.0 * uy, 0.0, 1.0 * uy},
  };
  for (const Point& p : path) {
    place(sys, L, 0, p.u);
    const Vec3 f = sys.elements().f[1];
    SCOPED_TRACE("u_s = " + std::to_string(p.u / uy) + " u_y");
    EXPECT_NEAR(f.y(), p.force, 1e-9 * cap);
    EXPECT_NEAR(f.x(), 0.0, 1e-9 * cap);
    EXPECT_NEAR(bonds->bonds()[0].plastic_shear.y(), p.slip, 1e-9 * uy);
    EXPECT_NEAR(bonds->bonds()[0].plastic_normal, 0.0, 1e-12);
    EXPECT_NEAR(sys.energy().potential.total_stored(), 0.5 * ksA * (p.u - p.slip) * (p.u - p.slip),
                1e-9 * cap * uy);
  }
}

// ------------------------------------------------------------------------------------------
// 3. Energy.

// Grains on an nx × ny × nz simple cubic lattice of spacing a (jittered), radii in [0.95, 1.05],
// bonded to their lattice neighbours.
struct Cluster {
  Elements el;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
};

Cluster lattice_cluster(const GrainMaterial& m, int nx, int ny, int nz, double a, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Cluster c;
  auto id = [&](int i, int j, int k) { return static_cast<std::uint32_t>((k * ny + j) * nx + i); };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const Vec3 x = a * Vec3(i, j, k) + 0.03 * Vec3(u(rng), u(rng), u(rng));
        c.el.add(grain_element(x, 0.5 * a * (1.0 + 0.05 * u(rng)), m));
      }
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (i + 1 < nx) c.pairs.push_back({id(i, j, k), id(i + 1, j, k)});
        if (j + 1 < ny) c.pairs.push_back({id(i, j, k), id(i, j + 1, k)});
        if (k + 1 < nz) c.pairs.push_back({id(i, j, k), id(i, j, k + 1)});
      }
  return c;
}

TEST(GrainBond, UndampedBondedClusterConservesEnergy) {
  const GrainMaterial au = gold();
  Cluster c = lattice_cluster(au, 3, 3, 2, 2.0, 7);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  for (std::size_t i = 0; i < c.el.size(); ++i) {
    c.el.v[i] = 0.02 * Vec3(g(rng), g(rng), g(rng));
    c.el.w[i] = 0.02 * Vec3(g(rng), g(rng), g(rng));
  }
  // A step well below the limit: Verlet's bounded energy fluctuation scales as (ω dt)² (measured:
  // 2.4e-4 at safety 0.05, 6.0e-5 at 0.025, 1.5e-5 at 0.0125; no drift).
  IntegratorSettings st = settings();
  st.safety = 0.02;
  System sys(std::move(c.el), st);
  auto* bonds = sys.add(std::make_unique<GrainBond>(params(au, BondBehaviour::Elastic, 0.0)));
  for (auto [i, j] : c.pairs) bonds->add(sys.elements(), i, j);
  sys.initialize();
  const double e0 = sys.energy().total();
  double worst = 0;
  for (int k = 0; k < 4000; ++k) {
    sys.run(1);
    worst = std::max(worst, std::abs(sys.energy().total() - e0) / e0);
  }
  std::printf("cluster: %zu grains, %zu bonds, dt %.4g ps, max |ΔE|/E over 4000 steps %.3g\n",
              sys.elements().size(), bonds->bonds().size(), sys.dt(), worst);
  EXPECT_LT(worst, 1e-4);
  EXPECT_GT(sys.energy().potential.total_stored(), 0.05 * e0);  // the bonds took part
  EXPECT_EQ(sys.energy().dissipated, 0.0);
}

// Grain 1 pulled along x at constant velocity out to u_out, back to u_back, grain 0 fixed:
// returns the system after the run.
struct Pull {
  std::unique_ptr<System> sys;
  GrainBond* bonds;
};

Pull pull_pair(const GrainMaterial& m, const GrainBondParams& p, double v, long out_steps,
               long back_steps) {
  const double R = 1.0, L = 2.0;
  Pull r;
  r.sys = std::make_unique<System>(pair_of_grains(m, R, L), settings());
  System& sys = *r.sys;
  sys.elements().fix_all(0);
  r.bonds = sys.add(std::make_unique<GrainBond>(p));
  r.bonds->add(sys.elements(), 0, 1);
  auto& dof = sys.elements().dof[1];
  dof.fill(DofMode::Fixed);
  dof[0] = DofMode::Prescribed;
  sys.initialize();
  // The velocity of the drift from step k to k+1 is set before it: here for k = 0, then by the
  // updater at the end of step k.
  sys.elements().v_prescribed[1].x() = v;
  const long nsteps = out_steps;
  sys.add_updater([v, nsteps, back_steps](System& s, double) {
    const long k = s.steps();
    s.elements().v_prescribed[1].x() = k < nsteps ? v : (k < nsteps + back_steps ? -v : 0.0);
  });
  sys.run(out_steps + back_steps);
  return r;
}

TEST(GrainBond, PlasticWorkIsBookedAsDissipatedAndTheBalanceHolds) {
  const GrainMaterial au = gold();
  const GrainBondParams p = params(au, BondBehaviour::Plastic, 8.0);
  const double R = 1.0, L = 2.0, A = kPi * R * R, knA = au.youngs / L * A, cap = p.strength * A;
  const double uy = cap / knA;
  // Out to 2 u_y in 2000 steps, back by 1 u_y.
  System probe(pair_of_grains(au, R, L), settings());
  probe.add(std::make_unique<GrainBond>(p))->add(probe.elements(), 0, 1);
  probe.initialize();
  const double dt = probe.dt();
  const double v = 2.0 * uy / (2000 * dt);
  Pull r = pull_pair(au, p, v, 2000, 1000);
  const System& sys = *r.sys;
  const double u_max = v * 2000 * dt;
  // Plastic slip u_max − u_y, released at the cap: W = σ_y·A·(u_max − u_y).
  const double slip = r.bonds->bonds()[0].plastic_normal;
  EXPECT_NEAR(slip, u_max - uy, 1e-9 * uy);
  EXPECT_NEAR(sys.energy().dissipated, cap * (u_max - uy), 1e-6 * cap * uy);
  std::printf(
      "plastic pull: slip %.6g nm (analytic %.6g), dissipated %.6g eV (analytic %.6g), "
      "balance error %.3g\n",
      slip, u_max - uy, sys.energy().dissipated, cap * (u_max - uy), sys.energy_balance_error());
  // Only the step entering yield mixes the trapezoid's mean force with the cap: ~1e-6.
  EXPECT_LT(sys.energy_balance_error(), 1e-5);
}

TEST(GrainBond, BrokenBondBooksItsEnergyAsDissipated) {
  const GrainMaterial cds = cadmium_sulfide();
  const GrainBondParams p = params(cds, BondBehaviour::Brittle, 4.0);
  const double R = 1.0, L = 2.0, A = kPi * R * R, knA = cds.youngs / L * A, cap = p.strength * A;
  const double uf = cap / knA;
  System probe(pair_of_grains(cds, R, L), settings());
  probe.add(std::make_unique<GrainBond>(p))->add(probe.elements(), 0, 1);
  probe.initialize();
  const double dt = probe.dt();
  const double v = 1.5 * uf / (3000 * dt);  // breaks after ~2000 steps
  Pull r = pull_pair(cds, p, v, 3000, 0);
  const System& sys = *r.sys;
  ASSERT_EQ(r.bonds->broken_count(), 1u);
  // Breaking releases the bond's ½ kn·A·u_f² (no contact after: the grains are apart), within
  // one step's motion of the break point.
  const double e_f = 0.5 * knA * uf * uf;
  const double tol = knA * uf * v * dt * 1.01;
  EXPECT_NEAR(sys.energy().dissipated, e_f, tol);
  EXPECT_EQ(sys.energy().potential.total_stored(), 0.0);
  std::printf("brittle pull: dissipated %.6g eV, bond energy at σ_f %.6g eV, balance error %.3g\n",
              sys.energy().dissipated, e_f, sys.energy_balance_error());
  // The step that breaks it ends with no force, so the integrator's trapezoid books half the
  // last step's work: an error of about v·dt/u_f (here 1.5/3000) of the bond's energy.
  EXPECT_LT(sys.energy_balance_error(), 1e-3);
}

// A chain 0–1–2 with a free grain in the middle, pulled and sheared at grain 2, with dashpots:
// the bonds yield (or break), the middle grain vibrates, and the ledger still balances.
double driven_chain_balance(BondBehaviour behaviour, std::size_t* events) {
  const GrainMaterial m = behaviour == BondBehaviour::Plastic ? gold() : cadmium_sulfide();
  const double strength = behaviour == BondBehaviour::Plastic ? 8.0 : 4.0;
  Elements el;
  for (int k = 0; k < 3; ++k) el.add(grain_element(Vec3(2.0 * k, 0, 0), 1.0, m));
  System sys(std::move(el), settings());
  sys.elements().fix_all(0);
  auto& dof = sys.elements().dof[2];
  dof.fill(DofMode::Fixed);
  dof[0] = dof[1] = DofMode::Prescribed;
  auto* bonds = sys.add(std::make_unique<GrainBond>(params(m, behaviour, strength)));
  bonds->add(sys.elements(), 0, 1);
  bonds->add(sys.elements(), 1, 2);
  sys.add(std::make_unique<GrainDashpots>(0.2, bonds, m.youngs, 1.0));
  sys.initialize();
  const double v = 0.8 / (3000 * sys.dt());  // 0.8 nm out in 3000 steps, then back
  sys.elements().v_prescribed[2] = Vec3(v, 0.5 * v, 0);
  sys.add_updater([v](System& s, double) {
    const double sgn = s.steps() < 3000 ? 1.0 : -1.0;
    s.elements().v_prescribed[2] = Vec3(sgn * v, 0.5 * sgn * v, 0);
  });
  sys.run(5000);
  *events = behaviour == BondBehaviour::Plastic ? bonds->yielded_count() : bonds->broken_count();
  std::printf("driven chain (%s): W_ext %.6g eV, dissipated %.6g eV, balance error %.3g\n",
              behaviour == BondBehaviour::Plastic ? "plastic" : "brittle",
              sys.energy().external_work, sys.energy().dissipated, sys.energy_balance_error());
  return sys.energy_balance_error();
}

TEST(GrainBond, DrivenPlasticChainKeepsTheLedgerBalance) {
  std::size_t yielded = 0;
  const double err = driven_chain_balance(BondBehaviour::Plastic, &yielded);
  EXPECT_EQ(yielded, 2u);
  EXPECT_LT(err, 1e-5);  // measured 2e-7: Verlet's error on the free grain's vibration
}

TEST(GrainBond, DrivenBrittleChainKeepsTheLedgerBalance) {
  std::size_t broken = 0;
  const double err = driven_chain_balance(BondBehaviour::Brittle, &broken);
  EXPECT_GE(broken, 1u);
  // Measured 6e-4: a bond breaking within a step leaves the trapezoid half the step's work short
  // (see BrokenBondBooksItsEnergyAsDissipated).
  EXPECT_LT(err, 2e-3);
}

// ------------------------------------------------------------------------------------------
// 4. A bonded chain as a cantilever.

// N equal grains on the x axis, spacing L = 2R, bonded neighbour to neighbour; grain 0 fixed in
// all six DOFs, a transverse force F (y) on the last grain, local damping to rest.
//
// Which beam the chain is: each bond is a neck of length L with a bending spring kn·I (kn = E/L)
// and a shear spring ks·A (ks = G/L) at its midpoint; so the chain is a Timoshenko beam of length
// ℓ = (N−1)L from the clamped centre to the loaded centre, flexural rigidity E·I and shear
// rigidity G·A with κ = 1 (the neck's shear spring is uniform over its section), whose curvature
// is lumped at the bond points. Discretely: the moment at bond k is M_k = F(ℓ − (k+½)L), each
// bond turns by M_k/(kn·I) and slides by F/(ks·A), and node k+1 rises by that slide plus the
// arms' turn (L/2)(φ_k + φ_{k+1}). Summed, the tip deflection is
//   δ = F ℓ³/(3 E I) + F ℓ/(G A) − F ℓ L²/(12 E I),
// Timoshenko's cantilever plus the trapezoidal rule's lumping error (−1/(4(N−1)²) of the
// bending term).
TEST(GrainBond, BondedChainCantileverDeflectsAsTimoshenko) {
  const GrainMaterial au = gold();
  const int N = 20;
  const double R = 1.0, L = 2.0 * R;
  Elements el;
  for (int k = 0; k < N; ++k) el.add(grain_element(Vec3(k * L, 0, 0), R, au));
  System sys(std::move(el), settings(0.7));
  sys.elements().fix_all(0);
  auto* bonds = sys.add(std::make_unique<GrainBond>(params(au, BondBehaviour::Elastic, 0.0)));
  for (int k = 0; k + 1 < N; ++k) bonds->add(sys.elements(), k, k + 1);

  const double A = kPi * R * R, I = kPi * R * R * R * R / 4;
  const double E = au.youngs, G = au.shear();
  const double kn = E / L, ks = G / L;  // so E = kn·L, G = ks·L per bond
  const double ell = (N - 1) * L;
  const double F = units::nN(0.001);
  const double timoshenko = F * ell * ell * ell / (3 * E * I) + F * ell / (G * A);
  // The discrete chain, by the recurrence (φ: node rotations about z).
  double phi = 0, y = 0;
  for (int k = 0; k + 1 < N; ++k) {
    const double phi_next = phi + F * (ell - (k + 0.5) * L) / (kn * I);
    y += F / (ks * A) + 0.5 * L * (phi + phi_next);
    phi = phi_next;
  }
  const double discrete = y, tip_rotation = phi;
  EXPECT_NEAR(discrete, timoshenko - F * ell * L * L / (12 * E * I), 1e-12 * discrete);

  sys.elements().f_ext[N - 1] = Vec3(0, F, 0);
  sys.initialize();
  double prev = 0;
  long steps = 0;
  for (; steps < 400000; steps += 5000) {
    sys.run(5000);
    const double d = sys.elements().x[N - 1].y();
    if (std::abs(d - prev) < 1e-6 * std::abs(d) && testing::max_unbalanced(sys) < 1e-4 * F) break;
    prev = d;
  }
  const double sim = sys.elements().x[N - 1].y();
  std::printf(
      "cantilever: %d grains, %ld steps, tip deflection sim %.6g nm, discrete %.6g nm, "
      "Timoshenko %.6g nm (shear part %.3g%%); tip rotation sim %.6g, analytic %.6g\n",
      N, steps, sim, discrete, timoshenko, 100 * F * ell / (G * A) / timoshenko,
      2.0 * std::atan2(sys.elements().q[N - 1].z(), sys.elements().q[N - 1].w()), tip_rotation);
  EXPECT_NEAR(sim / discrete, 1.0, 0.02);
  EXPECT_NEAR(sim / timoshenko, 1.0, 0.02);
  // The tip turns as the discrete chain predicts (Timoshenko: F ℓ²/(2 E I)).
  const Quat& q = sys.elements().q[N - 1];
  const double rotation = 2.0 * std::atan2(q.z(), q.w());
  EXPECT_NEAR(rotation / tip_rotation, 1.0, 0.02);
  EXPECT_NEAR(tip_rotation / (F * ell * ell / (2 * E * I)), 1.0, 1e-12);
}

// ------------------------------------------------------------------------------------------
// Dashpots.

TEST(GrainDashpots, ActAlongTheCentreLineWithTheCriticalRatioCoefficient) {
  const GrainMaterial au = gold();
  const double beta = 0.5;
  Elements el;
  el.add(grain_element(Vec3(0, 0, 0), 1.0, au));     // 0: bonded to 1
  el.add(grain_element(Vec3(2.0, 0, 0), 1.0, au));   // 1
  el.add(grain_element(Vec3(0, 1.9, 0), 1.0, au));   // 2: in contact with 0, unbonded
  el.add(grain_element(Vec3(0, 0, -5.0), 1.0, au));  // 3: far from all
  const std::size_t wall = add_platen(el, Vec3(0, 0, -5.8), Vec3(0, 0, 1), 1.0, 10.0);
  el.v[1] = Vec3(0.3, 0.1, 0);
  el.v[2] = Vec3(0.2, 0.5, 0);
  el.v[3] = Vec3(0.1, 0.0, -0.4);
  System sys(std::move(el), settings());
  for (int k = 0; k < 6; ++k) EXPECT_EQ(sys.elements().dof[wall][k], DofMode::Fixed);
  auto* bonds = sys.add(std::make_unique<GrainBond>(params(au, BondBehaviour::Elastic, 0.0)));
  bonds->add(sys.elements(), 0, 1);
  sys.add(std::make_unique<GrainDashpots>(beta, bonds, au.youngs, 1.0));
  sys.initialize();
  const Elements& e = sys.elements();
  const auto& fd = sys.damping_forces();
  auto c_of = [&](double m_eff, double k) { return 2 * beta * std::sqrt(m_eff * k); };
  const double m = e.mass[0];
  // Bond 0–1 along x: c with the bond's kn·A and half the mass; relative normal velocity 0.3.
  const double c01 = c_of(0.5 * m, bonds->stiffness(0).kn_area);
  // Contact 0–2 along y: Eq. 36 stiffness π R² (E/2)/(2R); relative normal velocity 0.5.
  const double c02 = c_of(0.5 * m, kPi * 1.0 * (0.5 * au.youngs) / 2.0);
  // Grain 3 against the platen (overlap 0.2): π R E with the grain's mass; normal velocity −0.4.
  const double c3w = c_of(m, kPi * 1.0 * au.youngs);
  EXPECT_NEAR(fd[1].x(), -c01 * 0.3, 1e-12 * c01);
  EXPECT_NEAR(fd[1].y(), 0.0, 1e-12 * c01);
  EXPECT_NEAR(fd[2].y(), -c02 * 0.5, 1e-12 * c02);
  EXPECT_NEAR(fd[0].x(), c01 * 0.3, 1e-12 * c01);
  EXPECT_NEAR(fd[0].y(), c02 * 0.5, 1e-12 * c02);
  EXPECT_NEAR(fd[3].z(), c3w * 0.4, 1e-12 * c3w);
  EXPECT_NEAR(fd[3].x(), 0.0, 1e-12 * c3w);
  EXPECT_NEAR(fd[wall].z(), -c3w * 0.4, 1e-12 * c3w);
}

// ------------------------------------------------------------------------------------------
// 5. Inputs.

void expect_invalid(const std::function<void()>& f, const std::string& field) {
  try {
    f();
    ADD_FAILURE() << "no exception; expected one naming " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos)
        << "message '" << e.what() << "' does not name " << field;
  }
}

TEST(GrainBond, RejectsInvalidInputsNamingTheField) {
  const GrainMaterial au = gold();
  auto with = [&](auto edit) {
    GrainBondParams p = params(au, BondBehaviour::Plastic, 8.0);
    edit(p);
    return [p] { GrainBond b(p); };
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  expect_invalid(with([&](GrainBondParams& p) { p.material.youngs = nan; }), "youngs");
  expect_invalid(with([&](GrainBondParams& p) { p.material.youngs = inf; }), "youngs");
  expect_invalid(with([&](GrainBondParams& p) { p.material.youngs = -1.0; }), "youngs");
  expect_invalid(with([&](GrainBondParams& p) { p.material.youngs = 0.0; }), "youngs");
  expect_invalid(with([&](GrainBondParams& p) { p.material.poisson = 0.5; }), "poisson");
  expect_invalid(with([&](GrainBondParams& p) { p.material.poisson = -0.1; }), "poisson");
  expect_invalid(with([&](GrainBondParams& p) { p.material.poisson = nan; }), "poisson");
  expect_invalid(with([&](GrainBondParams& p) { p.strength = 0.0; }), "strength");
  expect_invalid(with([&](GrainBondParams& p) { p.strength = nan; }), "strength");
  expect_invalid(with([&](GrainBondParams& p) {
                   p.behaviour = BondBehaviour::Brittle;
                   p.strength = 0.0;
                 }),
                 "strength");
  expect_invalid(with([&](GrainBondParams& p) {
                   p.behaviour = BondBehaviour::Brittle;
                   p.strength = -2.0;
                 }),
                 "strength");
  EXPECT_NO_THROW(GrainBond elastic(params(au, BondBehaviour::Elastic, 0.0)));

  Elements el = pair_of_grains(au, 1.0, 2.0);
  el.add(grain_element(Vec3(2.0, 0, 0), 1.0, au));  // coincides with grain 1
  GrainBond b(params(au, BondBehaviour::Brittle, 4.0));
  expect_invalid([&] { b.add(el, 0, 0); }, "i and j");
  EXPECT_EQ(b.add(el, 0, 1), 0u);
  expect_invalid([&] { b.add(el, 0, 1); }, "already bonded");
  expect_invalid([&] { b.add(el, 1, 0); }, "already bonded");
  expect_invalid([&] { b.add(el, 1, 2); }, "coincide");
  expect_invalid([&] { b.add(el, 0, 7); }, "out of range");
  EXPECT_TRUE(b.owns(1, 0));
  EXPECT_FALSE(b.owns(0, 2));

  expect_invalid([&] { grain_element(Vec3::Zero(), 0.0, au); }, "radius");
  expect_invalid([&] { grain_element(Vec3::Zero(), nan, au); }, "radius");
  expect_invalid([&] { grain_element(Vec3::Zero(), 1.0, GrainMaterial{}); }, "density");
  expect_invalid([&] { platen_element(Vec3::Zero(), Vec3::Zero(), 1.0, 1.0); }, "normal");
  expect_invalid([&] { platen_element(Vec3::Zero(), Vec3::UnitZ(), -1.0, 1.0); }, "mass");
  expect_invalid([&] { platen_element(Vec3::Zero(), Vec3::UnitZ(), 1.0, inf); }, "radius");
  expect_invalid([&] { GrainDashpots(-0.1, nullptr, au.youngs, 1.0); }, "ratio");
  expect_invalid([&] { GrainDashpots(0.5, nullptr, 0.0, 1.0); }, "contact_youngs");
}

TEST(Grain, MaterialsAndElementsFollowTheirDefinitions) {
  const GrainMaterial au = gold(), cds = cadmium_sulfide();
  EXPECT_NEAR(units::to_GPa(au.youngs), 79.0, 1e-12);
  EXPECT_NEAR(units::to_GPa(cds.youngs), 28.0, 1e-12);
  EXPECT_EQ(au.poisson, 0.46);
  // 19.3 g/cm³ = 19.3e-21 g/nm³ = 19.3e-24 kg/nm³, in amu/nm³.
  EXPECT_NEAR(units::to_amu(au.density), 19.3e-24 / units::kAmuKg,
              1e-9 * units::to_amu(au.density));
  EXPECT_NEAR(units::to_amu(cds.density), 4.82e-24 / units::kAmuKg,
              1e-9 * units::to_amu(cds.density));
  const ElementInit g = grain_element(Vec3(1, 2, 3), 1.5, au);
  const double m = au.density * 4.0 / 3.0 * kPi * 1.5 * 1.5 * 1.5;
  EXPECT_EQ(g.kind, ElementKind::Grain);
  EXPECT_NEAR(g.mass, m, 1e-12 * m);
  EXPECT_NEAR(g.inertia.x(), 0.4 * m * 2.25, 1e-12 * m);
  EXPECT_EQ(g.inertia.x(), g.inertia.z());
  const ElementInit p = platen_element(Vec3(0, 0, 5), Vec3(0, 0, -3), 2.0, 4.0);
  EXPECT_EQ(p.kind, ElementKind::Wall);
  EXPECT_LT((p.q * Vec3::UnitZ() - Vec3(0, 0, -1)).norm(), 1e-12);
  EXPECT_GT(p.inertia.minCoeff(), 0);
}

// Above kParallelMinItems bonds the bond and dashpot loops run threaded, each bond updated by
// one thread: the run matches the serial one (to the summation order of per-thread slots) and
// the same bonds break.
TEST(GrainBond, ThreadedBondLoopMatchesSerial) {
  const GrainMaterial m = cadmium_sulfide();
  std::vector<Vec3> x[2];
  std::vector<bool> broken[2];
  for (int run = 0; run < 2; ++run) {
    Cluster c = lattice_cluster(m, 10, 10, 10, 2.0, 3);  // 1000 grains, 2700 bonds
    System sys(std::move(c.el), settings(0.0, run + 1));
    Elements& el = sys.elements();
    for (std::size_t i = 0; i < 100; ++i) el.fix_all(i);
    for (std::size_t i = 900; i < 1000; ++i) {
      el.dof[i].fill(DofMode::Fixed);
      for (int k = 0; k < 3; ++k) el.dof[i][k] = DofMode::Prescribed;
      el.v_prescribed[i] = Vec3(0.0, 0.2, 0.6);
    }
    auto* bonds = sys.add(std::make_unique<GrainBond>(params(m, BondBehaviour::Brittle, 4.0)));
    for (auto [i, j] : c.pairs) bonds->add(el, i, j);
    ASSERT_GE(static_cast<long>(bonds->bonds().size()), kParallelMinItems);
    sys.add(std::make_unique<GrainDashpots>(0.5, bonds, m.youngs, 1.05));
    sys.run(150);
    std::printf("threads %d: dt %.4g ps, %zu of %zu bonds broken\n", run + 1, sys.dt(),
                bonds->broken_count(), bonds->bonds().size());
    EXPECT_GT(bonds->broken_count(), 0u);
    EXPECT_LT(bonds->broken_count(), bonds->bonds().size());
    x[run] = sys.elements().x;
    for (const auto& b : bonds->bonds()) broken[run].push_back(b.broken);
  }
  EXPECT_EQ(broken[0], broken[1]);
  double worst = 0;
  for (std::size_t i = 0; i < x[0].size(); ++i) worst = std::max(worst, (x[0][i] - x[1][i]).norm());
  EXPECT_LT(worst, 1e-9);
}

// ------------------------------------------------------------------------------------------
// 6. Checkpoints.

// A 3 × 3 × 3 cluster: bottom layer fixed, top layer pulled up and sideways, the middle free;
// dashpots and a little local damping, two threads.
std::unique_ptr<System> loaded_cluster(BondBehaviour behaviour) {
  const GrainMaterial m = behaviour == BondBehaviour::Plastic ? gold() : cadmium_sulfide();
  Cluster c = lattice_cluster(m, 3, 3, 3, 2.0, 5);
  auto sys = std::make_unique<System>(std::move(c.el), settings(0.1, 2));
  Elements& el = sys->elements();
  for (std::size_t i = 0; i < el.size(); ++i) {
    if (i < 9) el.fix_all(i);
    if (i >= 18) {
      el.dof[i].fill(DofMode::Fixed);
      for (int k = 0; k < 3; ++k) el.dof[i][k] = DofMode::Prescribed;
      el.v_prescribed[i] = Vec3(0.02, 0.0, 0.03);
    }
  }
  const double strength = behaviour == BondBehaviour::Plastic ? 8.0 : 4.0;
  auto* bonds = sys->add(std::make_unique<GrainBond>(params(m, behaviour, strength)));
  for (auto [i, j] : c.pairs) bonds->add(el, i, j);
  sys->add(std::make_unique<GrainDashpots>(0.5, bonds, m.youngs, 1.05));
  sys->initialize();
  return sys;
}

void expect_bit_identical_resume(BondBehaviour behaviour, long total, long stop) {
  auto full = loaded_cluster(behaviour);
  full->run(total);
  const GrainBond& fb = *full->find<GrainBond>();
  const std::size_t events_end =
      behaviour == BondBehaviour::Plastic ? fb.yielded_count() : fb.broken_count();

  std::string bytes;
  std::size_t events_at_stop = 0;
  {
    auto first = loaded_cluster(behaviour);
    first->run(stop);
    const GrainBond& b = *first->find<GrainBond>();
    events_at_stop = behaviour == BondBehaviour::Plastic ? b.yielded_count() : b.broken_count();
    StateWriter w;
    first->save_state(w);
    bytes = w.take();
  }
  // Partly yielded / broken at the stop, more after it.
  EXPECT_GT(events_at_stop, 0u);
  EXPECT_LT(events_at_stop, events_end);

  auto resumed = loaded_cluster(behaviour);
  StateReader r(bytes);
  resumed->load_state(r);
  r.expect_end();
  StateWriter again;
  resumed->save_state(again);
  EXPECT_EQ(again.bytes(), bytes);  // loading restores everything saving writes
  resumed->run(total - stop);

  const Elements& a = full->elements();
  const Elements& b = resumed->elements();
  EXPECT_TRUE(same_bits(a.x, b.x));
  EXPECT_TRUE(same_bits(a.q, b.q));
  EXPECT_TRUE(same_bits(a.v, b.v));
  EXPECT_TRUE(same_bits(a.w, b.w));
  EXPECT_TRUE(same_bits(a.f, b.f));
  EXPECT_TRUE(same_bits(a.t, b.t));
  const EnergyLedger &la = full->energy(), &lb = resumed->energy();
  EXPECT_EQ(std::memcmp(la.potential.stored.data(), lb.potential.stored.data(),
                        sizeof(la.potential.stored)),
            0);
  EXPECT_EQ(la.external_work, lb.external_work);
  EXPECT_EQ(la.dissipated, lb.dissipated);
  const auto& ba = fb.bonds();
  const auto& bb = resumed->find<GrainBond>()->bonds();
  ASSERT_EQ(ba.size(), bb.size());
  for (std::size_t k = 0; k < ba.size(); ++k) {
    EXPECT_EQ(ba[k].broken, bb[k].broken);
    EXPECT_EQ(ba[k].yielded, bb[k].yielded);
    EXPECT_EQ(std::memcmp(&ba[k].plastic_normal, &bb[k].plastic_normal, sizeof(double)), 0);
    EXPECT_EQ(std::memcmp(ba[k].plastic_shear.data(), bb[k].plastic_shear.data(), sizeof(Vec3)), 0);
  }
  std::printf("checkpoint (%s): %zu of %zu bonds at the stop, %zu at the end, balance error %.3g\n",
              behaviour == BondBehaviour::Plastic ? "yielded" : "broken", events_at_stop, ba.size(),
              events_end, full->energy_balance_error());
}

TEST(GrainBond, PlasticClusterResumesBitIdenticallyFromACheckpoint) {
  expect_bit_identical_resume(BondBehaviour::Plastic, 800, 160);
}

TEST(GrainBond, BrittleClusterResumesBitIdenticallyFromACheckpoint) {
  expect_bit_identical_resume(BondBehaviour::Brittle, 800, 230);
}

TEST(GrainBond, CheckpointOfAnotherBondSetIsRefused) {
  auto a = loaded_cluster(BondBehaviour::Brittle);
  a->run(10);
  StateWriter w;
  a->save_state(w);
  // Same elements and models, one bond fewer.
  const GrainMaterial m = cadmium_sulfide();
  Cluster c = lattice_cluster(m, 3, 3, 3, 2.0, 5);
  System b(std::move(c.el), settings(0.1, 2));
  auto* bonds = b.add(std::make_unique<GrainBond>(params(m, BondBehaviour::Brittle, 4.0)));
  for (std::size_t k = 1; k < c.pairs.size(); ++k)
    bonds->add(b.elements(), c.pairs[k].first, c.pairs[k].second);
  b.add(std::make_unique<GrainDashpots>(0.5, bonds, m.youngs, 1.05));
  StateReader r(w.bytes());
  try {
    b.load_state(r);
    ADD_FAILURE() << "loaded a checkpoint of another bond set";
  } catch (const CheckpointError& e) {
    EXPECT_NE(std::string(e.what()).find("bond count"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mdem
