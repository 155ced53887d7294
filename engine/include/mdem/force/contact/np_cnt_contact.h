#pragma once
// Nanoparticle–CNT segment contact (model.md §5, thesis Eq. 26–27, tensile.md §2.3).
//
//   U = f_c(R) · V(D),  V(D) = 4ε0 (A D^−α − B D^−β),  D = R / (ρ_NC δ(θ)) − 2
//
// with d = x_NP − x_seg, R = |d|, n = d/R, b the segment's unit axis, cos θ = |b·n| (θ = 90°
// beside the segment), δ(θ) and the smoothstep f_c (3T → 4T) exactly as the CNT–CNT contact's
// (model.md §4), V continued linearly (C¹) below D = d_min. Forces on both elements and the
// segment's torque are the exact gradient of U; the NP gets no torque (a point mass in the thesis).
#include <array>

#include "mdem/core/cnt.h"
#include "mdem/force/contact/vdw_shape.h"
#include "mdem/force/pair_driver.h"

namespace mdem {

struct NpCntParams {
  // ε0 (eV). The thesis's Table 5-2 prints 0.005407, a factor-ten misprint (model.md §5); kept a
  // parameter so the printed value can be run.
  double epsilon = 0.05407;
  double A = 58.1;
  double B = 14.2;
  double alpha = 8.34;
  double beta = 3.32;
  double rho =
      0.98623;  // ρ_NC (nm): an NP beside a long straight tube rests 3.462 nm from its axis
  double segment_length = cnt::kSegmentLength;  // T (nm); smoothstep cutoff from 3T to 4T
  std::array<double, 5> C = {0.35819, 0.03263, -0.00138, -0.00017, 0.00024};  // δ(θ), §4
  double d_min = 0.8;  // below: V continued linearly (C¹)

  double cutoff() const { return 4.0 * segment_length; }
};

// How NpCntKernel evaluates the driver's pairs: over batches with the vectorised law
// (np_cnt_simd.cpp, the default) or pair by pair with the scalar law (the reference).
enum class NpCntEvaluation { Batched, Scalar };

// The NP–CNT pair kernel (pair_driver.h): Nanoparticle–CntSegment pairs, in either order.
class NpCntKernel {
 public:
  static constexpr bool kDissipative = false;
  static constexpr Timescale kTimescale = Timescale::Slow;  // r-RESPA outer step
  static constexpr bool kTorques = true;                    // on the segment only
  static constexpr EnergyTerm kTerm = EnergyTerm::NpCnt;

  // Throws std::invalid_argument naming the parameter and its allowed range.
  explicit NpCntKernel(NpCntParams p = {}, NpCntEvaluation e = NpCntEvaluation::Batched);
  std::string_view name() const { return "np_cnt_contact"; }
  double cutoff() const { return p_.cutoff(); }
  KindPairs kinds() const {
    return KindPairs::of(ElementKind::Nanoparticle, ElementKind::CntSegment);
  }
  bool excludes(const Elements& el, std::size_t i, std::size_t j) const {
    return !kinds().has(el.kind[i], el.kind[j]);
  }
  bool pair(const Elements& el, std::size_t i, std::size_t j, const Vec3& d, PairForces& out) const;
  bool batched() const { return eval_ == NpCntEvaluation::Batched; }
  // The batch's pairs by the vectorised law; a lane with coincident centres by pair().
  void batch(const Elements& el, PairBatch& b) const;
  // batch() reads the kind of element j and, for a segment, its orientation.
  void touch(const Elements& el, std::uint32_t j) const {
    __builtin_prefetch(el.q.data() + j, 0, 3);
    __builtin_prefetch(el.kind.data() + j, 0, 3);
  }
  // Radial bound |∂²U/∂R²| at the pair's δ and at δ's smallest value (the side-on law), on both
  // elements; the segment's rotational bound from D's angular rate (vdw_shape max_log_slope).
  void stiffness(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                 StiffnessSums& s) const;
  const NpCntParams& params() const { return p_; }

  // The law for an NP at x_np and a segment at x_seg with unit axis b: U, the force on the NP
  // (f1), on the segment (f2) and the segment's torque (t2); t1 (the NP's) is zero. Zero beyond
  // the cutoff. Coincident centres (R < 1e-12 nm) give U = f_c·V(−2) with no force or torque.
  PairForces evaluate(const Vec3& x_np, const Vec3& x_seg, const Vec3& b) const;
  // The law's D = R/(ρ_NC δ(θ)) − 2 for that pair (−2 for coincident centres): overlap tests.
  double separation(const Vec3& x_np, const Vec3& x_seg, const Vec3& b) const;

  // Curvature ∂²U/∂R² of the side-on law (θ = 90°) at its minimum D0 = (αA/(βB))^{1/(α−β)}, R0 =
  // ρ_NC (D0 + 2) (3.541 nm with the defaults, where f_c = 1): V''(D0)/ρ_NC² (eV/nm²).
  double equilibrium_stiffness() const;

 private:
  // d = x_NP − x_seg; writes U, the NP's force (f_np), the segment's torque (t_seg).
  bool law(const Vec3& d, const Vec3& b, double& energy, Vec3& f_np, Vec3& t_seg) const;
  NpCntParams p_;
  NpCntEvaluation eval_;
  vdw_shape::DeltaPolynomial delta_;
  vdw_shape::SmoothstepCutoff fc_;
  vdw_shape::TwoPowerPotential v_;
  double v_min_ = 0, dv_min_ = 0;  // V and V' at d_min, where the linear branch starts
};

// The instruction set the batched law runs on this CPU (e.g. "AVX3", "AVX2", "EMU128").
const char* np_cnt_simd_target();

extern template class PairModel<NpCntKernel>;

class NpCntContact final : public PairModel<NpCntKernel> {
 public:
  explicit NpCntContact(NpCntParams p = {}, NpCntEvaluation e = NpCntEvaluation::Batched)
      : PairModel<NpCntKernel>(p, e) {}
  const NpCntParams& params() const { return k_.params(); }
};

}  // namespace mdem
