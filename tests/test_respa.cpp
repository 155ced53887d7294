// Multiple time stepping (r-RESPA, integrate/respa.h): k = 1 is the plain integrator bit for bit
// and a scene without slow models is unchanged by k; with k > 1 a vdW scene conserves energy (NVE)
// with a bounded error that grows as (k·dt)², the trajectory converges at second order in the
// outer step to a fine reference, the slow forces' critical step bounds the outer step, damping
// and local damping stay booked, checkpoints resume bit-identically, and bad values are refused.
#include <gtest/gtest.h>

#include <climits>
#include <cmath>

#include "mdem/core/cnt.h"
#include "mdem/core/limits.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/integrate/system.h"
#include "mdem/io/state_io.h"
#include "mdem/scene/tube_builder.h"
#include "mdem/spec.h"
#include "spec_support.h"
#include "step_scenes.h"
#include "support.h"

using namespace mdem;

namespace {

struct Scene {
  int k = 1;
  double dt = 0.005;           // ps
  bool vdw = true;             // the slow model
  bool dashpots = false;       // vdW contact dashpots (slow, with their pairs)
  double local_damping = 0.0;  // PFC local damping
  bool check_dt = true;
};

// Two bonded 12-segment (10,10) tubes side by side at the vdW contact distance (1.7 nm, a 3° angle
// and a stagger), with ~300 K random velocities and spins: the bonds' fast vibration and the
// slower motion in the vdW well.
System two_tubes(const Scene& sc) {
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 12, 0);
  add_straight_tube(el, Vec3(0.4, 1.7, 0.0), Vec3(1, 0.05, 0).normalized(), 12, 1);
  mdem::testing::thermal_kick(el, 7);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  IntegratorSettings s;
  s.dt = sc.dt;
  s.respa_k = sc.k;
  s.threads = 1;
  s.local_damping = sc.local_damping;
  s.check_dt = sc.check_dt;
  System sys(std::move(el), s);
  sys.add(std::move(bonds));
  if (sc.vdw) sys.add(std::make_unique<AnisotropicVdw>());
  if (sc.dashpots) sys.add(std::make_unique<ViscousContactDamping>(ContactDampingParams{}));
  return sys;
}

bool same_state(const System& a, const System& b) {
  const Elements &A = a.elements(), &B = b.elements();
  for (std::size_t i = 0; i < A.size(); ++i)
    if (A.x[i] != B.x[i] || A.v[i] != B.v[i] || A.w[i] != B.w[i] ||
        A.q[i].coeffs() != B.q[i].coeffs() || A.f[i] != B.f[i])
      return false;
  return a.energy().total() == b.energy().total() &&
         a.energy().external_work == b.energy().external_work &&
         a.energy().dissipated == b.energy().dissipated;
}

// Largest |E − E0| sampled at every outer step over `steps` inner steps, and E_end − E0 (eV).
struct Nve {
  double max_error = 0, drift = 0, e0 = 0;
};
Nve nve(int k, double dt, long steps) {
  System s = two_tubes({.k = k, .dt = dt});
  s.initialize();
  Nve r;
  r.e0 = s.energy().total();
  for (long n = 0; n < steps / k; ++n) {
    s.run(k);
    r.max_error = std::max(r.max_error, std::abs(s.energy().total() - r.e0));
  }
  r.drift = s.energy().total() - r.e0;
  return r;
}

// Largest position difference (nm) between two runs of the same scene at time T.
double position_error(const System& a, const System& b) {
  double e = 0;
  for (std::size_t i = 0; i < a.elements().size(); ++i)
    e = std::max(e, (a.elements().x[i] - b.elements().x[i]).norm());
  return e;
}

System run_for(int k, double dt, double T) {
  System s = two_tubes({.k = k, .dt = dt});
  s.run(std::lround(T / dt));
  return s;
}

}  // namespace

TEST(Respa, KOneIsThePlainIntegratorBitForBit) {
  // The option absent (default settings) and respa_k = 1 given: the same trajectory, damping and
  // books to the last bit, over a run that rebuilds the vdW sub-list.
  Scene sc{.dt = 0.01, .dashpots = true, .local_damping = 0.2};
  System absent = two_tubes(sc);
  IntegratorSettings s = absent.settings();
  ASSERT_EQ(s.respa_k, 1);  // the default
  System given = two_tubes({.k = 1, .dt = 0.01, .dashpots = true, .local_damping = 0.2});
  absent.run(3000);
  given.run(3000);
  EXPECT_TRUE(same_state(absent, given));
  EXPECT_GT(absent.energy().dissipated, 0.0);
}

TEST(Respa, WithoutSlowModelsAnyKIsThePlainIntegrator) {
  // Bonds only: nothing to split, so k = 4 must not change a bit (the slow impulse is zero).
  System a = two_tubes({.k = 1, .vdw = false});
  System b = two_tubes({.k = 4, .vdw = false});
  a.run(1001);
  b.run(1001);
  EXPECT_TRUE(same_state(a, b));
}

TEST(Respa, NveEnergyErrorIsBoundedAndGrowsAsTheOuterStepSquared) {
  // 20 ps at dt = 5 fs (a tenth of the critical step), E sampled at each outer step, against
  // 1.5 eV of kinetic and -9.6 eV of vdW energy. Plain Verlet (k = 1) has a bounded O(dt²) error
  // (measured 0.0173, 0.0042, 0.0011 eV at dt = 5, 2.5, 1.25 fs); r-RESPA adds a bounded error
  // of the slow impulses that grows as (k·dt)²: measured max |E - E0| = 0.024, 0.076, 0.36 eV
  // for k = 2, 4, 8 (0.0067 + 0.0043·k² fits k = 2, 4 and gives 0.28 for 8). Plain Verlet at the
  // outer step itself (dt = 20 fs) is worse than k = 4 at 5 fs: the split pays.
  const long steps = 4000;
  const Nve k1 = nve(1, 0.005, steps), k2 = nve(2, 0.005, steps), k4 = nve(4, 0.005, steps),
            k8 = nve(8, 0.005, steps);
  const Nve outer = nve(1, 0.02, steps / 4);
  RecordProperty("max_error_k1_eV", k1.max_error);
  RecordProperty("max_error_k2_eV", k2.max_error);
  RecordProperty("max_error_k4_eV", k4.max_error);
  RecordProperty("max_error_k8_eV", k8.max_error);
  RecordProperty("max_error_k1_dt20fs_eV", outer.max_error);
  EXPECT_LT(k1.max_error, 0.025);
  EXPECT_LT(k2.max_error, 0.035);
  EXPECT_LT(k4.max_error, 0.11);
  EXPECT_LT(k8.max_error, 0.5);
  // The part r-RESPA adds grows ~4x per doubling of k (second order in the outer step).
  const double r84 = k8.max_error / k4.max_error, r42 = k4.max_error / k2.max_error;
  EXPECT_GT(r84, 3.0);
  EXPECT_LT(r84, 6.0);
  EXPECT_GT(r42, 2.0);
  EXPECT_LT(r42, 6.0);
  EXPECT_LT(k4.max_error, outer.max_error);
}

TEST(Respa, TrajectoryConvergesAtSecondOrderInTheOuterStep) {
  // k = 4 at dt = 4, 2, 1 fs (outer step 16, 8, 4 fs) against plain Verlet at 0.25 fs, after 2 ps:
  // the position error falls 4× per halving of k·dt.
  const double T = 2.0;
  const System ref = run_for(1, 0.00025, T);
  const double e1 = position_error(run_for(4, 0.004, T), ref);
  const double e2 = position_error(run_for(4, 0.002, T), ref);
  const double e3 = position_error(run_for(4, 0.001, T), ref);
  const double p1 = std::log2(e1 / e2), p2 = std::log2(e2 / e3);
  RecordProperty("order_coarse", p1);
  RecordProperty("order_fine", p2);
  EXPECT_NEAR(p1, 2.0, 0.3);
  EXPECT_NEAR(p2, 2.0, 0.3);
  // Same inner step, outer step 4× larger: the split, not the inner step, is what the error is.
  const double e_k1 = position_error(run_for(1, 0.004, T), ref);
  EXPECT_LT(e_k1, e1);
}

TEST(Respa, OuterStepAboveTheSlowCriticalStepIsRefused) {
  System ok = two_tubes({.k = 2, .dt = 0.01});
  ok.initialize();
  const double outer_c = ok.critical_outer_dt();
  ASSERT_TRUE(std::isfinite(outer_c));
  EXPECT_GT(outer_c, ok.critical_dt());  // the vdW alone is softer than bonds + vdW
  // k·dt just above 0.6 × outer_c is refused, naming respa_k and the largest k allowed.
  const double dt = 0.01;
  const int k_bad = static_cast<int>(0.6 * outer_c / dt) + 1;
  ASSERT_LE(k_bad, mdem::limits::kMaxRespaK);
  System bad = two_tubes({.k = k_bad, .dt = dt});
  try {
    bad.initialize();
    FAIL() << "outer step " << k_bad * dt << " ps accepted";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_TRUE(mdem::testing::contains(m, "respa_k"));
    EXPECT_TRUE(mdem::testing::contains(m, "respa_k <= " + std::to_string(k_bad - 1))) << m;
  }
  // With the check off (stability studies) it is taken as given.
  System unchecked = two_tubes({.k = k_bad, .dt = dt, .check_dt = false});
  EXPECT_NO_THROW(unchecked.initialize());
}

TEST(Respa, BadKIsRefusedNamingTheFieldAndRange) {
  for (int k : {0, -1, 17, INT_MAX, INT_MIN}) {
    System s = two_tubes({.k = k});
    try {
      s.initialize();
      FAIL() << "respa_k " << k << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_TRUE(mdem::testing::contains(e.what(), "respa_k must be an integer in [1, 16]"))
          << e.what();
    }
  }
}

TEST(Respa, DampingAndLocalDampingStayBooked) {
  // Dashpots (slow, on the vdW pairs) and local damping at k = 4: the energy balance
  // W_ext = ΔE + E_diss closes at outer steps as well as at k = 1.
  for (int k : {1, 4}) {
    System s = two_tubes({.k = k, .dt = 0.005, .dashpots = true, .local_damping = 0.1});
    s.run(2000);
    EXPECT_GT(s.energy().dissipated, 0.0);
    EXPECT_LT(s.energy_balance_error(), 0.02) << "k = " << k;
    RecordProperty("balance_error_k" + std::to_string(k), s.energy_balance_error());
  }
}

TEST(Respa, CheckpointMidOuterStepResumesBitIdentically) {
  const Scene sc{.k = 4, .dt = 0.005, .dashpots = true, .local_damping = 0.1};
  System whole = two_tubes(sc);
  whole.run(1000);
  System first = two_tubes(sc);
  first.run(402);  // 402 % 4 = 2: inside an outer step
  StateWriter w;
  first.save_state(w);
  System resumed = two_tubes(sc);
  StateReader r(w.bytes());
  resumed.load_state(r);
  resumed.run(598);
  EXPECT_TRUE(same_state(whole, resumed));
  // A checkpoint of another split holds other forces: refused, naming respa_k.
  System other = two_tubes({.k = 2, .dt = 0.005, .dashpots = true, .local_damping = 0.1});
  StateReader r2(w.bytes());
  try {
    other.load_state(r2);
    FAIL() << "respa_k 4 checkpoint loaded into respa_k 2";
  } catch (const CheckpointError& e) {
    EXPECT_TRUE(mdem::testing::contains(e.what(), "respa_k")) << e.what();
  }
}

TEST(Respa, SpecAndFlagRefuseBadValues) {
  mdem::testing::expect_each_out_of_range_refused({{R"({"twist":{}, "run":{"respa_k":$}})",
                                                    "run.respa_k",
                                                    {"0", "17", "-1", "2147483647"},
                                                    ">= 1 and <= 16",
                                                    false}});
  EXPECT_EQ(mdem::testing::finalized_json(R"({"twist":{}})").run().respa_k(), 1);
  for (const char* bad : {"0", "17", "nan", "inf", "2.5", "99999999999", ""}) {
    const mdem::testing::CliResult r =
        mdem::testing::run_job("twist", {"--layers", "2", "--length", "5", "--respa-k", bad});
    EXPECT_NE(r.code, 0) << bad;
    EXPECT_TRUE(mdem::testing::contains(r.err, "respa")) << bad << ": " << r.err;
  }
}
