#pragma once
// Nanoparticle–nanoparticle contact (model.md §5, thesis Eq. 25, tensile.md §2.5).
//
//   U = f_c(R) · V(D),  V(D) = 4ε0 (A D^−α − B D^−β),  D = R / r_NP − 2
//
// (D is the gap normalised by the radius; the thesis's literal "R/r_NP" would put two NPs 0.43 nm
// apart centre to centre), f_c the smoothstep from 7.0 nm (1) to 8.0 nm (0), V continued linearly
// (C¹) below D = d_min. A central force; no torques. Its 8 nm reach gets its own neighbour
// sub-list (neighbor/pair_table.h), so it does not enlarge the CNT–CNT list.
#include "mdem/core/np.h"
#include "mdem/force/contact/vdw_shape.h"
#include "mdem/force/pair_driver.h"

namespace mdem {

struct NpNpParams {
  double epsilon = 0.009105;  // ε0 (eV)
  double A = 0.0188;
  double B = 0.2519;
  double alpha = 5.62;
  double beta = 4.3;
  double radius = np::kRadius;  // r_NP (nm)
  double taper_start = 7.0;     // f_c = 1 up to here (nm)
  double taper_width = 1.0;     // ... and 0 from taper_start + taper_width on (nm)
  double d_min = 0.1;           // below: V continued linearly (C¹)

  double cutoff() const { return taper_start + taper_width; }
};

// How NpNpKernel evaluates the driver's pairs: over batches with the vectorised law (the default)
// or pair by pair with the scalar law (the reference).
enum class NpNpEvaluation { Batched, Scalar };

// The NP–NP pair kernel (pair_driver.h).
class NpNpKernel {
 public:
  static constexpr bool kDissipative = false;
  static constexpr Timescale kTimescale = Timescale::Slow;  // r-RESPA outer step
  static constexpr bool kTorques = false;
  static constexpr EnergyTerm kTerm = EnergyTerm::NpNp;

  // Throws std::invalid_argument naming the parameter and its allowed range.
  explicit NpNpKernel(NpNpParams p = {}, NpNpEvaluation e = NpNpEvaluation::Batched);
  std::string_view name() const { return "np_np_contact"; }
  double cutoff() const { return p_.cutoff(); }
  KindPairs kinds() const {
    return KindPairs::of(ElementKind::Nanoparticle, ElementKind::Nanoparticle);
  }
  bool excludes(const Elements& el, std::size_t i, std::size_t j) const {
    return !kinds().has(el.kind[i], el.kind[j]);
  }
  bool pair(const Elements&, std::size_t, std::size_t, const Vec3& d, PairForces& out) const {
    return evaluate(d, out);
  }
  bool batched() const { return eval_ == NpNpEvaluation::Batched; }
  // The batch's pairs by the vectorised NP–CNT law with an isotropic shape (np_cnt_simd with
  // δ ≡ 1 and ρ = r_NP, which is this law: D = R/r_NP − 2, a central force, no torque); a lane
  // with coincident centres by evaluate(). pow() in the scalar law, one Log and two Exp here.
  void batch(const Elements& el, PairBatch& b) const;
  void stiffness(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                 StiffnessSums& s) const;
  const NpNpParams& params() const { return p_; }

  // The law for NP 2 at d from NP 1: U, forces f1, f2 (f2 = −U'(R) d/R); false beyond the cutoff.
  // Coincident centres (R < 1e-12 nm) give U = V(−2) and no force.
  bool evaluate(const Vec3& d, PairForces& out) const;
  // U(R) alone.
  double energy(double R) const;
  // Curvature U''(R0) at the minimum of V, D0 = (αA/(βB))^{1/(α−β)}, R0 = r_NP (D0 + 2)
  // (5.4287 nm with the defaults, where f_c = 1): V''(D0)/r_NP² (eV/nm²; 555.9 with the defaults).
  double equilibrium_stiffness() const;
  // R0 = r_NP (D0 + 2), the centre distance of the pair's minimum while f_c = 1 there (nm).
  double equilibrium_distance() const;
  // The law's D = R/r_NP − 2 at centre distance R: overlap tests.
  double separation(double R) const { return R / p_.radius - 2.0; }

 private:
  NpNpParams p_;
  NpNpEvaluation eval_;
  vdw_shape::SmoothstepCutoff fc_;
  vdw_shape::TwoPowerPotential v_;
  double v_min_ = 0, dv_min_ = 0;  // V(d_min), V'(d_min): the linear branch's start
};

extern template class PairModel<NpNpKernel>;

class NpNpContact final : public PairModel<NpNpKernel> {
 public:
  explicit NpNpContact(NpNpParams p = {}, NpNpEvaluation e = NpNpEvaluation::Batched)
      : PairModel<NpNpKernel>(p, e) {}
  const NpNpParams& params() const { return k_.params(); }
};

}  // namespace mdem
