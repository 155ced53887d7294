#pragma once
// Small rigid-body helpers on Eigen types: rotation vectors, SO(3) Jacobians, skew matrices.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace mdem {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

// The part of r perpendicular to the unit vector n.
inline Vec3 perpendicular(const Vec3& r, const Vec3& n) { return r - r.dot(n) * n; }

inline Mat3 skew(const Vec3& a) {
  Mat3 s;
  s << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return s;
}

// Unit quaternion of the rotation by |phi| about phi/|phi| (exponential map), accurate for small
// and large angles alike.
inline Quat quat_exp(const Vec3& phi) {
  const double a = phi.norm();
  const double half = 0.5 * a;
  // sin(a/2)/a, with its Taylor series below 1e-4 to keep full precision.
  const double s = a < 1e-4 ? 0.5 - a * a / 48.0 : std::sin(half) / a;
  return Quat(std::cos(half), s * phi.x(), s * phi.y(), s * phi.z());
}

// Rotation vector of a unit quaternion (inverse of quat_exp), angle in [0, pi].
inline Vec3 quat_log(const Quat& q_in) {
  Quat q = q_in;
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // shortest rotation
  const Vec3 v = q.vec();
  const double sv = v.norm();
  const double angle = 2.0 * std::atan2(sv, q.w());
  // angle/sin(angle/2) -> 2 as sv -> 0.
  const double factor = sv < 1e-12 ? 2.0 / q.w() : angle / sv;
  return factor * v;
}

// Inverse of the left Jacobian of SO(3): if D' = exp(dphi) D then log(D') = log(D) + Jl^-1 dphi.
inline Mat3 so3_left_jacobian_inverse(const Vec3& theta) {
  const double a = theta.norm();
  const Mat3 k = skew(theta);
  double c;  // coefficient of k²: 1/a² - (1+cos a)/(2 a sin a)
  if (a < 1e-4) {
    c = 1.0 / 12.0 + a * a / 720.0;
  } else {
    c = 1.0 / (a * a) - (1.0 + std::cos(a)) / (2.0 * a * std::sin(a));
  }
  return Mat3::Identity() - 0.5 * k + c * k * k;
}

inline bool all_finite(const Vec3& v) { return v.allFinite(); }

}  // namespace mdem
