// Anisotropic CNT–CNT van der Waals contact (model.md §4).
//
// Variables. r = x2 − x1, R = |r|, n = r/R, c = b1·b2, s = sign(c) (+1 for c = 0), so s·b2 is the
// flipped axis with b1·(s b2) = |c| = cos γ. With p1 = b1·n, p2 = b2·n:
//   cos θ = b3·n = (p1 + s p2)/|b1 + s b2|,   u = cos²θ = (p1 + s p2)² / (2(1 + |c|)),
//   cos 2θ = 2u − 1 = y,   cos 2kθ = T_k(y) (Chebyshev), so δ is a degree-5 polynomial in y;
//   1 − cos 2γ = 2(1 − c²).
// U is then a smooth function U(R, c, p1, p2) (the denominator 2(1 + |c|) ≥ 2 never vanishes, so
// near-parallel, near-coaxial and crossed pairs need no special case), and
//   dU/dr  = U_R n + (U_p1 (b1 − p1 n) + U_p2 (b2 − p2 n)) / R,   F1 = +dU/dr, F2 = −dU/dr,
//   dU/db1 = U_c b2 + U_p1 n,  dU/db2 = U_c b1 + U_p2 n,            τ_i = −b_i × dU/db_i
// (a rotation δφ moves an axis by δb = δφ × b, so δU = δφ · (b × dU/db)). These forces and torques
// are the exact gradient of U: an undamped run conserves energy, and x1×F1 + x2×F2 + τ1 + τ2 = 0.
//
// The flip s is piecewise constant. Where b1·b2 changes sign, u jumps from (p1+p2)²/(2(1+|c|)) to
// (p1−p2)²/(2(1+|c|)) unless p1 p2 = 0 (centre line perpendicular to an axis) — so U itself is
// discontinuous across b1·b2 = 0. That is a property of the published model (its θ uses
// b3 = (b1+b2)/|b1+b2| with the flipped b2), not of this implementation, and by default we keep it
// literal. The jump can be large: two free segments crossing at R ≈ 1.8 nm that rotate through
// γ = 90° can gain tens of eV (see the NVE test), so an undamped run is energy-conserving only
// while no pair crosses that plane. VdwParams::flip_blend > 0 replaces u inside |c| < flip_blend by
// a C¹ smoothstep blend of the two signed values (unchanged outside the window), which removes the
// jump and keeps every invariance.
//
// Pfc mode (VdwTorque::Pfc) is Table 2-3 taken literally: the same translational forces (the radial
// force −∂U/∂R n and the shear force −(1/R)∂U/∂θ are together exactly −dU/dr), but the only torque
// is the aligning moment −∂U/∂γ from M's γ dependence, τ1 = −b1 × (∂U/∂c|_M b2), τ2 = −b2 ×
// (∂U/∂c|_M b1). The torque from θ's dependence on the axes is dropped, so that law is not
// conservative under rotation (and the total angular momentum of an isolated pair drifts).
//
// Coincident centres (R < 1e-12 nm): D = −2 whatever θ, so U = M f_c V(−2) is well defined, but its
// gradient in r is a cone (direction-dependent); we return U, zero force, and the aligning torque
// of M (the only part of the gradient that exists). As soon as the centres separate the linear
// overlap branch pushes them apart with a finite force.
// Non-finite input: vdw_pair assumes finite positions and unit axes. A NaN propagates into the
// result (so the system's guard reports it); an infinite separation reads as beyond the cutoff.
#include "mdem/force/contact/anisotropic_vdw.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "force/contact/vdw_simd.h"

namespace mdem {

namespace {

constexpr double kCoincident2 = 1e-24;  // R² below which the centres count as coincident (nm²)

// V(D) and V'(D) on the Lennard-Jones-like branch.
inline void lj(const VdwConstants& k, double d, double& v, double& dv) {
  const VdwParams& p = k.p;
  double da, db;  // D^-α, D^-β
  const double inv = 1.0 / d;
  if (k.fast_lj) {
    const double inv2 = inv * inv;
    const double inv4 = inv2 * inv2;
    db = inv4;
    da = inv4 * inv4 * std::sqrt(inv2 * inv);  // D^-8 · D^-1.5
  } else {
    da = std::pow(d, -p.alpha);
    db = std::pow(d, -p.beta);
  }
  v = k.four_eps * (p.A * da - p.B * db);
  dv = k.four_eps * (-p.alpha * p.A * da + p.beta * p.B * db) * inv;
}

inline double lj_second(const VdwParams& p, double four_eps, double d) {
  return four_eps * (p.alpha * (p.alpha + 1) * p.A * std::pow(d, -p.alpha - 2) -
                     p.beta * (p.beta + 1) * p.B * std::pow(d, -p.beta - 2));
}

// V(D), V'(D) with the linear (C¹) continuation below d_min.
inline void potential(const VdwConstants& k, double d, double& v, double& dv) {
  if (d >= k.p.d_min) {
    lj(k, d, v, dv);
  } else {
    v = k.v_dmin + k.dv_dmin * (d - k.p.d_min);
    dv = k.dv_dmin;
  }
}

// δ and dδ/du as functions of u = cos²θ.
inline void delta_of_u(const VdwConstants& k, double u, double& delta, double& ddelta_du) {
  const double y = 2.0 * u - 1.0;
  const auto& a = k.delta_poly;
  delta = a[0] + y * (a[1] + y * (a[2] + y * (a[3] + y * (a[4] + y * a[5]))));
  const double dy = a[1] + y * (2 * a[2] + y * (3 * a[3] + y * (4 * a[4] + y * 5 * a[5])));
  ddelta_du = 2.0 * dy;
}

// Smoothstep cutoff f_c(R) and its derivative.
inline void cutoff_fn(const VdwConstants& k, double R, double& fc, double& dfc) {
  const double t = R * k.inv_T - 3.0;
  if (t <= 0.0) {
    fc = 1.0;
    dfc = 0.0;
  } else if (t >= 1.0) {
    fc = 0.0;
    dfc = 0.0;
  } else {
    fc = 1.0 - t * t * (3.0 - 2.0 * t);
    dfc = 6.0 * t * (t - 1.0) * k.inv_T;
  }
}

// W(R) and W'(R), given 1/R.
inline void w_of_r(const VdwConstants& k, double R, double inv_R, double& w, double& dw) {
  const VdwParams& p = k.p;
  const double rho = R * k.inv_r;
  if (rho > p.w_knee) {
    if (k.fast_w) {
      const double inv = p.radius * inv_R;  // 1/ρ
      const double inv2 = inv * inv;
      const double inv4 = inv2 * inv2;
      w = p.w_prefactor * inv4 * inv2 * std::sqrt(inv2 * inv);  // ρ^-6 · ρ^-1.5
    } else {
      w = p.w_prefactor * std::pow(rho, -p.w_exponent);
    }
    dw = -p.w_exponent * w * inv_R;
  } else {
    w = k.w_knee_value;
    dw = 0.0;
  }
}

// u = cos²θ of one flip sign s and its partial derivatives in (p1, p2, c).
struct CosTheta2 {
  double u, u_p1, u_p2, u_c;
};
[[gnu::always_inline]] inline CosTheta2 cos_theta2_signed(double s, double c, double p1,
                                                          double p2) {
  const double q = p1 + s * p2;
  const double inv_h = 0.5 / (1.0 + s * c);  // 1/|b1 + s b2|² (≥ 1/4 for unit axes)
  const double u = q * q * inv_h;
  const double u_p1 = 2.0 * q * inv_h;
  return {u, u_p1, s * u_p1, -2.0 * s * u * inv_h};
}

// u = cos²θ of the model (s = sign(c)), or, when |c| < blend, the C¹ blend
// u = w(c) u₊ + (1 − w(c)) u₋ with the smoothstep w from 0 at c = −blend to 1 at c = +blend.
// w(−c) = 1 − w(c) and u₊(−c, −p2) = u₋(c, p2), so the blend keeps U even in each axis.
[[gnu::always_inline]] inline CosTheta2 cos_theta2(const VdwConstants& k, double c, double p1,
                                                   double p2) {
  const double blend = k.p.flip_blend;
  if (!(std::abs(c) < blend)) return cos_theta2_signed(c < 0.0 ? -1.0 : 1.0, c, p1, p2);
  const CosTheta2 a = cos_theta2_signed(1.0, c, p1, p2), b = cos_theta2_signed(-1.0, c, p1, p2);
  const double t = 0.5 * (c + blend) / blend;
  const double w = t * t * (3.0 - 2.0 * t);
  const double dw = 3.0 * t * (1.0 - t) / blend;  // dw/dc
  return {b.u + w * (a.u - b.u), b.u_p1 + w * (a.u_p1 - b.u_p1), b.u_p2 + w * (a.u_p2 - b.u_p2),
          b.u_c + w * (a.u_c - b.u_c) + dw * (a.u - b.u)};
}

// rv = x2 − x1 (the minimum image in a periodic domain). Returns false (and leaves out untouched)
// beyond the cutoff.
[[gnu::always_inline]] inline bool eval_pair(const VdwConstants& k, const Vec3& rv, const Vec3& b1,
                                             const Vec3& b2, VdwPairResult& out) {
  const double R2 = rv.squaredNorm();
  if (R2 >= k.cutoff2) return false;  // (a NaN fails this test and propagates below)
  const double c = b1.dot(b2);
  const double one_minus_c2 = 1.0 - c * c;

  double w, dw;
  if (R2 < kCoincident2) {
    // Coincident centres: D = −2 for every θ (see the file comment).
    w_of_r(k, 0.0, 0.0, w, dw);
    double v, dv;
    potential(k, -2.0, v, dv);
    const double M = 1.0 + 2.0 * w * one_minus_c2;
    out.energy = M * v;
    const double uc = -4.0 * w * c * v;  // ∂U/∂c through M
    const Vec3 b12 = b1.cross(b2);
    out.t1 = -uc * b12;
    out.t2 = uc * b12;
    return true;
  }

  const double R = std::sqrt(R2);
  const double inv_R = 1.0 / R;
  const Vec3 n = rv * inv_R;
  const double p1 = b1.dot(n), p2 = b2.dot(n);
  const CosTheta2 ct = cos_theta2(k, c, p1, p2);

  double delta, ddelta_du;
  delta_of_u(k, ct.u, delta, ddelta_du);
  const double inv_delta = 1.0 / delta;
  const double d = R * k.inv_r * inv_delta - 2.0;
  double v, dv;
  potential(k, d, v, dv);
  double fc, dfc;
  cutoff_fn(k, R, fc, dfc);
  w_of_r(k, R, inv_R, w, dw);
  const double M = 1.0 + 2.0 * w * one_minus_c2;
  out.energy = M * fc * v;

  const double mfc = M * fc;
  const double dM_dR = 2.0 * dw * one_minus_c2;
  const double dM_dc = -4.0 * w * c;
  // ∂U/∂R at fixed (c, p1, p2); ∂D/∂R = 1/(r δ).
  const double U_R = (dM_dR * fc + M * dfc) * v + mfc * dv * k.inv_r * inv_delta;
  // ∂U/∂u through δ; ∂D/∂δ = −R/(r δ²) = −(D + 2)/δ, with D + 2 = R/(r δ) as such (D + 2 would
  // cancel to a few digits as R → 0, where D → −2).
  const double U_u = -mfc * dv * (R * k.inv_r * inv_delta) * inv_delta * ddelta_du;
  const double U_p1 = U_u * ct.u_p1;
  const double U_p2 = U_u * ct.u_p2;
  const double U_cM = dM_dc * fc * v;  // through M (γ) only
  const double U_c = U_cM + U_u * ct.u_c;

  const Vec3 g = U_R * n + ((U_p1 * b1 + U_p2 * b2) - (U_p1 * p1 + U_p2 * p2) * n) * inv_R;
  out.f1 = g;
  out.f2 = -g;
  const Vec3 b12 = b1.cross(b2);
  if (k.p.torque == VdwTorque::Exact) {
    out.t1 = -U_c * b12 - U_p1 * b1.cross(n);
    out.t2 = U_c * b12 - U_p2 * b2.cross(n);
  } else {
    out.t1 = -U_cM * b12;
    out.t2 = U_cM * b12;
  }
  return true;
}

// Bound of |∂²U/∂R²| at centre distance R, given δ, with γ = 90° (largest M).
double radial_bound(const VdwConstants& k, double R, double delta) {
  const VdwParams& p = k.p;
  if (!(R < p.cutoff())) return 0.0;
  const double a = k.inv_r / delta;  // ∂D/∂R
  const double d = R * a - 2.0;
  const double dc = std::max(d, p.d_min);
  double v, dv;
  potential(k, d, v, dv);
  const double ddv = lj_second(p, k.four_eps, dc);
  double fc, dfc;
  cutoff_fn(k, R, fc, dfc);
  const double t = R * k.inv_T - 3.0;
  const double ddfc = (t > 0.0 && t < 1.0) ? (12.0 * t - 6.0) * k.inv_T * k.inv_T : 0.0;
  double w, dw;
  w_of_r(k, R, 1.0 / R, w, dw);
  const double ddw = R * k.inv_r > p.w_knee ? p.w_exponent * (p.w_exponent + 1) * w / (R * R) : 0.0;
  const double M = 1.0 + 2.0 * w, dM = 2.0 * dw, ddM = 2.0 * ddw;
  return std::abs(ddM * fc * v) + std::abs(M * ddfc * v) + std::abs(M * fc * ddv) * a * a +
         2.0 * (std::abs(dM * dfc * v) + std::abs(dM * fc * dv) * a + std::abs(M * dfc * dv) * a);
}

// Bound of the vdW's rotational stiffness: B ≥ |∂²U/∂φ_α ∂φ_β| for unit rotations φ_α, φ_β of
// either segment (both of one segment: the diagonal 3×3 blocks; one of each: the off-diagonal
// block), so B bounds the spectral norm of every rotational block of the pair's Hessian.
//
// Derivation. A rotation φ a (|a| = 1) of segment 1 moves b1 to b1 + φ a×b1 + ½φ² a×(a×b1), and R,
// n do not change, so along it, with ' = d/dφ (or ∂/∂φ_β for the second derivative):
//   c' = a·(b1×b2), |c'| ≤ |b1×b2| = √(1−c²) =: g_c;  c'' = −b1⊥a·b2 or (a×b1)·(a'×b2), |c''| ≤ 1;
//   p1' = a·(b1×n), |p1'| ≤ √(1−p1²) ≤ g_p := max_i √(1−p_i²);  |p1''| ≤ 1  (segment 2 alike).
// u = q² h with q = p1 + s p2, h = 1/(2(1 + s c)) (one flip sign s), h' = −2 s h² c',
// h'' = 8 h³ c'c' − 2 s h² c'':
//   |u'|  ≤ u1 := 2|q| h g_p + 2 q² h² g_c,
//   |u''| ≤ u2 := 2 h g_p² + 8 |q| h² g_c g_p + 2 |q| h + q² (8 h³ g_c² + 2 h²).
// In the flip blend (|c| < flip_blend) u = (1−w) u₋ + w u₊ with the smoothstep w(c), so
//   |u'|  ≤ max(u1±) + |w_c| g_c |u₊−u₋|,
//   |u''| ≤ max(u2±) + 2 |w_c| g_c (u1₊ + u1₋) + (|w_cc| g_c² + |w_c|) |u₊−u₋|.
// δ(u) is the degree-5 polynomial P(y), y = 2u − 1: δ_u = 2P'(y), δ_uu = 4P''(y), so
//   |δ'| ≤ |δ_u| u1,   |δ''| ≤ |δ_uu| u1² + |δ_u| u2.
// D = X/δ − 2 with X = R/r: D' = −X δ'/δ², D'' = 2X δ'²/δ³ − X δ''/δ², and M = 1 + 2W(1−c²):
// |M'| ≤ 4W|c| g_c, |M''| ≤ 4W(g_c² + |c|). Then U = f_c M V(D) (f_c, W depend on R only):
//   U'' = f_c (M'' V + 2 M' V' D' + M (V'' D'D' + V' D''))
//   B   = f_c (|M''||V| + 2|M'||V'||D'|max + M (|V''| D'max² + |V'| D''max)),
// with V'' = 0 on the linear overlap branch (D < d_min). There |V'| is the branch's large slope
// and the |V'| D'' term (the δ(θ) curvature) dominates: the term the radial-curvature estimate
// k_t r² missed (docs/stability.md, crossed overlapping tubes). Coincident centres: U = M V(−2),
// so B = |M''||V(−2)|.
double rotational_bound(const VdwConstants& k, double R, double c, double p1, double p2) {
  const VdwParams& p = k.p;
  if (!(R < p.cutoff())) return 0.0;
  const double ac = std::min(std::abs(c), 1.0);
  const double gc = std::sqrt(std::max(0.0, 1.0 - c * c));
  double w, dw;
  if (R * R < kCoincident2) {
    w_of_r(k, 0.0, 0.0, w, dw);
    double v, dv;
    potential(k, -2.0, v, dv);
    return 4.0 * w * (gc * gc + ac) * std::abs(v);
  }
  const double gp = std::sqrt(std::max({0.0, 1.0 - p1 * p1, 1.0 - p2 * p2}));
  struct Signed {
    double u, u1, u2;
  };
  const auto signed_bounds = [&](double s) {
    const double q = std::abs(p1 + s * p2);
    const double h = 0.5 / (1.0 + s * c);
    return Signed{q * q * h, 2.0 * q * h * gp + 2.0 * q * q * h * h * gc,
                  2.0 * h * gp * gp + 8.0 * q * h * h * gc * gp + 2.0 * q * h +
                      q * q * (8.0 * h * h * h * gc * gc + 2.0 * h * h)};
  };
  const double blend = p.flip_blend;
  double u, u1, u2;
  if (!(std::abs(c) < blend)) {
    const Signed a = signed_bounds(c < 0.0 ? -1.0 : 1.0);
    u = a.u, u1 = a.u1, u2 = a.u2;
  } else {
    const Signed a = signed_bounds(1.0), b = signed_bounds(-1.0);
    const double t = 0.5 * (c + blend) / blend;
    const double wt = t * t * (3.0 - 2.0 * t);
    const double w_c = 3.0 * t * (1.0 - t) / blend;
    const double w_cc = 1.5 * std::abs(1.0 - 2.0 * t) / (blend * blend);
    const double du = std::abs(a.u - b.u);
    u = b.u + wt * (a.u - b.u);
    u1 = std::max(a.u1, b.u1) + w_c * gc * du;
    u2 = std::max(a.u2, b.u2) + 2.0 * w_c * gc * (a.u1 + b.u1) + (w_cc * gc * gc + w_c) * du;
  }
  const auto& a = k.delta_poly;
  const double y = 2.0 * u - 1.0;
  double delta, delta_u;
  delta_of_u(k, u, delta, delta_u);
  const double delta_uu = 4.0 * (2 * a[2] + y * (6 * a[3] + y * (12 * a[4] + y * 20 * a[5])));
  const double d1 = std::abs(delta_u) * u1;
  const double d2 = std::abs(delta_uu) * u1 * u1 + std::abs(delta_u) * u2;
  const double X = R * k.inv_r;
  const double D1 = X * d1 / (delta * delta);
  const double D2 = 2.0 * X * d1 * d1 / (delta * delta * delta) + X * d2 / (delta * delta);
  const double d = X / delta - 2.0;
  double v, dv;
  potential(k, d, v, dv);
  const double ddv = d >= p.d_min ? lj_second(p, k.four_eps, d) : 0.0;
  double fc, dfc;
  cutoff_fn(k, R, fc, dfc);
  w_of_r(k, R, 1.0 / R, w, dw);
  const double M = 1.0 + 2.0 * w * (1.0 - c * c);
  const double M1 = 4.0 * w * ac * gc, M2 = 4.0 * w * (gc * gc + ac);
  return fc * (M2 * std::abs(v) + 2.0 * M1 * std::abs(dv) * D1 +
               M * (std::abs(ddv) * D1 * D1 + std::abs(dv) * D2));
}

}  // namespace

VdwConstants::VdwConstants(const VdwParams& params) : p(params) {
  if (!(p.radius > 0) || !(p.segment_length > 0) || !(p.d_min > 0))
    throw std::invalid_argument("vdW parameters: radius, segment length and d_min must be > 0");
  // The blend's u₋ = (p1 − p2)²/(2(1 − c)) must stay away from c = 1.
  if (!(p.flip_blend >= 0 && p.flip_blend <= 0.5))
    throw std::invalid_argument("vdW parameters: flip_blend must be in [0, 0.5]");
  four_eps = 4.0 * p.epsilon;
  inv_r = 1.0 / p.radius;
  inv_T = 1.0 / p.segment_length;
  cutoff2 = p.cutoff() * p.cutoff();
  fast_lj = p.alpha == 9.5 && p.beta == 4.0;
  fast_w = p.w_exponent == 7.5;
  // δ = 1 + Σ C_k ((−1)^{k−1} + T_k(y)), expanded into monomials of y via the Chebyshev recursion.
  std::array<std::array<double, 6>, 6> T{};  // T[k][m]: coefficient of y^m in T_k
  T[0][0] = 1.0;
  T[1][1] = 1.0;
  for (int kk = 2; kk <= 5; ++kk)
    for (int m = 0; m <= 5; ++m) T[kk][m] = (m > 0 ? 2.0 * T[kk - 1][m - 1] : 0.0) - T[kk - 2][m];
  delta_poly.fill(0.0);
  delta_poly[0] = 1.0;
  for (int kk = 1; kk <= 5; ++kk) {
    const double ck = p.C[kk - 1];
    delta_poly[0] += ck * (kk % 2 == 1 ? 1.0 : -1.0);
    for (int m = 0; m <= 5; ++m) delta_poly[m] += ck * T[kk][m];
  }
  lj(*this, p.d_min, v_dmin, dv_dmin);
  ddv_dmin = lj_second(p, four_eps, p.d_min);
  w_knee_value = p.w_prefactor * std::pow(p.w_knee, -p.w_exponent);
}

VdwPairResult vdw_pair(const VdwConstants& k, const Vec3& x1, const Vec3& b1, const Vec3& x2,
                       const Vec3& b2) {
  VdwPairResult out;
  eval_pair(k, x2 - x1, b1, b2, out);
  return out;
}

VdwPairResult vdw_pair(const VdwParams& p, const Vec3& x1, const Vec3& b1, const Vec3& x2,
                       const Vec3& b2) {
  return vdw_pair(VdwConstants(p), x1, b1, x2, b2);
}

double vdw_delta(const VdwParams& p, double theta) {
  const VdwConstants k(p);
  const double cs = std::cos(theta);
  double delta, dd;
  delta_of_u(k, cs * cs, delta, dd);
  return delta;
}

double vdw_potential(const VdwParams& p, double d) {
  const VdwConstants k(p);
  double v, dv;
  potential(k, d, v, dv);
  return v;
}

double vdw_radial_stiffness(const VdwParams& p, double R) {
  return radial_bound(VdwConstants(p), R, 1.0);
}

namespace {

// The pair's stiffness bounds for the critical step: k_t (translational, eV/nm²) and k_r
// (rotational, eV/rad²). k_r is the larger of the lever-arm estimate k_t r² and the rotational
// bound B (rotational_bound); B exceeds k_t r² where crossed segments overlap deeply.
struct PairStiffness {
  double kt = 0, kr = 0;
};
PairStiffness pair_stiffness(const VdwConstants& k, const Vec3& rv, const Vec3& b1,
                             const Vec3& b2) {
  const VdwParams& p = k.p;
  const double R = rv.norm();
  if (!(R < p.cutoff())) return {};
  const double r2 = p.radius * p.radius;
  const double c = b1.dot(b2);
  const double side = radial_bound(k, R, 1.0);
  if (R * R < kCoincident2) return {side, std::max(side * r2, rotational_bound(k, R, c, 0, 0))};
  const Vec3 n = rv / R;
  const double p1 = b1.dot(n), p2 = b2.dot(n);
  double delta, dd;
  delta_of_u(k, cos_theta2(k, c, p1, p2).u, delta, dd);
  const double kt = std::max(side, radial_bound(k, R, delta));
  return {kt, std::max(kt * r2, rotational_bound(k, R, c, p1, p2))};
}

}  // namespace

double vdw_pair_stiffness(const VdwParams& p, const Vec3& x1, const Vec3& b1, const Vec3& x2,
                          const Vec3& b2) {
  return pair_stiffness(VdwConstants(p), x2 - x1, b1, b2).kt;
}

double vdw_rotational_stiffness(const VdwParams& p, const Vec3& x1, const Vec3& b1, const Vec3& x2,
                                const Vec3& b2) {
  return pair_stiffness(VdwConstants(p), x2 - x1, b1, b2).kr;
}

double vdw_separation(const VdwConstants& k, const Vec3& r, const Vec3& b1, const Vec3& b2) {
  const double R = r.norm();
  if (R * R < kCoincident2) return -2.0;
  const Vec3 n = r / R;
  double delta, dd;
  delta_of_u(k, cos_theta2(k, b1.dot(b2), b1.dot(n), b2.dot(n)).u, delta, dd);
  return R * k.inv_r / delta - 2.0;
}

namespace {

// Pair p of the batch by the scalar kernel (zero beyond the cutoff).
void scalar_lane(const VdwConstants& k, const Vec3* axes, PairBatch& b, int p) {
  VdwPairResult r;
  eval_pair(k, Vec3(b.dx[p], b.dy[p], b.dz[p]), axes[b.i[p]], axes[b.j[p]], r);
  b.store(p, r);
}

// The batch's pairs, with the axes of segments i, j at axes[i], axes[j]: gathered into SoA lanes
// (padded with pairs beyond the cutoff to a whole number of vectors), evaluated by the vectorised
// kernel; lanes with coincident centres, and parameters that need pow(), by the scalar one.
void evaluate_batch(const VdwConstants& k, const Vec3* axes, PairBatch& b) {
  constexpr int kCap = PairBatch::kCapacity;
  static_assert(kCap % vdw_simd::kMaxLanes == 0);
  if (!(k.fast_lj && k.fast_w)) {
    for (int p = 0; p < b.n; ++p) scalar_lane(k, axes, b, p);
    return;
  }
  alignas(64) double ax[kCap], ay[kCap], az[kCap], bx[kCap], by[kCap], bz[kCap];
  for (int p = 0; p < b.n; ++p) {
    const Vec3& a = axes[b.i[p]];
    const Vec3& c = axes[b.j[p]];
    ax[p] = a.x();
    ay[p] = a.y();
    az[p] = a.z();
    bx[p] = c.x();
    by[p] = c.y();
    bz[p] = c.z();
  }
  const int lanes = (b.n + static_cast<int>(vdw_simd::kMaxLanes) - 1) /
                    static_cast<int>(vdw_simd::kMaxLanes) * static_cast<int>(vdw_simd::kMaxLanes);
  for (int p = b.n; p < lanes; ++p) {
    b.dx[p] = 2.0 * k.p.cutoff();
    b.dy[p] = b.dz[p] = 0.0;
    ax[p] = bx[p] = 1.0;
    ay[p] = az[p] = by[p] = bz[p] = 0.0;
  }
  const vdw_simd::Lanes l{b.dx, b.dy, b.dz, ax,    ay,    az,    bx,    by,    bz,   b.energy,
                          b.fx, b.fy, b.fz, b.t1x, b.t1y, b.t1z, b.t2x, b.t2y, b.t2z};
  if (!vdw_simd::evaluate(k, l, static_cast<std::size_t>(lanes))) return;
  for (int p = 0; p < b.n; ++p)
    if (b.dx[p] * b.dx[p] + b.dy[p] * b.dy[p] + b.dz[p] * b.dz[p] < kCoincident2)
      scalar_lane(k, axes, b, p);
}

}  // namespace

void vdw_pairs_batched(const VdwConstants& k, std::span<const Vec3> r, std::span<const Vec3> b1,
                       std::span<const Vec3> b2, std::span<VdwPairResult> out) {
  if (b1.size() != r.size() || b2.size() != r.size() || out.size() != r.size())
    throw std::invalid_argument("vdw_pairs_batched: r, b1, b2 and out must have one length");
  constexpr int kCap = PairBatch::kCapacity;
  std::vector<Vec3> axes(2 * kCap);
  PairBatch b;
  for (std::size_t start = 0; start < r.size(); start += kCap) {
    b.n = static_cast<int>(std::min<std::size_t>(kCap, r.size() - start));
    for (int p = 0; p < b.n; ++p) {
      axes[2 * p] = b1[start + p];
      axes[2 * p + 1] = b2[start + p];
      b.i[p] = static_cast<std::uint32_t>(2 * p);
      b.j[p] = static_cast<std::uint32_t>(2 * p + 1);
      b.dx[p] = r[start + p].x();
      b.dy[p] = r[start + p].y();
      b.dz[p] = r[start + p].z();
    }
    evaluate_batch(k, axes.data(), b);
    for (int p = 0; p < b.n; ++p) {
      VdwPairResult& o = out[start + p];
      o.energy = b.energy[p];
      // f2 from the batch, not read back from o.f1 (a load straddling the two stores just made,
      // which the store buffer cannot forward: half of this helper's time in a benchmark).
      o.f1 = Vec3(b.fx[p], b.fy[p], b.fz[p]);
      o.f2 = Vec3(-b.fx[p], -b.fy[p], -b.fz[p]);
      o.t1 = Vec3(b.t1x[p], b.t1y[p], b.t1z[p]);
      o.t2 = Vec3(b.t2x[p], b.t2y[p], b.t2z[p]);
    }
  }
}

const char* vdw_simd_target() { return vdw_simd::target_name(); }

void VdwKernel::prepare(const Elements& el, long i) const { axes_[i] = el.axis(i); }

void VdwKernel::batch(const Elements&, PairBatch& b) const { evaluate_batch(k_, axes_.data(), b); }

bool VdwKernel::pair(const Elements&, std::size_t i, std::size_t j, const Vec3& d,
                     PairForces& out) const {
  return eval_pair(k_, d, axes_[i], axes_[j], out);
}

void VdwKernel::stiffness(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                          StiffnessSums& s) const {
  const PairStiffness k = pair_stiffness(k_, d, el.axis(i), el.axis(j));
  if (k.kt <= 0.0) return;
  // Translation-rotation coupling: the contact's force at a lever arm of about one radius.
  s.add_pair(i, j, k.kt, k.kr, k.kt * p_.radius);
}

template class PairModel<VdwKernel>;

}  // namespace mdem
