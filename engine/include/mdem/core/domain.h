#pragma once
// The simulation box: lower and upper corner and a periodic flag per axis. Every pair and distance
// computation of the engine takes its displacement from delta(), the minimum image along periodic
// axes and the plain difference along the others. The default domain is open on all three axes
// (no box): delta() is then exactly x_j − x_i, so scenes without a box behave as before.
#include <array>
#include <cmath>
#include <string>

#include "mdem/core/math.h"

namespace mdem {

class Domain {
 public:
  // Open on every axis.
  Domain() = default;
  // A box [lo, hi) with the given periodic axes. Throws std::invalid_argument when a corner is not
  // finite on a periodic axis or hi ≤ lo there (the other axes' corners are informative only).
  Domain(const Vec3& lo, const Vec3& hi, std::array<bool, 3> periodic);

  const Vec3& lo() const { return lo_; }
  const Vec3& hi() const { return hi_; }
  Vec3 length() const { return hi_ - lo_; }
  bool periodic(int axis) const { return periodic_[axis]; }
  bool any_periodic() const { return any_periodic_; }

  // Minimum-image displacement from x_i to x_j (x_j − x_i with whole box lengths removed along
  // periodic axes, so each periodic component lies in [−L/2, L/2]).
  Vec3 delta(const Vec3& xi, const Vec3& xj) const {
    Vec3 d = xj - xi;
    if (any_periodic_) {
      for (int a = 0; a < 3; ++a)
        if (periodic_[a]) d[a] -= length_[a] * std::nearbyint(d[a] * inv_length_[a]);
    }
    return d;
  }

  // The image of x_j nearest x_i: x_i + delta(x_i, x_j), but exactly x_j when no box length is
  // removed (so an open domain changes no bit). For bonded pairs, whose kinematics take both
  // positions.
  Vec3 image(const Vec3& xi, const Vec3& xj) const {
    if (!any_periodic_) return xj;
    Vec3 y = xj;
    for (int a = 0; a < 3; ++a)
      if (periodic_[a]) y[a] -= length_[a] * std::nearbyint((xj[a] - xi[a]) * inv_length_[a]);
    return y;
  }

  // x moved into [lo, hi) along the periodic axes (unchanged along the others).
  Vec3 wrap(const Vec3& x) const {
    Vec3 w = x;
    for (int a = 0; a < 3; ++a) {
      if (!periodic_[a]) continue;
      w[a] -= length_[a] * std::floor((x[a] - lo_[a]) * inv_length_[a]);
      if (w[a] >= hi_[a]) w[a] = lo_[a];  // rounding of a coordinate just below lo
    }
    return w;
  }

  // Empty when a pair search of this reach (nm) has a unique minimum image on every periodic axis
  // (box length ≥ 2·reach); otherwise a message naming the axis, its length and the minimum.
  std::string check_reach(double reach) const;

 private:
  Vec3 lo_ = Vec3::Zero(), hi_ = Vec3::Zero();
  Vec3 length_ = Vec3::Zero(), inv_length_ = Vec3::Zero();
  std::array<bool, 3> periodic_{false, false, false};
  bool any_periodic_ = false;
};

// The domain of a model no system has bound yet: open on every axis.
inline const Domain kOpenDomain{};

}  // namespace mdem
