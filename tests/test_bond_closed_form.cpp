// The parallel bond's closed-form kinematics (series near zero rotation, one atan2 beyond) against
// the textbook formulas built from math.h's quat_log and the matrix Jl⁻¹(θ): forces, torques and
// energies agree to round-off for relative rotations from 1e-9 rad to nearly π, on both sides of
// the series' switch at 0.1 rad.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "mdem/core/cnt.h"
#include "mdem/core/elements.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/scene/tube_builder.h"

namespace mdem {
namespace {

// model.md §3's bond by the header's formulas, with quat_log and so3_left_jacobian_inverse.
BondResult reference_eval(const Bond& b, const Vec3& xi, const Quat& qi, const Vec3& xj,
                          const Quat& qj) {
  const BondStiffness& s = b.k;
  const Vec3 ai = qi * b.ci, aj = qj * b.cj, ui = qi * b.ni, uj = qj * b.nj;
  const Vec3 m = ui + uj;
  const Vec3 n = m.normalized();
  const Vec3 g = (xj + aj) - (xi + ai);
  const Vec3 th = quat_log(qj * b.q_rel0.conjugate() * qi.conjugate());
  const double gn = g.dot(n), tn = th.dot(n);
  BondResult r;
  r.e_tension = 0.5 * s.kn_area * gn * gn;
  r.e_shear = 0.5 * s.ks_area * (g - gn * n).squaredNorm();
  r.e_bending = 0.5 * s.kn_inertia * (th - tn * n).squaredNorm();
  r.e_torsion = 0.5 * s.ks_polar * tn * tn;
  const Vec3 dU_dg = s.ks_area * g + (s.kn_area - s.ks_area) * gn * n;
  const Vec3 dU_dth = s.kn_inertia * th + (s.ks_polar - s.kn_inertia) * tn * n;
  const Vec3 dU_dn = (s.kn_area - s.ks_area) * gn * g + (s.ks_polar - s.kn_inertia) * tn * th;
  const Vec3 dU_dm = (dU_dn - n.dot(dU_dn) * n) / m.norm();
  const Mat3 jinv = so3_left_jacobian_inverse(th);
  r.fi = dU_dg;
  r.fj = -dU_dg;
  r.ti = ai.cross(dU_dg) - ui.cross(dU_dm) + jinv * dU_dth;
  r.tj = -aj.cross(dU_dg) - uj.cross(dU_dm) - jinv.transpose() * dU_dth;
  return r;
}

TEST(BondClosedForm, MatchesTextbookFormulasOverAllRotationAngles) {
  Elements el;
  el.add(cnt_segment(Vec3::Zero(), Quat::Identity(), 0, 0));
  el.add(cnt_segment(cnt::kSegmentLength * Vec3::UnitX(), Quat::Identity(), 0, 1));
  const Bond b = make_bond(el, 0, 1, cnt_bond_stiffness());
  std::mt19937_64 rng(7);
  std::normal_distribution<double> nd;
  auto unit = [&] { return Vec3(nd(rng), nd(rng), nd(rng)).normalized(); };
  int series = 0, closed = 0;
  // Angles of the relative rotation from 1e-9 rad to 3.1 rad, with points either side of 0.1.
  for (double angle :
       {1e-9, 1e-6, 1e-4, 1e-3, 0.01, 0.05, 0.0999, 0.1001, 0.2, 0.5, 1.0, 2.0, 3.1}) {
    for (int trial = 0; trial < 20; ++trial) {
      const Vec3 xi = el.x[0], xj = el.x[1] + 0.01 * unit();
      const Quat qi = quat_exp(0.3 * unit());
      const Quat qj = quat_exp(angle * unit()) * qi;  // |θ| = angle
      const BondResult r = bond_eval(b, xi, qi, xj, qj);
      const BondResult e = reference_eval(b, xi, qi, xj, qj);
      const double fscale = e.fi.norm() + e.ti.norm() + e.tj.norm();
      EXPECT_LE((r.fi - e.fi).norm(), 1e-12 * fscale) << angle;
      EXPECT_LE((r.ti - e.ti).norm(), 1e-12 * fscale) << angle;
      EXPECT_LE((r.tj - e.tj).norm(), 1e-12 * fscale) << angle;
      EXPECT_NEAR(r.energy(), e.energy(), 1e-12 * e.energy()) << angle;
      EXPECT_NEAR(r.e_bending + r.e_torsion, e.e_bending + e.e_torsion,
                  1e-12 * (e.e_bending + e.e_torsion))
          << angle;
      (angle < 0.1 ? series : closed)++;
    }
  }
  EXPECT_GT(series, 0);
  EXPECT_GT(closed, 0);
}

}  // namespace
}  // namespace mdem
