#pragma once
// Anisotropic CNT–CNT van der Waals contact (model.md §4, thesis Eq. 5–8, Tables 2-2, 2-3).
//
//   U(R, θ, γ) = M(R, γ) · f_c(R) · V(D),  V(D) = 4ε (A D^-α − B D^-β),  D = R / (r δ(θ)) − 2
//
// continued linearly in D below D_min (C¹), so overlapping tubes feel a finite repulsion.
#include <array>
#include <span>
#include <vector>

#include "mdem/force/pair_driver.h"

namespace mdem {

enum class VdwTorque {
  Exact,  // forces and torques are the exact gradient of U (energy-conserving), the default
  // Table 2-3 literally: radial + shear force, aligning moment −∂U/∂γ only. Drops the torque
  // from θ's dependence on the axes: not conservative under rotation, and the pair's angular
  // momentum is not balanced.
  Pfc,
};

struct VdwParams {
  double epsilon = 0.03733;  // eV (4ε = 149.3 meV)
  double A = 0.0223;
  double B = 1.31;
  double alpha = 9.5;
  double beta = 4.0;
  double radius = 0.678;          // r (nm)
  double segment_length = 1.356;  // T (nm); smoothstep cutoff from 3T to 4T
  std::array<double, 5> C = {0.35819, 0.03263, -0.00138, -0.00017, 0.00024};
  double d_min = 0.4;         // below: V continued linearly (C¹)
  double w_prefactor = 90.0;  // W(R) = 90 (R/r)^-7.5 for R/r > 2.75
  double w_exponent = 7.5;
  double w_knee = 2.75;
  // Segments of one tube closer than this many indices apart do not interact (0: all do).
  int intra_tube_exclusion = 20;
  VdwTorque torque = VdwTorque::Exact;
  // The model flips b2 by s = sign(b1·b2), which makes U jump where b1·b2 = 0 (unless the centre
  // line is perpendicular to an axis). 0: the literal model. > 0: inside |b1·b2| < flip_blend,
  // cos²θ is a C¹ smoothstep blend of its two signed values, so U is continuous (C¹) everywhere
  // and an undamped run conserves energy through γ = 90° as well. The blend's torque scales as
  // 1/flip_blend, so a narrow window needs a small step: 0.2 (γ within 11.5° of 90°) is tested at
  // 5–10 fs; 0.02 blows up at 10 fs. Must be in [0, 0.5]. Default 0.2, so the default model
  // conserves energy (model.md §4 asks for that); flip_blend = 0 is the thesis's literal form.
  double flip_blend = 0.2;

  double cutoff() const { return 4.0 * segment_length; }
};

// Energy and generalized forces of one segment pair. f1, f2 forces (eV/nm), t1, t2 torques (eV)
// on segment 1 and 2; zero beyond the cutoff.
using VdwPairResult = PairForces;

// x1, x2 centres; b1, b2 unit axes (either sign: the model flips b2 so b1·b2 ≥ 0, which makes U
// jump where b1·b2 changes sign unless the centre line is perpendicular to an axis — a property
// of the published model; see flip_blend). Coincident centres (R < 1e-12 nm) give the finite
// energy M·V(−2), zero force and the aligning torque; a NaN input propagates into the result;
// an infinitely distant pair reads as beyond the cutoff.
VdwPairResult vdw_pair(const VdwParams& p, const Vec3& x1, const Vec3& b1, const Vec3& x2,
                       const Vec3& b2);

// δ(θ) and V(D) on their own, for tests and reports.
double vdw_delta(const VdwParams& p, double theta);
double vdw_potential(const VdwParams& p, double d);

// Radial stiffness bound of one pair at centre distance R (eV/nm²), for the critical step.
// Side by side (θ = 90°, δ = 1, the smallest δ) and crossed (γ = 90°, the largest M): the sum of
// the absolute values of the terms of ∂²(M f_c V)/∂R², with V'' taken at max(D, d_min) (so a pair
// on the linear overlap branch still counts the stiffness of the branch it leaves).
double vdw_radial_stiffness(const VdwParams& p, double R);
// The same bound at the pair's actual δ(θ) (γ = 90° still), and never below
// vdw_radial_stiffness(p, R): an end-to-end pair (δ up to 1.714) can be much stiffer at a given R
// than a side-by-side one. Zero beyond the cutoff.
double vdw_pair_stiffness(const VdwParams& p, const Vec3& x1, const Vec3& b1, const Vec3& x2,
                          const Vec3& b2);
// Rotational stiffness bound of one pair (eV/rad²), for the critical step: at least the spectral
// norm of each 3×3 rotational block of the pair energy's Hessian (one segment's, and the coupling
// of the two segments' rotations), from the derivatives of c = b1·b2, cos²θ, δ(θ), D and M along
// a rotation (the derivation is at rotational_bound in anisotropic_vdw.cpp); never below the
// lever-arm estimate vdw_pair_stiffness · radius². Zero beyond the cutoff.
double vdw_rotational_stiffness(const VdwParams& p, const Vec3& x1, const Vec3& b1, const Vec3& x2,
                                const Vec3& b2);

// Constants derived once from a parameter set (δ as a polynomial in cos 2θ, V and V' at d_min,
// W below the knee), so the pair kernel needs no pow() or trigonometry.
struct VdwConstants {
  explicit VdwConstants(const VdwParams& p);
  VdwParams p;
  double four_eps, inv_r, inv_T, cutoff2;
  std::array<double, 6> delta_poly;  // δ = Σ delta_poly[k] y^k, y = cos 2θ = 2 cos²θ − 1
  bool fast_lj;                      // α = 9.5, β = 4: no pow()
  bool fast_w;                       // W exponent 7.5: no pow()
  double v_dmin, dv_dmin, ddv_dmin;  // V, V', V'' at d_min
  double w_knee_value;               // W(R) for R/r ≤ knee
};

VdwPairResult vdw_pair(const VdwConstants& k, const Vec3& x1, const Vec3& b1, const Vec3& x2,
                       const Vec3& b2);

// The pair's D = R/(r δ(θ)) − 2 as vdw_pair computes it (θ with the flip or its blend), for
// r = x2 − x1; −2 for coincident centres. For overlap tests (tensile pre-relaxation, §3.3).
double vdw_separation(const VdwConstants& k, const Vec3& r, const Vec3& b1, const Vec3& b2);

// How VdwKernel evaluates its pairs. Batched (the default): in batches of pairs in
// structure-of-arrays form with SIMD, on the widest instruction set of the CPU chosen at run
// time (vdw_simd_target()); equal to the scalar kernel to round-off, not bit for bit. Scalar:
// one pair at a time with vdw_pair's code, the reference. Parameters with α ≠ 9.5, β ≠ 4 or a
// W exponent ≠ 7.5 (which need pow()) are evaluated by the scalar code on either path.
enum class VdwEvaluation { Batched, Scalar };

// The batched path on its own, for tests: out[p] is pair p (r[p] = x2 − x1, axes b1[p], b2[p])
// as the kernel's batched path evaluates it. Throws std::invalid_argument unless the four spans
// have one length.
void vdw_pairs_batched(const VdwConstants& k, std::span<const Vec3> r, std::span<const Vec3> b1,
                       std::span<const Vec3> b2, std::span<VdwPairResult> out);
// The instruction set of the batched path on this CPU (Highway's name: "AVX3", "AVX2", ...).
const char* vdw_simd_target();

// The CNT–CNT vdW pair kernel (pair_driver.h): CntSegment–CntSegment pairs outside the
// intra-tube exclusion; the segment axes are computed once per evaluation, not once per pair.
class VdwKernel {
 public:
  static constexpr bool kDissipative = false;
  static constexpr Timescale kTimescale = Timescale::Slow;  // r-RESPA outer step
  static constexpr bool kTorques = true;
  static constexpr EnergyTerm kTerm = EnergyTerm::Vdw;

  explicit VdwKernel(VdwParams p = {}, VdwEvaluation e = VdwEvaluation::Batched)
      : p_(p), k_(p), eval_(e) {}
  std::string_view name() const { return "anisotropic_vdw"; }
  double cutoff() const { return p_.cutoff(); }
  KindPairs kinds() const {
    return KindPairs::of(ElementKind::CntSegment, ElementKind::CntSegment);
  }
  bool excludes(const Elements& el, std::size_t i, std::size_t j) const {
    return el.cnt_pair_excluded(i, j, p_.intra_tube_exclusion);
  }
  void begin(const Elements& el) const { axes_.resize(el.size()); }
  void prepare(const Elements& el, long i) const;
  bool pair(const Elements& el, std::size_t i, std::size_t j, const Vec3& d, PairForces& out) const;
  bool batched() const { return eval_ == VdwEvaluation::Batched; }
  void batch(const Elements& el, PairBatch& b) const;
  void touch(const Elements&, std::uint32_t j) const {
    pair_driver_detail::prefetch_vec3_end<0>(axes_.data() + j);
  }
  void stiffness(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                 StiffnessSums& s) const;
  const VdwParams& params() const { return p_; }

 private:
  VdwParams p_;
  VdwConstants k_;
  VdwEvaluation eval_;
  // Segment axes of the current evaluation, computed once per step rather than once per pair.
  mutable std::vector<Vec3> axes_;
};

// Instantiated in anisotropic_vdw.cpp, where the kernel's pair() inlines into the driver's loop.
extern template class PairModel<VdwKernel>;

class AnisotropicVdw final : public PairModel<VdwKernel> {
 public:
  explicit AnisotropicVdw(VdwParams p = {}, VdwEvaluation e = VdwEvaluation::Batched)
      : PairModel<VdwKernel>(p, e) {}
  const VdwParams& params() const { return k_.params(); }
};

}  // namespace mdem
