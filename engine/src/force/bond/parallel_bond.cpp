#include "mdem/force/bond/parallel_bond.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include "mdem/core/cnt.h"

namespace mdem {

namespace {

void require_stiffness(double v, const char* field) {
  if (!std::isfinite(v) || v < 0)
    throw std::invalid_argument(std::string("bond stiffness ") + field +
                                " must be finite and >= 0, got " + std::to_string(v));
}

// The rotation vector θ of a quaternion (the shortest rotation, |θ| in [0, π]) and the
// coefficient c of K² in the inverse left Jacobian of SO(3), Jl⁻¹(θ) = I − ½K + cK² (K = [θ]×,
// c = 1/a² − (1 + cos a)/(2a sin a), a = |θ|), from one quaternion formula: with w = cos(a/2),
// s = sin(a/2) (for any scale of q), (1 + cos a)/(2a sin a) = w/(2as), and θ = (a/s)·v.
// Near zero (t = s/w = tan(a/2) below 0.05, a < 0.1 rad, the common case) both come from their
// series in t² and a², without a square root or trigonometric call, to full double precision
// (the first omitted terms are below 1e-18 relative); beyond, one sqrt and one atan2.
struct RotationLog {
  Vec3 theta;
  double c;
};

RotationLog rotation_log(const Quat& q) {
  double w = q.w();
  Vec3 v = q.vec();
  if (w < 0) {  // shortest rotation
    w = -w;
    v = -v;
  }
  const double s2 = v.squaredNorm();
  RotationLog r;
  if (s2 < 0.0025 * w * w) {
    // atan(t)/t = Σ (−u)^k/(2k+1), u = t²; then a/s = 2 atan(t)/(t w), a² = 4 u (atan(t)/t)².
    const double u = s2 / (w * w);
    const double p =
        1.0 +
        u * (-1.0 / 3 +
             u * (1.0 / 5 + u * (-1.0 / 7 + u * (1.0 / 9 + u * (-1.0 / 11 + u * (1.0 / 13))))));
    r.theta = (2.0 * p / w) * v;
    const double a2 = 4.0 * u * p * p;
    // 1/a² − cot(a/2)/(2a), from cot's Laurent series.
    r.c = 1.0 / 12 +
          a2 * (1.0 / 720 + a2 * (1.0 / 30240 + a2 * (1.0 / 1209600 + a2 * (1.0 / 47900160))));
  } else {
    const double s = std::sqrt(s2);
    const double a = 2.0 * std::atan2(s, w);
    r.theta = (a / s) * v;
    r.c = 1.0 / (a * a) - w / (2.0 * a * s);
  }
  return r;
}

// The current bond geometry shared by bond_deformation and bond_eval.
struct Kinematics {
  Vec3 ai, aj;      // world centre -> bond point arms
  Vec3 ui, uj;      // world bond directions of the two bodies
  double inv_m;     // 1 / |ui + uj| (0 at a 180° bend, where n falls back to ui)
  Vec3 n;           // (ui + uj) / |ui + uj|
  Vec3 g;           // gap between the two bond points
  RotationLog rot;  // rotation vector of R_j R_rel0⁻¹ R_iᵀ and its Jacobian coefficient
};

Kinematics kinematics(const Bond& b, const Vec3& xi, const Quat& qi, const Vec3& xj,
                      const Quat& qj) {
  Kinematics k;
  k.ai = qi * b.ci;
  k.aj = qj * b.cj;
  k.ui = qi * b.ni;
  k.uj = qj * b.nj;
  const Vec3 m = k.ui + k.uj;
  const double m2 = m.squaredNorm();
  // |m| = 0 only when the two bond directions are exactly opposite (a 180° bend); fall back to
  // body i's direction there so the result stays finite.
  if (m2 > 1e-24) {
    k.inv_m = 1.0 / std::sqrt(m2);
    k.n = k.inv_m * m;
  } else {
    k.inv_m = 0;
    k.n = k.ui;
  }
  k.g = (xj + k.aj) - (xi + k.ai);
  // Conjugates: unit quaternions, and the log is scale invariant anyway.
  k.rot = rotation_log(qj * b.q_rel0.conjugate() * qi.conjugate());
  return k;
}

}  // namespace

BondStiffness cnt_bond_stiffness() {
  BondStiffness k;
  k.kn_area = cnt::kBondKn * cnt::kBondArea;
  k.ks_area = cnt::kBondKs * cnt::kBondArea;
  k.kn_inertia = cnt::kBondKn * cnt::kBondI;
  k.ks_polar = cnt::kBondKs * cnt::kBondJ;
  return k;
}

Bond make_bond(const Elements& el, std::uint32_t i, std::uint32_t j, const BondStiffness& k) {
  const std::size_t n = el.size();
  if (i >= n || j >= n)
    throw std::invalid_argument("bond element index out of range: i = " + std::to_string(i) +
                                ", j = " + std::to_string(j) + ", " + std::to_string(n) +
                                " elements");
  if (i == j)
    throw std::invalid_argument("bond element indices i and j must differ, both are " +
                                std::to_string(i));
  require_stiffness(k.kn_area, "kn_area");
  require_stiffness(k.ks_area, "ks_area");
  require_stiffness(k.kn_inertia, "kn_inertia");
  require_stiffness(k.ks_polar, "ks_polar");

  const Vec3 xi = el.x[i], xj = el.x[j];
  const Vec3 dx = xj - xi;
  const double len = dx.norm();
  if (!(len > 0) || !std::isfinite(len))
    throw std::invalid_argument("bond centres of elements " + std::to_string(i) + " and " +
                                std::to_string(j) + " coincide (centre distance " +
                                std::to_string(len) + ")");
  const double ri = el.radius[i], rj = el.radius[j];
  if (!(ri > 0) || !(rj > 0) || !std::isfinite(ri + rj))
    throw std::invalid_argument("bond element radius must be finite and > 0");

  const Quat qi = el.q[i].normalized(), qj = el.q[j].normalized();
  const Vec3 p = xi + (ri / (ri + rj)) * dx;
  const Vec3 d = dx / len;

  Bond b;
  b.i = i;
  b.j = j;
  b.ci = qi.conjugate() * (p - xi);
  b.cj = qj.conjugate() * (p - xj);
  b.ni = qi.conjugate() * d;
  b.nj = qj.conjugate() * d;
  b.q_rel0 = (qi.conjugate() * qj).normalized();
  b.k = k;
  return b;
}

BondDeformation bond_deformation(const Bond& b, const Vec3& xi, const Quat& qi, const Vec3& xj,
                                 const Quat& qj) {
  const Kinematics k = kinematics(b, xi, qi, xj, qj);
  BondDeformation d;
  d.n = k.n;
  d.u_n = k.g.dot(k.n);
  d.u_s = k.g - d.u_n * k.n;
  d.theta_t = k.rot.theta.dot(k.n);
  d.theta_b = k.rot.theta - d.theta_t * k.n;
  return d;
}

// Gradient of U(g, n, θ) (see the header) and its chain rule to both bodies. Rotations are
// world-frame perturbations R → exp(δφ) R, torque τ = −∂U/∂δφ.
//   gap:   δg = δx_j + δφ_j×a_j − δx_i − δφ_i×a_i  ⇒ F_j = −G, F_i = G, τ_j = −a_j×G, τ_i = a_i×G
//   axis:  δu = δφ×u, ∂U/∂m = (I − n nᵀ) ∂U/∂n / |m|  ⇒ τ_{i,j} = −u_{i,j} × ∂U/∂m
//   rot.:  D = R_j R0⁻¹ R_iᵀ; exp(δφ_j) D ⇒ δθ = J_l⁻¹(θ) δφ_j; D exp(−δφ_i) ⇒ δθ = −J_l⁻ᵀ(θ) δφ_i
//          ⇒ τ_j = −J_l⁻ᵀ ∂U/∂θ, τ_i = +J_l⁻¹ ∂U/∂θ, with J_l⁻¹ y = y − ½ θ×y + c θ×(θ×y) and
//          J_l⁻ᵀ y = y + ½ θ×y + c θ×(θ×y) (K is skew, K² symmetric): no matrix is formed.
BondResult bond_eval(const Bond& b, const Vec3& xi, const Quat& qi, const Vec3& xj,
                     const Quat& qj) {
  const Kinematics k = kinematics(b, xi, qi, xj, qj);
  const BondStiffness& s = b.k;
  const Vec3& n = k.n;
  const Vec3& g = k.g;
  const Vec3& th = k.rot.theta;

  const double gn = g.dot(n);
  const Vec3 gs = g - gn * n;
  const double tn = th.dot(n);
  const Vec3 tb = th - tn * n;

  BondResult r;
  r.e_tension = 0.5 * s.kn_area * gn * gn;
  r.e_shear = 0.5 * s.ks_area * gs.squaredNorm();
  r.e_bending = 0.5 * s.kn_inertia * tb.squaredNorm();
  r.e_torsion = 0.5 * s.ks_polar * tn * tn;

  const double kg = (s.kn_area - s.ks_area) * gn;
  const double kt = (s.ks_polar - s.kn_inertia) * tn;
  const Vec3 dU_dg = s.ks_area * g + kg * n;
  const Vec3 dU_dth = s.kn_inertia * th + kt * n;
  const Vec3 dU_dn = kg * g + kt * th;

  r.fi = dU_dg;
  r.fj = -dU_dg;
  r.ti = k.ai.cross(dU_dg);
  r.tj = -k.aj.cross(dU_dg);

  if (k.inv_m > 0) {
    const Vec3 dU_dm = k.inv_m * (dU_dn - n.dot(dU_dn) * n);
    r.ti -= k.ui.cross(dU_dm);
    r.tj -= k.uj.cross(dU_dm);
  }

  const Vec3 p = th.cross(dU_dth);
  const Vec3 sym = dU_dth + k.rot.c * th.cross(p);
  r.ti += sym - 0.5 * p;
  r.tj -= sym + 0.5 * p;
  return r;
}

std::unique_ptr<ParallelBond> ParallelBond::from_topology(const Elements& el, BondType type,
                                                          const BondStiffness& k) {
  auto model = std::make_unique<ParallelBond>();
  for (const TopologyBond& tb : el.topology.bonds())
    if (tb.type == type)
      model->add(make_bond(el, static_cast<std::uint32_t>(el.index_of(tb.a)),
                           static_cast<std::uint32_t>(el.index_of(tb.b)), k));
  return model;
}

void ParallelBond::reorder(std::span<const std::uint32_t> old_to_new) {
  for (Bond& b : bonds_) {
    b.i = old_to_new[b.i];
    b.j = old_to_new[b.j];
  }
  // Then in the elements' memory order, so the bond loop streams through them as the pair loop
  // does: by the pair's lower index, then its higher one (unique per pair, so the order depends on
  // the elements' order only, not on the reorderings that led to it: a resumed run has the same).
  // Sorted on 8-byte keys (a bond is ~170 bytes), the bonds then moved once.
  std::vector<std::uint64_t> key(bonds_.size());
  for (std::size_t k = 0; k < bonds_.size(); ++k) {
    const Bond& b = bonds_[k];
    key[k] = std::uint64_t{std::min(b.i, b.j)} << 32 | std::max(b.i, b.j);
  }
  if (std::is_sorted(key.begin(), key.end())) return;
  std::vector<std::uint32_t> order(bonds_.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return key[a] < key[b]; });
  std::vector<Bond> sorted;
  sorted.reserve(bonds_.size());
  for (std::uint32_t k : order) sorted.push_back(bonds_[k]);
  bonds_ = std::move(sorted);
}

void ParallelBond::compute(const Elements& el, const NeighborList*, ForceSink& sink) const {
  if (bonds_.empty()) return;
  const int nt = sink.threads();
  if (nt < 1) throw std::logic_error("parallel_bond: force sink has no thread buffers");
  const std::size_t nb = bonds_.size();
  const Vec3* x = el.x.data();
  const Quat* q = el.q.data();
  const Domain& dom = domain();
#pragma omp parallel num_threads(nt) if (static_cast <long>(nb) >= kParallelMinItems)
  {
    const int tid = omp_get_thread_num();
    Vec3* f = sink.force(tid);
    Vec3* t = sink.torque(tid);
    BondTally tally;
#pragma omp for schedule(static)
    for (std::size_t k = 0; k < nb; ++k) {
      const Bond& b = bonds_[k];
      tally.apply(bond_eval(b, x[b.i], q[b.i], dom.image(x[b.i], x[b.j]), q[b.j]), b.i, b.j, f, t);
    }
    tally.add_to(sink.energy(tid));
  }
}

void add_bond_stiffness(const Bond& b, StiffnessSums& s) {
  const BondStiffness& k = b.k;
  const double kt = std::max(k.kn_area, k.ks_area);
  const double krot = std::max(k.kn_inertia, k.ks_polar);
  const double ai = b.ci.norm(), aj = b.cj.norm();
  s.kt[b.i] += kt;
  s.kt[b.j] += kt;
  s.kr[b.i] += krot + k.ks_area * ai * ai;
  s.kr[b.j] += krot + k.ks_area * aj * aj;
  s.ktr[b.i] += k.ks_area * ai;
  s.ktr[b.j] += k.ks_area * aj;
}

void ParallelBond::add_stiffness(const Elements&, const NeighborList*, StiffnessSums& s) const {
  for (const Bond& b : bonds_) add_bond_stiffness(b, s);
}

}  // namespace mdem
