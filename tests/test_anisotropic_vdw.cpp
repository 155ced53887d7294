// Anisotropic CNT–CNT van der Waals contact (model.md §4): check values, the exact gradient,
// invariances, the tube-level adhesion and sliding, overlap and degenerate input, and the threaded
// force loop against a brute-force sum.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/neighbor/neighbor_list.h"

using namespace mdem;

namespace {

constexpr double kPi = 3.14159265358979323846;
// Most tests check the thesis's literal form (no blend across b1·b2 = 0); the default model
// differs from it only inside |b1·b2| < flip_blend (see DefaultBlendEqualsLiteralOutsideWindow).
const VdwParams kP = [] {
  VdwParams p;
  p.flip_blend = 0.0;
  return p;
}();
const double kT = kP.segment_length;
const double kR = kP.radius;

// Independent, literal evaluation of model.md §4 with acos, cos and pow.
double reference_energy(const VdwParams& p, const Vec3& x1, const Vec3& b1, const Vec3& x2,
                        Vec3 b2) {
  const Vec3 rv = x2 - x1;
  const double R = rv.norm();
  if (R >= 4 * p.segment_length) return 0.0;
  if (b1.dot(b2) < 0) b2 = -b2;
  const double gamma = std::acos(std::clamp(b1.dot(b2), -1.0, 1.0));
  const Vec3 b3 = (b1 + b2).normalized();
  const double theta = std::acos(std::clamp(b3.dot(rv / R), -1.0, 1.0));
  double delta = 1.0;
  for (int k = 1; k <= 5; ++k)
    delta += p.C[k - 1] * ((k % 2 ? 1.0 : -1.0) + std::cos(2 * k * theta));
  const double D = R / (p.radius * delta) - 2.0;
  auto lj = [&](double d) {
    return 4 * p.epsilon * (p.A * std::pow(d, -p.alpha) - p.B * std::pow(d, -p.beta));
  };
  auto dlj = [&](double d) {
    return 4 * p.epsilon *
           (-p.alpha * p.A * std::pow(d, -p.alpha - 1) + p.beta * p.B * std::pow(d, -p.beta - 1));
  };
  const double V = D >= p.d_min ? lj(D) : lj(p.d_min) + dlj(p.d_min) * (D - p.d_min);
  const double t = std::clamp(R / p.segment_length - 3.0, 0.0, 1.0);
  const double fc = 1 - 3 * t * t + 2 * t * t * t;
  const double rho = R / p.radius;
  const double W = 90.0 * std::pow(rho > 2.75 ? rho : 2.75, -7.5);
  const double M = 1 + W * (1 - std::cos(2 * gamma));
  return M * fc * V;
}

double energy(const VdwParams& p, const Vec3& x1, const Quat& q1, const Vec3& x2, const Quat& q2) {
  return vdw_pair(p, x1, q1 * Vec3::UnitX(), x2, q2 * Vec3::UnitX()).energy;
}

std::string sci(double v) {
  std::ostringstream o;
  o.precision(6);
  o << v;
  return o.str();
}

Vec3 random_unit(std::mt19937& g) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec3 v(n(g), n(g), n(g));
  return v.normalized();
}

Quat quat_of_axis(const Vec3& b, double spin) {
  return Quat::FromTwoVectors(Vec3::UnitX(), b) * Quat(Eigen::AngleAxisd(spin, Vec3::UnitX()));
}

// Unit vector at angle `ang` from a (in a random plane through a).
Vec3 tilt(const Vec3& a, double ang, std::mt19937& g) {
  Vec3 perp = random_unit(g);
  perp = (perp - perp.dot(a) * a).normalized();
  return std::cos(ang) * a + std::sin(ang) * perp;
}

double d_of(const VdwParams& p, const Vec3& x1, const Vec3& b1, const Vec3& x2, Vec3 b2) {
  if (b1.dot(b2) < 0) b2 = -b2;
  const Vec3 rv = x2 - x1;
  const double th = std::acos(std::clamp((b1 + b2).normalized().dot(rv.normalized()), -1.0, 1.0));
  return rv.norm() / (p.radius * vdw_delta(p, th)) - 2.0;
}

struct Config {
  Vec3 x1, x2;
  Quat q1, q2;
};

}  // namespace

// 1. The check values of model.md §4 (segment 1 at the origin, axis x).
TEST(AnisotropicVdw, CheckValuesOfModelMd) {
  const Vec3 o = Vec3::Zero(), ex = Vec3::UnitX();
  const double u1 = vdw_pair(kP, o, ex, Vec3(0, 1.734357, 0), ex).energy;
  const double u2 = vdw_pair(kP, o, ex, Vec3(0, 2.0, 0), ex).energy;
  const double u3 = vdw_pair(kP, o, ex, Vec3(0, 1.734357, 0), Vec3::UnitZ()).energy;
  EXPECT_NEAR(u1, -1.1677221, 1e-6 * 1.1677221);
  EXPECT_NEAR(u2, -0.2348774, 1e-6 * 0.2348774);
  EXPECT_NEAR(u3, -1.2742876, 1e-6 * 1.2742876);
  // (0, 1.734357, 0) is the pair minimum: no radial force there.
  const auto r = vdw_pair(kP, o, ex, Vec3(0, 1.734357, 0), ex);
  EXPECT_LT(r.f2.norm(), 1e-4);
}

// The default model is the literal one outside the blend window and at the check values, and its
// forces and torques are still the exact gradient inside it.
TEST(AnisotropicVdw, DefaultBlendEqualsLiteralOutsideWindow) {
  const VdwParams def;
  ASSERT_GT(def.flip_blend, 0.0);
  std::mt19937 g(17);
  std::uniform_real_distribution<double> Rd(0.8, 5.6);
  int inside = 0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3 x1 = random_unit(g), b1 = random_unit(g), b2 = random_unit(g);
    const Vec3 x2 = x1 + Rd(g) * random_unit(g);
    const double lit = vdw_pair(kP, x1, b1, x2, b2).energy;
    const double got = vdw_pair(def, x1, b1, x2, b2).energy;
    if (std::abs(b1.dot(b2)) >= def.flip_blend) {
      EXPECT_NEAR(got, lit, 1e-12 * std::max(1.0, std::abs(lit))) << k;
    } else {
      ++inside;
      // Inside the window: finite, and the force is minus the numerical gradient.
      const auto r = vdw_pair(def, x1, b1, x2, b2);
      const double h = 1e-6;
      for (int a = 0; a < 3; ++a) {
        Vec3 d = Vec3::Zero();
        d[a] = h;
        const double fd =
            -(vdw_pair(def, x1, b1, x2 + d, b2).energy - vdw_pair(def, x1, b1, x2 - d, b2).energy) /
            (2 * h);
        EXPECT_NEAR(r.f2[a], fd, 1e-5 * std::max(1.0, r.f2.norm())) << k;
      }
    }
  }
  EXPECT_GT(inside, 100);
}

// The u = cos²θ / Chebyshev algebra equals the literal acos/cos/pow formula everywhere.
TEST(AnisotropicVdw, EnergyMatchesLiteralFormula) {
  std::mt19937 g(7);
  std::uniform_real_distribution<double> Rd(0.3, 5.6);
  for (int k = 0; k < 500; ++k) {
    const Vec3 x1 = 3.0 * random_unit(g), b1 = random_unit(g), b2 = random_unit(g);
    const Vec3 x2 = x1 + Rd(g) * random_unit(g);
    const double ref = reference_energy(kP, x1, b1, x2, b2);
    const double got = vdw_pair(kP, x1, b1, x2, b2).energy;
    EXPECT_NEAR(got, ref, 1e-10 * std::max(1.0, std::abs(ref))) << k;
  }
}

// 2. δ, f_c and the C¹ continuation of V.
TEST(AnisotropicVdw, DeltaCutoffAndLinearBranch) {
  EXPECT_NEAR(vdw_delta(kP, kPi / 2), 1.0, 1e-12);
  EXPECT_NEAR(vdw_delta(kP, 0.0), 1.7141, 1e-4);
  EXPECT_NEAR(vdw_delta(kP, kPi), 1.7141, 1e-4);
  for (double th = 0; th <= kPi; th += 0.01) {
    double d = 1.0;
    for (int k = 1; k <= 5; ++k) d += kP.C[k - 1] * ((k % 2 ? 1.0 : -1.0) + std::cos(2 * k * th));
    EXPECT_NEAR(vdw_delta(kP, th), d, 1e-12);
    EXPECT_GE(vdw_delta(kP, th),
              1.0 - 1e-12);  // 90° is the smallest δ (used by the stiffness bound)
  }

  // f_c: continuous value and slope at 3T and 4T (so the force is continuous there too).
  const Vec3 o = Vec3::Zero(), ex = Vec3::UnitX(), ey = Vec3::UnitY();
  const double h = 1e-7;
  for (double Rk : {3 * kT, 4 * kT}) {
    const auto lo = vdw_pair(kP, o, ex, (Rk - h) * ey, ex);
    const auto hi = vdw_pair(kP, o, ex, (Rk + h) * ey, ex);
    EXPECT_NEAR(lo.energy, hi.energy, 1e-8);
    EXPECT_NEAR(lo.f2.y(), hi.f2.y(), 1e-6);
  }
  EXPECT_NEAR(vdw_pair(kP, o, ex, (4 * kT - 1e-4) * ey, ex).energy, 0.0, 1e-9);
  EXPECT_EQ(vdw_pair(kP, o, ex, (4 * kT + 1e-9) * ey, ex).energy, 0.0);
  // Below 3T f_c = 1: the energy is M·V(D) exactly.
  {
    const double Rt = 3 * kT - 0.01, D = Rt / kR - 2.0;
    const double W = 90.0 * std::pow(Rt / kR, -7.5);
    EXPECT_NEAR(vdw_pair(kP, o, ex, Rt * ey, Vec3::UnitZ()).energy,
                (1 + 2 * W) * vdw_potential(kP, D), 1e-14);
  }

  // V: C¹ at d_min, linear below it with the analytic slope of the published branch.
  const double dm = kP.d_min, e4 = 4 * kP.epsilon;
  const double v0 = e4 * (kP.A * std::pow(dm, -9.5) - kP.B * std::pow(dm, -4.0));
  const double s0 = e4 * (-9.5 * kP.A * std::pow(dm, -10.5) + 4.0 * kP.B * std::pow(dm, -5.0));
  EXPECT_NEAR(vdw_potential(kP, dm), v0, 1e-12 * std::abs(v0));
  const double eps = 1e-6;
  EXPECT_NEAR(vdw_potential(kP, dm - eps), vdw_potential(kP, dm + eps), 2.1 * eps * std::abs(s0));
  const double left = (vdw_potential(kP, dm) - vdw_potential(kP, dm - eps)) / eps;
  const double right = (vdw_potential(kP, dm + eps) - vdw_potential(kP, dm)) / eps;
  EXPECT_NEAR(left, s0, 1e-9 * std::abs(s0));
  EXPECT_NEAR(right, s0, 1e-3 * std::abs(s0));  // one-sided: O(ε V'') error
  EXPECT_NEAR(vdw_potential(kP, -1.5), v0 + s0 * (-1.5 - dm),
              1e-9 * std::abs(v0 + s0 * (-1.5 - dm)));
  EXPECT_GT(s0, 0.0 - 1e9);
  EXPECT_LT(s0, 0.0);  // repulsive: V decreases with D
}

// 3. Forces and torques are minus the finite-difference gradient of the energy.
TEST(AnisotropicVdw, ForcesAndTorquesAreTheExactGradient) {
  std::mt19937 g(2024);
  std::uniform_real_distribution<double> U01(0.0, 1.0);
  auto Rin = [&](double a, double b) { return a + (b - a) * U01(g); };
  std::vector<Config> cfgs;
  std::vector<int> kind;
  auto add = [&](const Vec3& x1, const Vec3& b1, const Vec3& x2, const Vec3& b2, int kd) {
    if (std::abs(b1.dot(b2)) < 2e-3 && kd != 4) return;  // away from the model's sign flip
    const double R = (x2 - x1).norm();
    if (std::abs(R / kR - kP.w_knee) < 1e-4) return;  // W(R) has a kink there (the model's)
    if (std::abs(d_of(kP, x1, b1, x2, b2) - kP.d_min) < 1e-4) return;  // V'' jumps at d_min
    cfgs.push_back({x1, x2, quat_of_axis(b1, Rin(0, 6)), quat_of_axis(b2, Rin(0, 6))});
    kind.push_back(kd);
  };
  for (int k = 0; k < 80; ++k) {  // generic
    const Vec3 x1 = random_unit(g), n = random_unit(g);
    add(x1, random_unit(g), x1 + Rin(1.2, 5.5) * n, random_unit(g), 0);
  }
  for (int k = 0; k < 40; ++k) {  // near-parallel, either sign of the axis
    const Vec3 b1 = random_unit(g);
    Vec3 b2 = tilt(b1, Rin(0, 1e-3), g);
    if (k % 2) b2 = -b2;
    const Vec3 x1 = random_unit(g);
    add(x1, b1, x1 + Rin(1.2, 5.5) * random_unit(g), b2, 1);
  }
  for (int k = 0; k < 40; ++k) {  // near-coaxial: centre line almost along b1
    const Vec3 b1 = random_unit(g);
    const Vec3 n = tilt(b1, Rin(0, 1e-3), g) * (k % 2 ? 1.0 : -1.0);
    const Vec3 b2 = k % 3 ? tilt(b1, Rin(0, 0.5), g) : random_unit(g);
    add(Vec3::Zero(), b1, Rin(1.2, 5.5) * n, b2, 2);
  }
  int overlapping = 0;
  for (int k = 0; k < 40; ++k) {  // crossing / overlapping, D < 0.4
    const Vec3 b1 = random_unit(g), b2 = random_unit(g);
    const Vec3 x1 = random_unit(g);
    const Vec3 x2 = x1 + Rin(k < 20 ? 0.05 : 1.2, 1.55) * random_unit(g);
    if (d_of(kP, x1, b1, x2, b2) < kP.d_min) ++overlapping;
    add(x1, b1, x2, b2, 3);
  }
  EXPECT_GE(overlapping, 35);
  for (int k = 0; k < 40; ++k) {  // near 90° crossings, |b1·b2| in [0.01, 0.05]
    const Vec3 b1 = random_unit(g);
    const Vec3 b2 = tilt(b1, kPi / 2 - (k % 2 ? 1 : -1) * Rin(0.01, 0.05), g);
    const Vec3 x1 = random_unit(g);
    add(x1, b1, x1 + Rin(1.2, 5.5) * random_unit(g), b2, 4);
  }
  ASSERT_GE(cfgs.size(), 200u);

  const double h = 1e-6;
  for (VdwTorque mode : {VdwTorque::Exact, VdwTorque::Pfc}) {
    VdwParams p = kP;
    p.torque = mode;
    double worst = 0;
    for (std::size_t c = 0; c < cfgs.size(); ++c) {
      const Config& C = cfgs[c];
      const auto r = vdw_pair(p, C.x1, C.q1 * Vec3::UnitX(), C.x2, C.q2 * Vec3::UnitX());
      const double scale = std::max({r.f1.norm(), r.t1.norm(), r.t2.norm(), 1e-3});
      Vec3 f1, f2, t1, t2;
      for (int a = 0; a < 3; ++a) {
        const Vec3 e = h * Vec3::Unit(a);
        f1[a] = -(energy(p, C.x1 + e, C.q1, C.x2, C.q2) - energy(p, C.x1 - e, C.q1, C.x2, C.q2)) /
                (2 * h);
        f2[a] = -(energy(p, C.x1, C.q1, C.x2 + e, C.q2) - energy(p, C.x1, C.q1, C.x2 - e, C.q2)) /
                (2 * h);
        t1[a] = -(energy(p, C.x1, quat_exp(e) * C.q1, C.x2, C.q2) -
                  energy(p, C.x1, quat_exp(-e) * C.q1, C.x2, C.q2)) /
                (2 * h);
        t2[a] = -(energy(p, C.x1, C.q1, C.x2, quat_exp(e) * C.q2) -
                  energy(p, C.x1, C.q1, C.x2, quat_exp(-e) * C.q2)) /
                (2 * h);
      }
      const double tol = 1e-6 * scale;
      EXPECT_LT((r.f1 - f1).norm(), tol) << "config " << c << " kind " << kind[c];
      EXPECT_LT((r.f2 - f2).norm(), tol) << "config " << c << " kind " << kind[c];
      worst = std::max({worst, (r.f1 - f1).norm() / scale, (r.f2 - f2).norm() / scale});
      if (mode == VdwTorque::Exact) {
        EXPECT_LT((r.t1 - t1).norm(), tol) << "config " << c << " kind " << kind[c];
        EXPECT_LT((r.t2 - t2).norm(), tol) << "config " << c << " kind " << kind[c];
        worst = std::max({worst, (r.t1 - t1).norm() / scale, (r.t2 - t2).norm() / scale});
      }
    }
    RecordProperty(mode == VdwTorque::Exact ? "worst_rel_exact" : "worst_rel_pfc_forces",
                   sci(worst));
  }
}

// 4. Momentum balance, and what the pfc option changes.
TEST(AnisotropicVdw, NewtonThirdLawAndPfcTorques) {
  std::mt19937 g(11);
  std::uniform_real_distribution<double> Rd(0.2, 5.3);
  VdwParams pfc = kP;
  pfc.torque = VdwTorque::Pfc;
  for (int k = 0; k < 300; ++k) {
    const Vec3 x1 = 2.0 * random_unit(g), b1 = random_unit(g), b2 = random_unit(g);
    const Vec3 x2 = x1 + Rd(g) * random_unit(g);
    const auto r = vdw_pair(kP, x1, b1, x2, b2);
    const double s = std::max({r.f1.norm(), r.t1.norm(), 1e-6});
    EXPECT_LT((r.f1 + r.f2).norm(), 1e-12 * s);
    EXPECT_LT((x1.cross(r.f1) + x2.cross(r.f2) + r.t1 + r.t2).norm(), 1e-11 * s) << k;
    const auto q = vdw_pair(pfc, x1, b1, x2, b2);
    EXPECT_EQ(q.energy, r.energy);
    EXPECT_LT((q.f1 - r.f1).norm(), 1e-12 * s);
    EXPECT_LT((q.f2 - r.f2).norm(), 1e-12 * s);
    // Pfc torque: only the aligning moment |∂U/∂γ| = f_c V · 2 W sin 2γ (M = 1 + W(1 − cos 2γ)),
    // about b1 × b2, equal and opposite on the two segments.
    const double R = (x2 - x1).norm();
    const double c = std::abs(b1.dot(b2)), gam = std::acos(std::min(c, 1.0));
    const double t = std::clamp(R / kT - 3.0, 0.0, 1.0);
    const double fc = 1 - 3 * t * t + 2 * t * t * t;
    const double W = 90.0 * std::pow(std::max(R / kR, 2.75), -7.5);
    const double Mg = 1 + W * (1 - std::cos(2 * gam));
    const double V = reference_energy(kP, x1, b1, x2, b2) / (Mg * fc);
    EXPECT_NEAR(q.t2.norm(), std::abs(fc * V * 2 * W * std::sin(2 * gam)), 1e-9 * s);
    EXPECT_LT((q.t1 + q.t2).norm(), 1e-12 * s);
    EXPECT_LT(std::abs(q.t2.dot(b1)) + std::abs(q.t2.dot(b2)), 1e-12 * s);
  }
  // θ depends on the axes: b1 = x, b2 at 30° in the xy plane, centre line at 45° in xy. The exact
  // torque includes the shear (θ) moment; pfc drops it.
  const Vec3 b1 = Vec3::UnitX(), b2(std::cos(0.5236), std::sin(0.5236), 0);
  const Vec3 x2 = 2.2 * Vec3(1, 1, 0.3).normalized();
  const auto e = vdw_pair(kP, Vec3::Zero(), b1, x2, b2);
  const auto q = vdw_pair(pfc, Vec3::Zero(), b1, x2, b2);
  EXPECT_GT((e.t1 - q.t1).norm(), 0.1 * e.t1.norm());
  EXPECT_GT((e.t1 - q.t1).norm(), 1e-2);
  // ... so pfc violates angular momentum balance there.
  EXPECT_GT((x2.cross(q.f2) + q.t1 + q.t2).norm(), 1e-2);
}

// 5. Invariances: axis sign, segment order, rigid motion.
TEST(AnisotropicVdw, Invariances) {
  std::mt19937 g(5);
  std::uniform_real_distribution<double> Rd(0.5, 5.3);
  for (int k = 0; k < 200; ++k) {
    const Vec3 x1 = random_unit(g), b1 = random_unit(g), b2 = random_unit(g);
    const Vec3 x2 = x1 + Rd(g) * random_unit(g);
    const auto r = vdw_pair(kP, x1, b1, x2, b2);
    const double tol = 1e-12 * std::max({1.0, std::abs(r.energy), r.f1.norm(), r.t1.norm()});
    for (const auto& [c1, c2] : {std::pair{-1.0, 1.0}, {1.0, -1.0}, {-1.0, -1.0}}) {
      const auto f = vdw_pair(kP, x1, c1 * b1, x2, c2 * b2);
      EXPECT_NEAR(f.energy, r.energy, tol);
      EXPECT_LT((f.f1 - r.f1).norm(), tol);
      EXPECT_LT((f.t1 - r.t1).norm(), tol);
      EXPECT_LT((f.t2 - r.t2).norm(), tol);
    }
    const auto s = vdw_pair(kP, x2, b2, x1, b1);
    EXPECT_NEAR(s.energy, r.energy, tol);
    EXPECT_LT((s.f1 - r.f2).norm(), tol);
    EXPECT_LT((s.t1 - r.t2).norm(), tol);
    EXPECT_LT((s.t2 - r.t1).norm(), tol);
    const Mat3 Q = quat_exp(3.0 * random_unit(g)).toRotationMatrix();
    const Vec3 d(10.3, -4.1, 7.7);
    const auto m = vdw_pair(kP, Q * x1 + d, Q * b1, Q * x2 + d, Q * b2);
    EXPECT_NEAR(m.energy, r.energy, 1e-11 * std::max(1.0, std::abs(r.energy)));
    EXPECT_LT((m.f1 - Q * r.f1).norm(), 1e-10 * std::max(1.0, r.f1.norm()));
    EXPECT_LT((m.t2 - Q * r.t2).norm(), 1e-10 * std::max(1.0, r.t2.norm()));
  }
}

namespace {
// Energy of a probe tube (n segments, axis x, first centre at (s, y, 0)) beside a straight
// 81-segment tube along x centred at the origin.
double beside_tube(double y, double s, int n_probe) {
  double e = 0;
  for (int i = 0; i < n_probe; ++i)
    for (int k = -40; k <= 40; ++k)
      e += vdw_pair(kP, Vec3(s + i * kT, y, 0), Vec3::UnitX(), Vec3(k * kT, 0, 0), Vec3::UnitX())
               .energy;
  return e;
}
// Golden-section minimum of beside_tube over y.
double min_spacing(double s, int n_probe, double* e_min) {
  double a = 1.55, b = 1.9;
  const double gr = (std::sqrt(5.0) - 1) / 2;
  double c = b - gr * (b - a), d = a + gr * (b - a);
  double fc = beside_tube(c, s, n_probe), fd = beside_tube(d, s, n_probe);
  while (b - a > 1e-6) {
    if (fc < fd) {
      b = d, d = c, fd = fc, c = b - gr * (b - a), fc = beside_tube(c, s, n_probe);
    } else {
      a = c, c = d, fc = fd, d = a + gr * (b - a), fd = beside_tube(d, s, n_probe);
    }
  }
  const double y = 0.5 * (a + b);
  *e_min = beside_tube(y, s, n_probe);
  return y;
}
}  // namespace

// 6. A segment beside an infinite parallel tube: minimum near 1.71 nm, about −2.19 eV/nm.
TEST(AnisotropicVdw, SegmentBesideInfiniteTube) {
  for (double s : {0.0, 0.5 * kT}) {
    double e;
    const double y = min_spacing(s, 1, &e);
    RecordProperty(s == 0 ? "y_min_aligned" : "y_min_staggered", sci(y));
    RecordProperty(s == 0 ? "e_per_nm_aligned" : "e_per_nm_staggered", sci(e / kT));
    EXPECT_GE(y, 1.70);
    EXPECT_LE(y, 1.72);
    EXPECT_NEAR(e / kT, -2.19, 0.02 * 2.19);
  }
}

// 7. Sliding along the tube: corrugation far below the adhesion energy.
TEST(AnisotropicVdw, SlidingCorrugationIsSmall) {
  for (int n_probe : {1, 10}) {
    double e0;
    const double y = min_spacing(0.0, n_probe, &e0);
    double lo = 1e300, hi = -1e300;
    for (int k = 0; k <= 40; ++k) {
      const double e = beside_tube(y, -0.5 * (n_probe - 1) * kT + k * kT / 40.0, n_probe);
      lo = std::min(lo, e);
      hi = std::max(hi, e);
    }
    RecordProperty(n_probe == 1 ? "corrugation_1" : "corrugation_10",
                   sci((hi - lo) / std::abs(e0)));
    EXPECT_LT(hi - lo, 0.01 * std::abs(e0)) << n_probe << " segments";
  }
}

// 8. Crossing and overlapping segments: finite, repulsive along the centre line.
TEST(AnisotropicVdw, CrossingTubesAreFiniteAndRepulsive) {
  std::mt19937 g(3);
  for (int k = 0; k < 200; ++k) {
    const Vec3 b1 = random_unit(g), b2 = random_unit(g), x1 = random_unit(g);
    const double R = k % 2 ? 0.1 : 1e-6;
    const Vec3 n = random_unit(g);
    const auto r = vdw_pair(kP, x1, b1, x1 + R * n, b2);
    ASSERT_TRUE(std::isfinite(r.energy));
    ASSERT_TRUE(r.f1.allFinite() && r.f2.allFinite() && r.t1.allFinite() && r.t2.allFinite());
    EXPECT_GT(r.energy, 100.0);     // deep in the linear repulsive branch
    EXPECT_GT(r.f2.dot(n), 100.0);  // pushes segment 2 away from segment 1
    EXPECT_LT(r.f2.norm(), 1e4);    // but finitely
  }
  // Exactly at the same centre.
  const auto r =
      vdw_pair(kP, Vec3(1, 2, 3), Vec3::UnitX(), Vec3(1, 2, 3), Vec3(0, 1, 1).normalized());
  EXPECT_TRUE(std::isfinite(r.energy));
  EXPECT_TRUE(r.t1.allFinite() && r.t2.allFinite());
}

// 9. Degenerate input: coincident centres and non-finite values (behaviour documented in the .cpp).
TEST(AnisotropicVdw, CoincidentCentresAndNonFiniteInput) {
  const Vec3 x(0.3, -0.2, 0.9), b1 = Vec3::UnitX();
  const Vec3 b2 = Vec3(1, 1, 0).normalized();  // γ = 45°
  const auto r = vdw_pair(kP, x, b1, x, b2);
  // D = −2 whatever θ: U = M(0, γ) · V(−2) on the linear branch; zero force; the aligning torque.
  const double W = 90.0 * std::pow(2.75, -7.5);
  const double M = 1 + W * (1 - std::cos(2 * kPi / 4));
  const double V = vdw_potential(kP, -2.0);
  EXPECT_NEAR(r.energy, M * V, 1e-12 * std::abs(M * V));
  EXPECT_EQ(r.f1.norm(), 0.0);
  EXPECT_EQ(r.f2.norm(), 0.0);
  EXPECT_NEAR(r.t2.norm(), std::abs(V * 2 * W * std::sin(2 * kPi / 4)), 1e-12 * std::abs(V));
  EXPECT_LT((r.t1 + r.t2).norm(), 1e-14);
  // The energy is continuous into R = 0 (and so is the torque); the force magnitude stays finite.
  const auto near = vdw_pair(kP, x, b1, x + Vec3(0, 0, 1e-9), b2);
  EXPECT_NEAR(near.energy, r.energy, 1e-5 * std::abs(r.energy));
  EXPECT_TRUE(near.f2.allFinite());
  EXPECT_LT(near.f2.norm(), 1e4);
  // A NaN propagates (so the system guard reports it instead of a silent zero).
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto bad = vdw_pair(kP, x, b1, Vec3(nan, 0, 0), b2);
  EXPECT_FALSE(std::isfinite(bad.energy) && bad.f1.allFinite());
  const auto bad_axis = vdw_pair(kP, x, b1, x + Vec3(0, 1.7, 0), Vec3(nan, 0, 0));
  EXPECT_FALSE(std::isfinite(bad_axis.energy) && bad_axis.t2.allFinite());
  // An infinitely distant segment is beyond the cutoff.
  const auto far = vdw_pair(kP, x, b1, Vec3(std::numeric_limits<double>::infinity(), 0, 0), b2);
  EXPECT_EQ(far.energy, 0.0);
  EXPECT_EQ(far.f1.norm(), 0.0);
}

// The stiffness bound used for the critical step dominates the actual radial curvature.
TEST(AnisotropicVdw, StiffnessBoundDominatesRadialCurvature) {
  std::mt19937 g(9);
  std::uniform_real_distribution<double> Rd(1.0, 5.5);
  const double h = 1e-4;
  int checked = 0;
  for (int k = 0; k < 400; ++k) {
    const Vec3 b1 = random_unit(g), b2 = random_unit(g), n = random_unit(g);
    const double R = Rd(g);
    auto U = [&](double RR) { return vdw_pair(kP, Vec3::Zero(), b1, RR * n, b2).energy; };
    const double curv = std::abs(U(R + h) - 2 * U(R) + U(R - h)) / (h * h);
    const double bound = vdw_pair_stiffness(kP, Vec3::Zero(), b1, R * n, b2);
    EXPECT_GE(bound, vdw_radial_stiffness(kP, R));
    if (std::abs(d_of(kP, Vec3::Zero(), b1, R * n, b2) - kP.d_min) < 1e-3) continue;
    if (std::abs(R / kR - kP.w_knee) < 1e-3) continue;
    EXPECT_GE(bound * (1 + 1e-6) + 1e-6, curv) << k << " R " << R;
    ++checked;
  }
  EXPECT_GT(checked, 350);
  // Side by side at the pair minimum: V''(D)/r² (M = 1 + 2W, f_c = 1 there).
  const double R0 = 1.734357, D0 = R0 / kR - 2;
  const double vpp = 4 * kP.epsilon *
                     (9.5 * 10.5 * kP.A * std::pow(D0, -11.5) - 4 * 5 * kP.B * std::pow(D0, -6.0));
  const double W0 = 90.0 * std::pow(2.75, -7.5);
  EXPECT_NEAR(vdw_radial_stiffness(kP, R0), (1 + 2 * W0) * vpp / (kR * kR), 1e-9 * vpp);
  EXPECT_EQ(vdw_radial_stiffness(kP, 4 * kT + 0.01), 0.0);
}

TEST(AnisotropicVdw, RejectsInvalidParameters) {
  VdwParams p = kP;
  p.flip_blend = 0.8;  // would let the blend's 1/(1 − |c|) diverge
  EXPECT_THROW(AnisotropicVdw{p}, std::invalid_argument);
  p = kP;
  p.radius = 0;
  EXPECT_THROW(AnisotropicVdw{p}, std::invalid_argument);
  p = kP;
  p.flip_blend = 0.5;
  EXPECT_NO_THROW(AnisotropicVdw{p});
}

TEST(AnisotropicVdw, Exclusions) {
  Elements el;
  auto seg = [&](int tube, int index, ElementKind kind = ElementKind::CntSegment) {
    ElementInit e;
    e.kind = kind;
    e.x = Vec3(el.size(), 0, 0);
    e.mass = 1;
    e.inertia = Vec3::Ones();
    e.radius = 0.678;
    e.tube = tube;
    e.index = index;
    return el.add(e);
  };
  const auto a0 = seg(0, 0), a5 = seg(0, 5), a20 = seg(0, 20), b3 = seg(1, 3);
  const auto np = seg(-1, -1, ElementKind::Nanoparticle);
  VdwParams p = kP;
  p.intra_tube_exclusion = 20;
  const AnisotropicVdw m(p);
  EXPECT_TRUE(m.excludes(el, a0, a5));
  EXPECT_FALSE(m.excludes(el, a0, a20));
  EXPECT_FALSE(m.excludes(el, a5, b3));
  EXPECT_TRUE(m.excludes(el, a0, np));
  EXPECT_TRUE(m.excludes(el, np, b3));
  p.intra_tube_exclusion = 0;
  EXPECT_FALSE(AnisotropicVdw(p).excludes(el, a0, a5));
}

// 10. The threaded loop over a neighbour list equals a brute-force pair sum (1 and 2 threads).
TEST(AnisotropicVdw, ComputeMatchesBruteForce) {
  Elements el;
  auto add_seg = [&](const Vec3& x, const Vec3& axis, int tube, int index,
                     ElementKind kind = ElementKind::CntSegment) {
    ElementInit e;
    e.kind = kind;
    e.x = x;
    e.q = Quat::FromTwoVectors(Vec3::UnitX(), axis);
    e.mass = 1;
    e.inertia = Vec3::Ones();
    e.radius = kind == ElementKind::CntSegment ? kR : 2.5;
    e.tube = tube;
    e.index = index;
    el.add(e);
  };
  // A ring of 24 segments (self-adhering across it with a small exclusion), two straight tubes
  // crossing it and each other, some random loose segments, and a nanoparticle in the middle.
  const int nring = 24;
  const double rad = nring * kT / (2 * kPi);
  for (int k = 0; k < nring; ++k) {
    const double a = 2 * kPi * k / nring;
    add_seg(Vec3(rad * std::cos(a), 0.8 * rad * std::sin(a), 0.3 * std::sin(3 * a)),
            Vec3(-std::sin(a), 0.8 * std::cos(a), 0.9 * std::cos(3 * a)).normalized(), 0, k);
  }
  for (int k = 0; k < 30; ++k) add_seg(Vec3(-20 + k * kT, 0.5, 1.7), Vec3::UnitX(), 1, k);
  for (int k = 0; k < 30; ++k)
    add_seg(Vec3(0.3, -20 + k * kT, -1.6), Vec3(0.2, 1, 0.1).normalized(), 2, k);
  std::mt19937 g(1);
  std::uniform_real_distribution<double> pos(-6, 6);
  for (int k = 0; k < 40; ++k) add_seg(Vec3(pos(g), pos(g), pos(g)), random_unit(g), 3 + k, 0);
  add_seg(Vec3(0, 0, 0), Vec3::UnitX(), -1, -1, ElementKind::Nanoparticle);
  const std::size_t n = el.size();

  VdwParams p = kP;
  p.intra_tube_exclusion = 4;
  const AnisotropicVdw model(p);

  // Brute force.
  std::vector<Vec3> fb(n, Vec3::Zero()), tb(n, Vec3::Zero());
  double eb = 0;
  int interacting = 0, intra = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      if (model.excludes(el, i, j)) continue;
      const auto r = vdw_pair(p, el.x[i], el.axis(i), el.x[j], el.axis(j));
      if (r.energy != 0) {
        ++interacting;
        if (el.tube[i] == el.tube[j]) ++intra;
      }
      eb += r.energy;
      fb[i] += r.f1;
      fb[j] += r.f2;
      tb[i] += r.t1;
      tb[j] += r.t2;
    }
  ASSERT_GT(interacting, 100);
  ASSERT_GT(intra, 10);

  for (bool list_excludes : {true, false}) {
    NeighborList nl(model.cutoff(), 0.3);
    // The list is shared by all pair models, so the model must also hold when it is not filtered.
    if (list_excludes)
      nl.set_exclusion(
          [&](const Elements& e, std::size_t i, std::size_t j) { return model.excludes(e, i, j); });
    nl.build(el);
    for (int threads : {1, 2}) {
      ForceSink sink;
      sink.resize(n, threads, false);
      sink.clear();
      model.compute(el, &nl, sink);
      std::vector<Vec3> f(n), t(n), fd, td;
      const EnergyTally e = sink.reduce(f, t, fd, td);
      EXPECT_NEAR(e.stored[static_cast<int>(EnergyTerm::Vdw)], eb, 1e-9 * std::abs(eb));
      EXPECT_NEAR(e.total_stored(), eb, 1e-9 * std::abs(eb));
      double df = 0, dt = 0, fs = 0;
      for (std::size_t i = 0; i < n; ++i) {
        df = std::max(df, (f[i] - fb[i]).norm());
        dt = std::max(dt, (t[i] - tb[i]).norm());
        fs = std::max(fs, fb[i].norm());
      }
      EXPECT_LT(df, 1e-10 * fs) << threads << " threads";
      EXPECT_LT(dt, 1e-10 * fs) << threads << " threads";
      EXPECT_EQ(f[n - 1].norm(), 0.0);  // the nanoparticle feels no CNT–CNT vdW
    }
    // Stiffness sums: every interacting pair contributes its bound to both elements.
    StiffnessSums s;
    s.reset(n);
    model.add_stiffness(el, &nl, s);
    std::vector<double> kt(n, 0.0), kr(n, 0.0);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j) {
        if (model.excludes(el, i, j)) continue;
        const double k = vdw_pair_stiffness(p, el.x[i], el.axis(i), el.x[j], el.axis(j));
        const double r = vdw_rotational_stiffness(p, el.x[i], el.axis(i), el.x[j], el.axis(j));
        EXPECT_GE(r, (1 - 1e-12) * k * kR * kR);  // never below the lever-arm estimate
        kt[i] += k;
        kt[j] += k;
        kr[i] += r;
        kr[j] += r;
      }
    for (std::size_t i = 0; i < n; ++i) {
      EXPECT_NEAR(s.kt[i], kt[i], 1e-9 * std::max(1.0, kt[i]));
      EXPECT_NEAR(s.kr[i], kr[i], 1e-9 * std::max(1.0, kr[i]));
    }
  }
}

namespace {
struct NveRun {
  double max_error = 0;  // max |E − E0| (eV)
  double drift = 0;      // E_end − E0 (eV)
  double min_abs_c = 1;  // smallest |b1·b2| met
  bool crossed = false;  // b1·b2 changed sign
  double max_R = 0;
};
// Symplectic run of two free (10,10) segments (isotropic inertia I = m r², so a free rotation is
// q ← exp(ω dt) q exactly): half kick, drift, half kick. They start at γ = 20°, side by side;
// the aligning moment turns them towards the crossed (lower-energy) pair, reaching γ = 90° after
// ~15 ps (literal model: crosses there; blended: turns back, crosses at ~37 ps and again later).
NveRun nve_run(VdwTorque mode, double blend, double dt, int steps) {
  VdwParams p = kP;
  p.torque = mode;
  p.flip_blend = blend;
  const double m = 2648.8 * 1.036426966e-2, I = m * kR * kR;  // eV·ps²/nm², eV·ps²
  Vec3 x[2] = {Vec3::Zero(), Vec3(0.3, 1.85, 0.2)};
  Quat q[2] = {
      Quat::Identity(),
      quat_of_axis(Vec3(std::cos(0.35), 0.3 * std::sin(0.35), 0.95 * std::sin(0.35)), 0.4)};
  Vec3 v[2] = {Vec3(0.01, -0.02, 0.0), Vec3(-0.01, 0.03, 0.02)};
  Vec3 w[2] = {Vec3(0.0, 0.01, 0.012), Vec3(-0.01, 0.0, 0.015)};
  Vec3 f[2], t[2];
  auto forces = [&]() {
    const auto r = vdw_pair(p, x[0], q[0] * Vec3::UnitX(), x[1], q[1] * Vec3::UnitX());
    f[0] = r.f1, f[1] = r.f2, t[0] = r.t1, t[1] = r.t2;
    return r.energy;
  };
  auto total = [&](double u) {
    double e = u;
    for (int a = 0; a < 2; ++a) e += 0.5 * m * v[a].squaredNorm() + 0.5 * I * w[a].squaredNorm();
    return e;
  };
  auto cos_gamma = [&]() { return (q[0] * Vec3::UnitX()).dot(q[1] * Vec3::UnitX()); };
  const double e0 = total(forces());
  const double c0 = cos_gamma();
  NveRun run;
  double e = e0;
  for (int s = 0; s < steps; ++s) {
    for (int a = 0; a < 2; ++a) {
      v[a] += 0.5 * dt / m * f[a];
      w[a] += 0.5 * dt / I * t[a];
      x[a] += dt * v[a];
      q[a] = (quat_exp(dt * w[a]) * q[a]).normalized();
    }
    const double u = forces();
    for (int a = 0; a < 2; ++a) {
      v[a] += 0.5 * dt / m * f[a];
      w[a] += 0.5 * dt / I * t[a];
    }
    e = total(u);
    run.max_error = std::max(run.max_error, std::abs(e - e0));
    run.min_abs_c = std::min(run.min_abs_c, std::abs(cos_gamma()));
    run.crossed = run.crossed || cos_gamma() * c0 < 0;
    run.max_R = std::max(run.max_R, (x[1] - x[0]).norm());
  }
  run.drift = e - e0;
  return run;
}
}  // namespace

// NVE with the exact torques: bounded, second-order energy error while the pair stays on one side
// of b1·b2 = 0 (10 ps: γ goes from 20° to ~50°).
TEST(AnisotropicVdw, ExactModeConservesEnergy) {
  const NveRun a = nve_run(VdwTorque::Exact, 0.0, 0.01, 1000);
  const NveRun b = nve_run(VdwTorque::Exact, 0.0, 0.005, 2000);
  RecordProperty("nve_err_dt10fs", sci(a.max_error));
  RecordProperty("nve_err_dt5fs", sci(b.max_error));
  ASSERT_GT(a.min_abs_c, 0.5);
  ASSERT_LT(a.max_R, 2.5);                     // a bound pair
  EXPECT_LT(a.max_error, 1e-3);                // eV, against a ~0.7 eV well
  EXPECT_LT(b.max_error, 0.35 * a.max_error);  // ~1/4: second order in dt
  EXPECT_LT(std::abs(a.drift), 1e-3);
}

// The literal model's b1·b2 = 0 discontinuity, and the flip_blend option that removes it.
TEST(AnisotropicVdw, SignFlipDiscontinuityAndBlend) {
  // Crossed pair, centre line with components along both axes (p1 p2 ≠ 0): U jumps across
  // γ = 90° by exactly the literal formula's jump.
  const Vec3 x2(0.6, 0.5, 1.75);
  const Vec3 b1 = Vec3::UnitX();
  auto b2_at = [](double c) { return Vec3(c, std::sqrt(1 - c * c), 0); };
  const double up = vdw_pair(kP, Vec3::Zero(), b1, x2, b2_at(1e-9)).energy;
  const double dn = vdw_pair(kP, Vec3::Zero(), b1, x2, b2_at(-1e-9)).energy;
  EXPECT_NEAR(up, reference_energy(kP, Vec3::Zero(), b1, x2, b2_at(1e-9)), 1e-10);
  EXPECT_NEAR(dn, reference_energy(kP, Vec3::Zero(), b1, x2, b2_at(-1e-9)), 1e-10);
  RecordProperty("literal_jump_eV", sci(up - dn));
  EXPECT_GT(std::abs(up - dn), 0.05);
  // Centre line perpendicular to an axis (stacked crossing): no jump.
  EXPECT_NEAR(vdw_pair(kP, Vec3::Zero(), b1, Vec3(0, 0.5, 1.75), b2_at(1e-9)).energy,
              vdw_pair(kP, Vec3::Zero(), b1, Vec3(0, 0.5, 1.75), b2_at(-1e-9)).energy, 1e-7);

  VdwParams bl = kP;
  bl.flip_blend = 0.2;
  // Continuous across c = 0 with the blend, literal outside the window.
  EXPECT_NEAR(vdw_pair(bl, Vec3::Zero(), b1, x2, b2_at(1e-9)).energy,
              vdw_pair(bl, Vec3::Zero(), b1, x2, b2_at(-1e-9)).energy, 1e-7);
  for (double c : {0.2, 0.35, -0.2, -0.6, 0.9}) {
    const auto r = vdw_pair(bl, Vec3::Zero(), b1, x2, b2_at(c));
    const auto l = vdw_pair(kP, Vec3::Zero(), b1, x2, b2_at(c));
    EXPECT_EQ(r.energy, l.energy);
    EXPECT_EQ(r.t2, l.t2);
  }
  // Exact gradient, Newton, zero total torque and axis-flip invariance inside the window.
  std::mt19937 g(17);
  std::uniform_real_distribution<double> U01(0.0, 1.0);
  const double h = 1e-6;
  for (int k = 0; k < 60; ++k) {
    const Vec3 a = random_unit(g);
    const Vec3 b = tilt(a, kPi / 2 + (2 * U01(g) - 1) * 0.19, g);
    const Vec3 x1 = random_unit(g), y2 = x1 + (1.2 + 4.3 * U01(g)) * random_unit(g);
    const Quat q1 = quat_of_axis(a, 0.3), q2 = quat_of_axis(b, 1.1);
    const auto r = vdw_pair(bl, x1, a, y2, b);
    const double scale = std::max({r.f1.norm(), r.t1.norm(), r.t2.norm(), 1e-3});
    Vec3 f2, t1, t2;
    for (int ax = 0; ax < 3; ++ax) {
      const Vec3 e = h * Vec3::Unit(ax);
      f2[ax] = -(energy(bl, x1, q1, y2 + e, q2) - energy(bl, x1, q1, y2 - e, q2)) / (2 * h);
      t1[ax] =
          -(energy(bl, x1, quat_exp(e) * q1, y2, q2) - energy(bl, x1, quat_exp(-e) * q1, y2, q2)) /
          (2 * h);
      t2[ax] =
          -(energy(bl, x1, q1, y2, quat_exp(e) * q2) - energy(bl, x1, q1, y2, quat_exp(-e) * q2)) /
          (2 * h);
    }
    EXPECT_LT((r.f2 - f2).norm(), 1e-6 * scale) << k;
    EXPECT_LT((r.t1 - t1).norm(), 1e-6 * scale) << k;
    EXPECT_LT((r.t2 - t2).norm(), 1e-6 * scale) << k;
    EXPECT_LT((r.f1 + r.f2).norm(), 1e-12 * scale);
    EXPECT_LT((x1.cross(r.f1) + y2.cross(r.f2) + r.t1 + r.t2).norm(), 1e-11 * scale);
    const auto fl = vdw_pair(bl, x1, -a, y2, b);
    const auto sw = vdw_pair(bl, y2, b, x1, -a);
    EXPECT_NEAR(fl.energy, r.energy, 1e-12 * std::max(1.0, std::abs(r.energy)));
    EXPECT_LT((fl.t2 - r.t2).norm(), 1e-12 * scale);
    EXPECT_NEAR(sw.energy, r.energy, 1e-12 * std::max(1.0, std::abs(r.energy)));
  }

  // Dynamics through γ = 90°: the literal model throws the pair apart (it gains tens of eV); with
  // the blend the energy is conserved.
  const NveRun lit = nve_run(VdwTorque::Exact, 0.0, 0.01, 4000);
  const NveRun blended = nve_run(VdwTorque::Exact, 0.2, 0.005, 16000);
  RecordProperty("nve_literal_through_90deg_eV", sci(lit.drift));
  RecordProperty("nve_blend_through_90deg_err_eV", sci(blended.max_error));
  EXPECT_TRUE(lit.crossed);
  EXPECT_GT(lit.drift, 1.0);
  EXPECT_TRUE(blended.crossed);
  EXPECT_LT(blended.max_error, 5e-3);  // vs 40 eV literal, a 0.7 eV well
}
