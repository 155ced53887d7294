// The units table against independently derived SI numbers (model.md §1).
#include <gtest/gtest.h>

#include "mdem/core/cnt.h"
#include "mdem/core/units.h"
#include "mdem/integrate/system.h"

using namespace mdem;

TEST(Units, ConversionsOfModelMd) {
  EXPECT_NEAR(units::nNnm(1.0), 6.241509, 1e-6);       // 1 nN·nm in eV
  EXPECT_NEAR(1.0 / units::nN(1.0), 0.1602177, 1e-7);  // 1 eV/nm in nN
  EXPECT_NEAR(units::GPa(1.0), 6.241509, 1e-6);        // 1 GPa in eV/nm³
  // 1 amu = 1.66053907e-27 kg, not the proton mass (1.67262e-27 kg).
  EXPECT_NEAR(units::kAmuKg, 1.66053907e-27, 1e-35);
  // amu in eV·ps²/nm²: 1.66053907e-27 kg · (1e-9 m)² / (1e-12 s)² / 1.602176634e-19 J.
  EXPECT_NEAR(units::amu(1.0) / (1.66053907e-27 * 1e-18 / 1e-24 / 1.602176634e-19), 1.0, 1e-8);
  // A strain rate of 1e-7 /fs is 1e-4 /ps.
  EXPECT_NEAR(1e-7 * units::kPerFemtosecond, 1e-4, 1e-18);
  EXPECT_NEAR(units::kGramPerCm3InAmuPerNm3, 602.2140762, 1e-6);
  // Round trips.
  EXPECT_DOUBLE_EQ(units::to_nN(units::nN(3.7)), 3.7);
  EXPECT_DOUBLE_EQ(units::to_GPa(units::GPa(79.0)), 79.0);
}

TEST(Units, CntConstantsOfTable21) {
  // E = kn·T ≈ 1.03 TPa; G = ks·T ≈ 0.46 TPa; bending stiffness kn·I·T = 2.24e3 eV·nm.
  EXPECT_NEAR(units::to_GPa(cnt::kBondKn * cnt::kSegmentLength) / 1000.0, 1.03, 0.005);
  EXPECT_NEAR(units::to_GPa(cnt::kBondKs * cnt::kSegmentLength) / 1000.0, 0.46, 0.005);
  EXPECT_NEAR(cnt::kBondKn * cnt::kBondI * cnt::kSegmentLength, 2.24e3, 5.0);
  EXPECT_NEAR(cnt::kMassAmu, 220.5 * 12.0107, 0.5);  // 220.5 carbon atoms
}

TEST(Units, ConstantForceAccelerationInSi) {
  // 1 eV/nm on 1 amu for 1 ps: a = 1.602176634e-10 N / 1.66053907e-27 kg = 9.64853e16 m/s²
  // = 96.4853 nm/ps², so the element travels a/2 = 48.243 nm. Velocity Verlet is exact here.
  Elements el;
  ElementInit e;
  e.mass = units::amu(1.0);
  e.inertia = Vec3::Constant(units::amu(1.0));
  e.radius = 100.0;  // large, so the run guard's per-step travel check does not apply
  el.add(e);
  el.f_ext[0] = Vec3(1.0, 0, 0);
  IntegratorSettings s;
  s.dt = 0.001;
  System sys(std::move(el), s);
  sys.run(1000);
  const double a_si = 1.602176634e-19 / 1e-9 / 1.66053906660e-27;  // m/s²
  const double expected_nm = 0.5 * a_si * 1e9 * 1e-24;             // ½ a t² with t = 1 ps
  EXPECT_NEAR(sys.elements().x[0].x(), expected_nm, 1e-9 * expected_nm);
  EXPECT_NEAR(expected_nm, 48.2427, 1e-3);
  // All of the external work is kinetic energy.
  EXPECT_NEAR(sys.energy().external_work, sys.energy().kinetic(), 1e-9 * sys.energy().kinetic());
}

// kB T at room temperature: 25.85 meV at 300 K (8.617333e-5 eV/K).
TEST(Units, BoltzmannConstant) {
  EXPECT_NEAR(mdem::units::kBoltzmann, 8.617333262e-5, 1e-13);
  EXPECT_NEAR(mdem::units::kBoltzmann * 300.0, 0.0258520, 1e-6);
}
