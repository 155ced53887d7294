// Shape functions of the anisotropic van der Waals laws (vdw_shape.h).
#include "mdem/force/contact/vdw_shape.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace mdem::vdw_shape {

DeltaPolynomial::DeltaPolynomial(const std::array<double, 5>& C) {
  // T[k][m]: coefficient of y^m in the Chebyshev polynomial T_k.
  std::array<std::array<double, 6>, 6> T{};
  T[0][0] = 1.0;
  T[1][1] = 1.0;
  for (int k = 2; k <= 5; ++k)
    for (int m = 0; m <= 5; ++m) T[k][m] = (m > 0 ? 2.0 * T[k - 1][m - 1] : 0.0) - T[k - 2][m];
  a_.fill(0.0);
  a_[0] = 1.0;
  for (int k = 1; k <= 5; ++k) {
    a_[0] += C[k - 1] * (k % 2 == 1 ? 1.0 : -1.0);
    for (int m = 0; m <= 5; ++m) a_[m] += C[k - 1] * T[k][m];
  }
  min_delta_ = 1e300;
  constexpr int kSamples = 2000;
  for (int s = 0; s <= kSamples; ++s) {
    double d, dd;
    (*this)(static_cast<double>(s) / kSamples, d, dd);
    if (!(d > 0)) throw std::invalid_argument("vdW shape: δ(θ) must stay positive");
    min_delta_ = std::min(min_delta_, d);
    max_log_slope_ = std::max(max_log_slope_, std::abs(dd) / d);
  }
}

TwoPowerPotential::TwoPowerPotential(const char* what, double epsilon, double A, double B,
                                     double alpha, double beta, double d_min)
    : four_eps_(4.0 * epsilon), A_(A), B_(B), alpha_(alpha), beta_(beta), d_min_(d_min) {
  auto require = [what](bool ok, const char* field, const char* allowed, double got) {
    if (!ok)
      throw std::invalid_argument(std::string(what) + " " + field + " must be " + allowed +
                                  ", got " + std::to_string(got));
  };
  require(std::isfinite(epsilon) && epsilon > 0, "epsilon", "finite and > 0 (eV)", epsilon);
  require(std::isfinite(A) && A > 0, "A", "finite and > 0", A);
  require(std::isfinite(B) && B > 0, "B", "finite and > 0", B);
  require(std::isfinite(beta) && beta > 0, "beta", "finite and > 0", beta);
  require(std::isfinite(alpha) && alpha > beta, "alpha", "finite and > beta", alpha);
  require(std::isfinite(d_min) && d_min > 0, "d_min", "finite and > 0", d_min);
  power_law(d_min_, v_min_, dv_min_);
}

void TwoPowerPotential::power_law(double d, double& v, double& dv) const {
  const double da = std::pow(d, -alpha_), db = std::pow(d, -beta_);
  v = four_eps_ * (A_ * da - B_ * db);
  dv = four_eps_ * (-alpha_ * A_ * da + beta_ * B_ * db) / d;
}

double TwoPowerPotential::second(double d) const {
  const double dc = std::max(d, d_min_);
  return four_eps_ * (alpha_ * (alpha_ + 1) * A_ * std::pow(dc, -alpha_ - 2) -
                      beta_ * (beta_ + 1) * B_ * std::pow(dc, -beta_ - 2));
}

double TwoPowerPotential::minimum() const {
  return std::pow(alpha_ * A_ / (beta_ * B_), 1.0 / (alpha_ - beta_));
}

double radial_stiffness_bound(const SmoothstepCutoff& fc, const TwoPowerPotential& V, double R,
                              double d, double a) {
  double f, df, v, dv;
  fc(R, f, df);
  V(d, v, dv);
  return std::abs(fc.second(R) * v) + 2.0 * std::abs(df * dv) * a +
         std::abs(f * V.second(d)) * a * a;
}

}  // namespace mdem::vdw_shape
