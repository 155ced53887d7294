#pragma once
// Shape functions of the anisotropic van der Waals laws (model.md §4, §5), shared by the
// nanoparticle contacts: δ(θ) as a polynomial in u = cos²θ, the smoothstep cutoff f_c, and the
// two-power potential V(D) = 4ε(A D^−α − B D^−β) continued linearly (C¹) below D_min.
//
// The CNT–CNT contact (anisotropic_vdw.cpp) still carries its own copies of these (with a pow-free
// fast path for its exponents); switching it over to this header is left for later.
#include <array>

namespace mdem::vdw_shape {

// δ(θ) = 1 + Σ_{k=1..5} C_k [(−1)^{k−1} + cos 2kθ] (model.md §4). Since cos 2kθ = T_k(y) with
// y = cos 2θ = 2u − 1, u = cos²θ, δ is a degree-5 polynomial in y: no trigonometry per pair.
class DeltaPolynomial {
 public:
  explicit DeltaPolynomial(const std::array<double, 5>& C);
  // δ and dδ/du at u = cos²θ ∈ [0, 1].
  void operator()(double u, double& delta, double& ddelta_du) const {
    const double y = 2.0 * u - 1.0;
    const auto& a = a_;
    delta = a[0] + y * (a[1] + y * (a[2] + y * (a[3] + y * (a[4] + y * a[5]))));
    const double dy = a[1] + y * (2 * a[2] + y * (3 * a[3] + y * (4 * a[4] + y * 5 * a[5])));
    ddelta_du = 2.0 * dy;
  }
  double operator()(double u) const {
    double d, dd;
    (*this)(u, d, dd);
    return d;
  }
  // max over u ∈ [0, 1] of |dδ/du| / δ (sampled finely once): how fast D can change with the
  // angle, for the rotational stiffness bounds.
  double max_log_slope() const { return max_log_slope_; }
  // min over u ∈ [0, 1] of δ (1 for the published C, at θ = 90°).
  double min_delta() const { return min_delta_; }
  // δ = Σ_k a_k y^k, y = 2u − 1 (for vectorised copies of the polynomial).
  const std::array<double, 6>& coefficients() const { return a_; }

 private:
  std::array<double, 6> a_{};
  double max_log_slope_ = 0, min_delta_ = 1;
};

// f_c(R) = 1 − 3t² + 2t³ with t = (R − start)/width clamped to [0, 1]: 1 up to `start`, 0 from
// start + width on, C¹ in between.
struct SmoothstepCutoff {
  double start = 0, width = 1;
  void operator()(double R, double& fc, double& dfc) const {
    const double t = (R - start) / width;
    if (t <= 0.0) {
      fc = 1.0;
      dfc = 0.0;
    } else if (t >= 1.0) {
      fc = 0.0;
      dfc = 0.0;
    } else {
      fc = 1.0 - t * t * (3.0 - 2.0 * t);
      dfc = 6.0 * t * (t - 1.0) / width;
    }
  }
  // f_c''(R) (zero outside the ramp; the jumps at its ends are bounded, so this is a fine bound).
  double second(double R) const {
    const double t = (R - start) / width;
    return (t > 0.0 && t < 1.0) ? (12.0 * t - 6.0) / (width * width) : 0.0;
  }
  double end() const { return start + width; }
};

// V(D) = 4ε (A D^−α − B D^−β) for D ≥ d_min, V(d_min) + V'(d_min)(D − d_min) below.
class TwoPowerPotential {
 public:
  // Throws std::invalid_argument naming `what` and the field for ε ≤ 0, A or B ≤ 0,
  // α ≤ β or β ≤ 0, d_min ≤ 0 (or any non-finite value).
  TwoPowerPotential(const char* what, double epsilon, double A, double B, double alpha, double beta,
                    double d_min);
  void operator()(double d, double& v, double& dv) const {
    if (d >= d_min_) {
      power_law(d, v, dv);
    } else {
      v = v_min_ + dv_min_ * (d - d_min_);
      dv = dv_min_;
    }
  }
  double operator()(double d) const {
    double v, dv;
    (*this)(d, v, dv);
    return v;
  }
  // V''(max(d, d_min)): a pair on the linear branch still counts the stiffness of the branch it
  // leaves.
  double second(double d) const;
  // The minimum of V: D0 = (αA/(βB))^{1/(α−β)}.
  double minimum() const;
  double d_min() const { return d_min_; }

 private:
  void power_law(double d, double& v, double& dv) const;
  double four_eps_, A_, B_, alpha_, beta_, d_min_;
  double v_min_ = 0, dv_min_ = 0;
};

// Bound of |∂²U/∂R²| for U = f_c(R)·V(D(R)) with ∂D/∂R = a (constant along R):
// |f_c'' V| + 2|f_c' V'| a + |f_c V''| a², with V'' at max(D, d_min).
double radial_stiffness_bound(const SmoothstepCutoff& fc, const TwoPowerPotential& V, double R,
                              double d, double a);

}  // namespace mdem::vdw_shape
