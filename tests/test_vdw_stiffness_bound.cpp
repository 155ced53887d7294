// The vdW pair's rotational stiffness bound (vdw_rotational_stiffness, used by the critical step)
// against the true rotational stiffness: the 3×3 rotational blocks of the pair energy's Hessian
// by central finite differences of vdw_pair's energy under small rotations of the axes
// (independent of the bound's formula). docs/stability.md, "crossed overlapping tubes": the old
// estimate k_t r² was 8.4× below the true block on two crossing tubes.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>

#include "cnt_scene.h"
#include "mdem/force/contact/anisotropic_vdw.h"

namespace {

using namespace mdem;
using Mat3 = Eigen::Matrix3d;

const VdwParams kP{};
const double kT = kP.segment_length;

Vec3 rotated(const Vec3& b, const Vec3& phi) {
  const double a = phi.norm();
  return a == 0.0 ? b : Eigen::AngleAxisd(a, phi / a) * b;
}

// The true stiffness of a pair: the largest |eigenvalue| of each segment's rotational block and
// the largest singular value of the block coupling the two segments' rotations.
struct TrueStiffness {
  double own = 0, coupling = 0;
};

TrueStiffness finite_difference(const Vec3& x1, const Vec3& b1, const Vec3& x2, const Vec3& b2) {
  constexpr double h = 1e-4;  // rad
  const auto energy = [&](const Vec3& f1, const Vec3& f2) {
    return vdw_pair(kP, x1, rotated(b1, f1), x2, rotated(b2, f2)).energy;
  };
  // H_ij = ∂²U/∂φ_i∂φ_j over the 6 rotation coordinates (3 per segment, exponential map).
  Eigen::Matrix<double, 6, 6> H;
  const auto unit = [](int i, double s) {
    Eigen::Matrix<double, 6, 1> e = Eigen::Matrix<double, 6, 1>::Zero();
    e[i] = s;
    return e;
  };
  for (int i = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j) {
      double sum = 0;
      for (const double si : {1.0, -1.0})
        for (const double sj : {1.0, -1.0}) {
          const Eigen::Matrix<double, 6, 1> f = unit(i, si * h) + unit(j, sj * h);
          sum += si * sj * energy(f.head<3>(), f.tail<3>());
        }
      H(i, j) = H(j, i) = sum / (4 * h * h);
    }
  const auto largest = [](const Mat3& m) {
    return Eigen::SelfAdjointEigenSolver<Mat3>(m).eigenvalues().cwiseAbs().maxCoeff();
  };
  const Mat3 h12 = H.block<3, 3>(0, 3);
  return {std::max(largest(H.block<3, 3>(0, 0)), largest(H.block<3, 3>(3, 3))),
          Eigen::JacobiSVD<Mat3>(h12).singularValues()[0]};
}

// The smallest ratio of the old lever-arm estimate k_t r² to the true stiffness seen by check()
// (reported: below 1 where that estimate alone would have been unsafe).
double lever_arm_margin = 1e300;
double largest_truth = 0;  // the largest true stiffness check() saw (reported)

// Checks the bound on one configuration; returns bound / true (the margin).
double check(const std::string& what, const Vec3& x1, const Vec3& b1, const Vec3& x2,
             const Vec3& b2) {
  const double bound = vdw_rotational_stiffness(kP, x1, b1, x2, b2);
  const TrueStiffness t = finite_difference(x1, b1, x2, b2);
  // Finite-difference noise: ~1e-13 of the energy over h².
  const double noise = 1e-13 * (1.0 + std::abs(vdw_pair(kP, x1, b1, x2, b2).energy)) / 1e-8;
  EXPECT_GE(bound + noise, t.own) << what << ": R " << (x2 - x1).norm() << " b1·b2 " << b1.dot(b2);
  EXPECT_GE(bound + noise, t.coupling) << what << ": R " << (x2 - x1).norm();
  EXPECT_TRUE(std::isfinite(bound)) << what;
  const double truth = std::max(t.own, t.coupling);
  largest_truth = std::max(largest_truth, truth);
  if (truth > 0)
    lever_arm_margin = std::min(
        lever_arm_margin, vdw_pair_stiffness(kP, x1, b1, x2, b2) * kP.radius * kP.radius / truth);
  return truth > 0 ? bound / truth : std::numeric_limits<double>::infinity();
}

void report(const std::string& what, int n, double min_margin) {
  std::printf(
      "[vdw bound] %s: %d configurations, bound / true >= %.3g (k_t r² alone: >= %.3g), largest "
      "true %.4g eV/rad²\n",
      what.c_str(), n, min_margin, lever_arm_margin, largest_truth);
  lever_arm_margin = 1e300;
  largest_truth = 0;
}

// Two segments crossing at 90°, the second's centre moved along the first's normal through the
// first: coincident, deep overlap (linear branch), shallow overlap, equilibrium, far.
TEST(VdwStiffnessBound, CrossedSegmentsFromCoincidentToFar) {
  double margin = 1e300;
  int n = 0;
  for (const double R : {0.0, 0.05, 0.2, 0.5, 0.8, 1.0, 1.2, 1.35, 1.5, 1.7, 2.0, 3.0, 5.0}) {
    for (const Vec3& dir :
         {Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(0.6, 0.0, 0.8), Vec3(0.5, 0.5, 0.7)}) {
      const Vec3 x2 = R * dir.normalized();
      margin = std::min(margin, check("crossed", Vec3::Zero(), Vec3::UnitX(), x2, Vec3::UnitY()));
      ++n;
    }
  }
  report("crossed at 90 deg", n, margin);
}

// Parallel segments side by side and end to end (δ up to 1.714), from overlap to the cutoff.
TEST(VdwStiffnessBound, ParallelAndEndToEnd) {
  double margin = 1e300;
  int n = 0;
  for (double R = 0.1; R < 4 * kT; R += 0.137) {
    margin = std::min(margin, check("side by side", Vec3::Zero(), Vec3::UnitX(), R * Vec3::UnitZ(),
                                    Vec3::UnitX()));
    margin = std::min(
        margin, check("end to end", Vec3::Zero(), Vec3::UnitX(), R * Vec3::UnitX(), Vec3::UnitX()));
    margin = std::min(
        margin, check("tilted 10 deg", Vec3::Zero(), Vec3::UnitX(),
                      R * Vec3(0.3, 0, 1).normalized(), Vec3(std::cos(0.17), std::sin(0.17), 0)));
    n += 3;
  }
  report("parallel, end to end, tilted", n, margin);
}

// Random axes and centre lines at random distances, inside and outside the flip blend: deep and
// shallow overlap. Configurations within the finite-difference step of a kink of the model (the
// blend window's edge |b1·b2| = flip_blend, where δ's second derivative jumps, and D = d_min,
// where V'' does) are skipped.
TEST(VdwStiffnessBound, RandomConfigurations) {
  std::mt19937 rng(15);
  std::uniform_real_distribution<double> uni(-1.0, 1.0), dist(0.0, 4.2 * kT);
  const auto random_unit = [&] {
    Vec3 v;
    do v = Vec3(uni(rng), uni(rng), uni(rng));
    while (v.norm() < 0.1 || v.norm() > 1);
    return v.normalized();
  };
  double margin = 1e300;
  int n = 0;
  for (int k = 0; k < 600; ++k) {
    const Vec3 b1 = random_unit(), b2 = random_unit(), x2 = dist(rng) * random_unit();
    const double c = std::abs(b1.dot(b2));
    const double d = vdw_separation(VdwConstants(kP), x2, b1, b2);
    if (std::abs(c - kP.flip_blend) < 1e-3 || std::abs(d - kP.d_min) < 1e-2) continue;
    margin = std::min(margin, check("random", Vec3::Zero(), b1, x2, b2));
    ++n;
  }
  EXPECT_GT(n, 500);
  report("random", n, margin);
}

// The states of the crossing run of docs/stability.md (two 11-segment tubes crossing at 90° with
// coincident middle centres) at the step the old bound allowed (10.31 fs, the check off), every 5
// steps while the crossing segments pass through each other: every inter-tube pair in range.
TEST(VdwStiffnessBound, StatesOfTheCrossingRun) {
  Elements el;
  mdem::testing::add_crossing_tubes(el);
  IntegratorSettings s;
  s.threads = 1;
  s.dt = 0.01031;
  s.check_dt = false;
  System sys = mdem::testing::cnt_scene_system(std::move(el), s);
  sys.initialize();
  double margin = 1e300;
  int n = 0;
  for (int block = 0; block <= 12; ++block) {
    const Elements& e = sys.elements();
    for (std::size_t i = 0; i < 11; ++i)
      for (std::size_t j = 11; j < 22; ++j) {
        if ((e.x[j] - e.x[i]).norm() >= 4 * kT) continue;
        const double d = vdw_separation(VdwConstants(kP), e.x[j] - e.x[i], e.axis(i), e.axis(j));
        if (std::abs(d - kP.d_min) < 1e-2) continue;
        margin = std::min(margin, check("crossing run step " + std::to_string(5 * block), e.x[i],
                                        e.axis(i), e.x[j], e.axis(j)));
        ++n;
      }
    sys.run(5);
  }
  report("crossing run, steps 0-60", n, margin);
}

}  // namespace
