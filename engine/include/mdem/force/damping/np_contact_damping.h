#pragma once
// Viscous dashpots in the nanoparticle contacts (model.md §4's Eq. 33–34 carried over to NP pairs,
// tensile.md §3.4): on every pair of an NP contact within its cutoff, a force −c·(n·v_rel)·n along
// the centre line n, c = 2ψ√(m_eff k), m_eff the pair's reduced mass (an NP is 41 segment masses,
// so m_eff is close to the segment's on NP–CNT pairs and half an NP's on NP–NP pairs).
//
// Each dashpot belongs to its contact (owner() = the contact's name): it acts on exactly that
// contact's pairs and no others. Normal-only by default, like the CNT–CNT dashpot
// (viscous_contact_damping.h): rigid motions are not damped, linear and angular momentum are
// conserved, and the NP gets no torque. With `shear`, as the CNT–CNT dashpot's shear option (the
// thesis's Eq. 33–34 shear dashpot with c_s = c_n), the force is −c·v_rel on the whole relative
// centre velocity: sliding of an NP along a tube or past another NP is damped too.
//
// The stiffness k of c = 2ψ√(m_eff k) is, by default, the CNT–CNT dashpot's k = 100 eV/nm², as
// tensile.md §3.4 and its defaults table settle (c = 3.11 eV·ps/nm² NP–CNT, 14.2 NP–NP, with the
// pairs' reduced masses). The laws' own equilibrium curvatures (NpCntKernel/NpNpKernel::
// equilibrium_stiffness(): 4.45 eV/nm² side-on NP–CNT, 555.9 NP–NP) are the alternative a user can
// set in `stiffness` to make ψ the damping ratio of each pair's own small oscillation.
#include <string_view>
#include <tuple>

#include "mdem/force/contact/np_cnt_contact.h"
#include "mdem/force/contact/np_np_contact.h"
#include "mdem/force/damping/dashpot_law.h"
#include "mdem/force/pair_driver.h"

namespace mdem {

struct NpDampingParams {
  double ratio = 0.03;       // ψ (the CNT–CNT dashpot's, thesis)
  double stiffness = 100.0;  // k (eV/nm²), > 0: tensile.md §3.4, as the CNT–CNT dashpot
  double cutoff = 0.0;       // acts on pairs closer than this (nm): the contact's cutoff
  bool shear = false;        // damp the whole relative velocity, not only its normal part
};

// The dashpot pair kernel of one NP contact (pair_driver.h).
class NpDashpotKernel {
 public:
  static constexpr bool kDissipative = true;
  static constexpr Timescale kTimescale = Timescale::Slow;  // r-RESPA outer step
  static constexpr bool kTorques = false;
  static constexpr EnergyTerm kTerm = EnergyTerm::NpCnt;  // unused: dissipative

  // name, owner: static strings. Throws std::invalid_argument for a ratio outside [0, 10], a
  // non-positive stiffness or cutoff.
  NpDashpotKernel(std::string_view name, std::string_view owner, KindPairs kinds, NpDampingParams p,
                  DashpotEvaluation e = DashpotEvaluation::Batched);
  std::string_view name() const { return name_; }
  std::string_view owner() const { return owner_; }
  // Runs in one pass with its contact (compute_with), the NP–CNT's or the NP–NP's.
  using Owners = std::tuple<NpCntKernel, NpNpKernel>;
  bool active() const { return p_.ratio != 0; }
  double cutoff() const { return p_.cutoff; }
  KindPairs kinds() const { return kinds_; }
  bool excludes(const Elements& el, std::size_t i, std::size_t j) const {
    return !kinds_.has(el.kind[i], el.kind[j]);
  }
  bool pair(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
            PairForces& out) const {
    return dashpot_pair(el, i, j, d, p_.ratio, p_.stiffness, p_.cutoff, p_.shear, out);
  }
  bool batched() const { return eval_ == DashpotEvaluation::Batched; }
  void batch(const Elements& el, PairBatch& b) const {
    dashpot_batch(el, b, p_.ratio, p_.stiffness, p_.shear);
  }
  void touch(const Elements& el, std::uint32_t j) const { dashpot_touch(el, j); }
  void stiffness(const Elements& el, std::size_t i, std::size_t j, const Vec3& d,
                 StiffnessSums& s) const {
    dashpot_stiffness(el, i, j, d, p_.ratio, p_.stiffness, p_.cutoff, s);
  }
  const NpDampingParams& params() const { return p_; }

 private:
  std::string_view name_, owner_;
  KindPairs kinds_;
  NpDampingParams p_;
  DashpotEvaluation eval_;
};

// The dashpots of the NP–CNT and NP–NP contacts with parameters `contact`: cutoff the contact's,
// stiffness k (eV/nm²), with or without the shear part.
NpDashpotKernel np_cnt_dashpot(double ratio = 0.03, const NpCntParams& contact = {},
                               double stiffness = NpDampingParams{}.stiffness, bool shear = false);
NpDashpotKernel np_np_dashpot(double ratio = 0.03, const NpNpParams& contact = {},
                              double stiffness = NpDampingParams{}.stiffness, bool shear = false);

extern template class PairModel<NpDashpotKernel>;

class NpContactDamping final : public PairModel<NpDashpotKernel> {
 public:
  explicit NpContactDamping(NpDashpotKernel k) : PairModel<NpDashpotKernel>(k) {}
  const NpDampingParams& params() const { return k_.params(); }
};

}  // namespace mdem
