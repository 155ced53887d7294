#include "mdem/integrate/spectrum.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/core/math.h"
#include "mdem/integrate/system.h"

namespace mdem {

namespace {

void check(const SpectrumSettings& s) {
  if (!(s.max_iterations >= 2 && s.max_iterations <= 10000))
    throw std::invalid_argument("spectrum: max_iterations = " + std::to_string(s.max_iterations) +
                                ": give a whole number of Lanczos steps from 2 to 10000");
  if (!(s.tolerance > 0 && s.tolerance < 1))
    throw std::invalid_argument("spectrum: tolerance = " + std::to_string(s.tolerance) +
                                ": give a relative residual in (0, 1)");
  if (!(s.displacement > 0 && s.displacement <= 0.01))
    throw std::invalid_argument("spectrum: displacement = " + std::to_string(s.displacement) +
                                ": give the difference quotient's largest move in (0, 0.01] nm");
}

// The mass-weighted coordinates of the free degrees of freedom: per element 6 entries, three
// translations (world axes, × √m) and three rotations (principal body axes, × √I_k); a masked
// entry (a degree of freedom that is not free) stays zero.
class Coordinates {
 public:
  explicit Coordinates(const Elements& el) : n_(el.size()), free_(6 * n_, 0.0) {
    R_.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) {
      R_[i] = el.q[i].toRotationMatrix();
      for (int k = 0; k < 3; ++k) free_[6 * i + k] = el.dof[i][k] == DofMode::Free ? 1.0 : 0.0;
      // A rotation is perturbed about body axes: only when all three world rotations are free.
      const bool rot = el.dof[i][3] == DofMode::Free && el.dof[i][4] == DofMode::Free &&
                       el.dof[i][5] == DofMode::Free;
      for (int k = 3; k < 6; ++k) free_[6 * i + k] = rot ? 1.0 : 0.0;
    }
  }
  std::size_t size() const { return 6 * n_; }
  void mask(std::vector<double>& v) const {
    for (std::size_t a = 0; a < v.size(); ++a) v[a] *= free_[a];
  }
  // World displacement and rotation vector of element i for mass-weighted coordinates u.
  Vec3 move(const Elements& el, const std::vector<double>& u, std::size_t i) const {
    return Vec3(u[6 * i], u[6 * i + 1], u[6 * i + 2]) / std::sqrt(el.mass[i]);
  }
  Vec3 turn(const Elements& el, const std::vector<double>& u, std::size_t i) const {
    const Vec3& I = el.inertia[i];
    const Vec3 b(u[6 * i + 3] / std::sqrt(I.x()), u[6 * i + 4] / std::sqrt(I.y()),
                 u[6 * i + 5] / std::sqrt(I.z()));
    return R_[i] * b;
  }
  // Mass-weighted generalised forces of the state displaced by h·u from (x0, q0): forces / √m,
  // and the torque corrected to the derivative along the rotation vector (τ − ½ φ × τ), in body
  // axes / √I.
  void forces(const Elements& el, const std::vector<double>& u, double h,
              std::vector<double>& g) const {
    for (std::size_t i = 0; i < n_; ++i) {
      const Vec3 f = el.f[i] / std::sqrt(el.mass[i]);
      const Vec3 phi = h * turn(el, u, i);
      const Vec3 tc = el.t[i] - 0.5 * phi.cross(el.t[i]);
      const Vec3 b = R_[i].transpose() * tc;
      const Vec3& I = el.inertia[i];
      g[6 * i] = f.x();
      g[6 * i + 1] = f.y();
      g[6 * i + 2] = f.z();
      g[6 * i + 3] = b.x() / std::sqrt(I.x());
      g[6 * i + 4] = b.y() / std::sqrt(I.y());
      g[6 * i + 5] = b.z() / std::sqrt(I.z());
    }
    mask(g);
  }
  // The step h that moves no element's point further than `largest` nm for unit vector u.
  double step(const Elements& el, const std::vector<double>& u, double largest) const {
    double m = 0;
    for (std::size_t i = 0; i < n_; ++i)
      m = std::max({m, move(el, u, i).norm(), turn(el, u, i).norm() * el.radius[i]});
    return m > 0 ? largest / m : largest;
  }

 private:
  std::size_t n_;
  std::vector<double> free_;
  std::vector<Mat3> R_;
};

double dot(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (std::size_t k = 0; k < a.size(); ++k) s += a[k] * b[k];
  return s;
}

// Lanczos on the system's state (x0, q0), which the caller restores.
SpectrumEstimate lanczos(System& sys, const SpectrumSettings& s, const std::vector<Vec3>& x0,
                         const std::vector<Quat>& q0) {
  Elements& el = sys.elements();
  const std::size_t n = el.size();
  const Coordinates c(el);
  SpectrumEstimate out;
  out.critical_dt = std::numeric_limits<double>::infinity();

  // K v by central differences: −(g(+h v) − g(−h v)) / 2h.
  std::vector<double> gp(c.size()), gm(c.size());
  const auto apply = [&](const std::vector<double>& v, std::vector<double>& w) {
    const double h = c.step(el, v, s.displacement);
    for (int side = 0; side < 2; ++side) {
      const double sh = side == 0 ? h : -h;
      for (std::size_t i = 0; i < n; ++i) {
        el.x[i] = x0[i] + sh * c.move(el, v, i);
        el.q[i] = (quat_exp(sh * c.turn(el, v, i)) * q0[i]).normalized();
      }
      sys.refresh();
      ++out.force_evaluations;
      c.forces(el, v, sh, side == 0 ? gp : gm);
    }
    for (std::size_t a = 0; a < w.size(); ++a) w[a] = -(gp[a] - gm[a]) / (2.0 * h);
  };

  std::vector<double> v(c.size()), v_prev(c.size(), 0.0), w(c.size());
  std::mt19937_64 rng(s.seed);
  std::normal_distribution<double> normal;
  for (double& e : v) e = normal(rng);
  c.mask(v);
  const double norm0 = std::sqrt(dot(v, v));
  if (norm0 > 0) {
    for (double& e : v) e /= norm0;
    std::vector<double> alpha, beta;  // T's diagonal, and its off-diagonal beta[k] below alpha[k]
    double b_prev = 0;
    for (int k = 0; k < s.max_iterations; ++k) {
      apply(v, w);
      const double a = dot(w, v);
      for (std::size_t e = 0; e < w.size(); ++e) w[e] -= a * v[e] + b_prev * v_prev[e];
      c.mask(w);
      const double b = std::sqrt(dot(w, w));
      alpha.push_back(a);
      // The largest Ritz value of T_k and its eigenvector's last component.
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig;
      const Eigen::VectorXd d = Eigen::Map<const Eigen::VectorXd>(alpha.data(), alpha.size());
      const Eigen::VectorXd sub = Eigen::Map<const Eigen::VectorXd>(beta.data(), beta.size());
      eig.computeFromTridiagonal(d, sub, Eigen::ComputeEigenvectors);
      const Eigen::Index top = alpha.size() - 1;  // eigenvalues in increasing order
      const double theta = eig.eigenvalues()(top);
      out.residual = b * std::abs(eig.eigenvectors()(top, top));
      out.iterations = k + 1;
      out.omega_max = std::sqrt(std::max(theta, 0.0));
      if (theta > 0 && out.residual <= s.tolerance * theta) {
        out.converged = true;
        break;
      }
      // An invariant subspace: T_k's spectrum is exact (round-off aside).
      if (!(b > 1e-14 * std::max(std::abs(theta), 1e-300))) {
        out.converged = true;
        break;
      }
      beta.push_back(b);
      b_prev = b;
      v_prev.swap(v);
      for (std::size_t e = 0; e < w.size(); ++e) v[e] = w[e] / b;
    }
  } else {
    out.converged = true;  // nothing free to vibrate
  }
  if (out.omega_max > 0) out.critical_dt = 2.0 / out.omega_max;
  return out;
}

SpectrumEstimate estimate(System& sys, const SpectrumSettings& s, const std::vector<Vec3>& x0,
                          const std::vector<Quat>& q0) {
  SpectrumEstimate out = lanczos(sys, s, x0, q0);
  if (!s.check_smoothness) return out;
  SpectrumSettings fine = s;
  fine.displacement = 0.1 * s.displacement;
  const SpectrumEstimate f = lanczos(sys, fine, x0, q0);
  out.omega_fine = f.omega_max;
  out.force_evaluations += f.force_evaluations;
  const double limit = std::max(100.0 * s.tolerance, 1e-6);
  out.smooth = std::abs(f.omega_max - out.omega_max) <= limit * std::max(out.omega_max, 1e-300);
  return out;
}

}  // namespace

SpectrumEstimate largest_frequency(System& sys, const SpectrumSettings& s) {
  check(s);
  if (!sys.initialized()) sys.initialize();
  Elements& el = sys.elements();
  const std::vector<Vec3> x0 = el.x;
  const std::vector<Quat> q0 = el.q;
  const auto restore = [&] {
    el.x = x0;
    el.q = q0;
    sys.refresh();
  };
  SpectrumEstimate out;
  try {
    out = estimate(sys, s, x0, q0);
  } catch (...) {
    // A displaced state the force loop refused (a non-finite force): back to the given state,
    // whose forces were finite, then the caller hears why.
    restore();
    throw;
  }
  restore();
  return out;
}

}  // namespace mdem
