#include "mdem/force/bond/parallel_bond.h"

#include <omp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include "force/bond/bond_simd.h"
#include "mdem/core/cnt.h"

namespace mdem {

namespace {

void require_stiffness(double v, const char* field) {
  if (!std::isfinite(v) || v < 0)
    throw std::invalid_argument(std::string("bond stiffness ") + field +
                                " must be finite and >= 0, got " + std::to_string(v));
}

// The bond's arithmetic is written on plain doubles (P3 below), not on Eigen's 3-vectors: Eigen
// packs two of a vector's three components into one SSE register and moves the third alone, and
// in this long chain of small products the compiler spilled such halves to the stack and read
// them back whole, a store-forwarding stall per quaternion rotation (perf: a quarter of the
// kinematics' time). Same formulas, same order of the bonds: results differ at round-off only.
#include "force/bond/triple-inl.h"
using P3 = Triple<double>;
inline P3 p3(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

// The rotation matrix of a unit quaternion, applied to two body-frame vectors: one matrix for
// both (the bond point arm and the bond direction), no trigonometric call.
struct Rot {
  double m[3][3];
  explicit Rot(const Quat& q) {
    const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
    const double tx = 2 * x, ty = 2 * y, tz = 2 * z;
    const double twx = tx * w, twy = ty * w, twz = tz * w, txx = tx * x, txy = ty * x, txz = tz * x,
                 tyy = ty * y, tyz = tz * y, tzz = tz * z;
    m[0][0] = 1 - (tyy + tzz);
    m[0][1] = txy - twz;
    m[0][2] = txz + twy;
    m[1][0] = txy + twz;
    m[1][1] = 1 - (txx + tzz);
    m[1][2] = tyz - twx;
    m[2][0] = txz - twy;
    m[2][1] = tyz + twx;
    m[2][2] = 1 - (txx + tyy);
  }
  P3 operator*(const Vec3& v) const {
    return {m[0][0] * v.x() + m[0][1] * v.y() + m[0][2] * v.z(),
            m[1][0] * v.x() + m[1][1] * v.y() + m[1][2] * v.z(),
            m[2][0] * v.x() + m[2][1] * v.y() + m[2][2] * v.z()};
  }
};

// A quaternion as its scalar and vector parts.
struct Q4 {
  double w;
  P3 v;
};
inline Q4 q4(const Quat& q) { return {q.w(), {q.x(), q.y(), q.z()}}; }

// The rotation vector θ of a quaternion (the shortest rotation, |θ| in [0, π]) and the
// coefficient c of K² in the inverse left Jacobian of SO(3), Jl⁻¹(θ) = I − ½K + cK² (K = [θ]×,
// c = 1/a² − (1 + cos a)/(2a sin a), a = |θ|), from one quaternion formula: with w = cos(a/2),
// s = sin(a/2) (for any scale of q), (1 + cos a)/(2a sin a) = w/(2as), and θ = (a/s)·v.
// Near zero (t = s/w = tan(a/2) below 0.05, a < 0.1 rad, the common case) both come from their
// series in t² and a², without a square root or trigonometric call, to full double precision
// (the first omitted terms are below 1e-18 relative); beyond, one sqrt and one atan2.
struct RotationLog {
  P3 theta;
  double c;
};

RotationLog rotation_log(Q4 q) {
  if (q.w < 0) q = {-q.w, -1.0 * q.v};  // shortest rotation
  const double w = q.w;
  const P3& v = q.v;
  const double s2 = dot(v, v);
  RotationLog r;
  if (s2 < 0.0025 * w * w) {
    // atan(t)/t = Σ (−u)^k/(2k+1), u = t²; then a/s = 2 atan(t)/(t w), a² = 4 u (atan(t)/t)².
    const double iw = 1.0 / w;
    const double u = s2 * iw * iw;
    const double p =
        1.0 +
        u * (-1.0 / 3 +
             u * (1.0 / 5 + u * (-1.0 / 7 + u * (1.0 / 9 + u * (-1.0 / 11 + u * (1.0 / 13))))));
    r.theta = (2.0 * p * iw) * v;
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
  P3 ai, aj;        // world centre -> bond point arms
  P3 ui, uj;        // world bond directions of the two bodies
  double inv_m;     // 1 / |ui + uj| (0 at a 180° bend, where n falls back to ui)
  P3 n;             // (ui + uj) / |ui + uj|
  P3 g;             // gap between the two bond points
  RotationLog rot;  // rotation vector of R_j R_rel0⁻¹ R_iᵀ and its Jacobian coefficient
};

Kinematics kinematics(const Bond& b, const Vec3& xi, const Quat& qi, const Vec3& xj,
                      const Quat& qj) {
  Kinematics k;
  const Rot Ri(qi), Rj(qj);
  k.ai = Ri * b.ci;
  k.aj = Rj * b.cj;
  k.ui = Ri * b.ni;
  k.uj = Rj * b.nj;
  const P3 m = k.ui + k.uj;
  const double m2 = dot(m, m);
  // |m| = 0 only when the two bond directions are exactly opposite (a 180° bend); fall back to
  // body i's direction there so the result stays finite.
  if (m2 > 1e-24) {
    k.inv_m = 1.0 / std::sqrt(m2);
    k.n = k.inv_m * m;
  } else {
    k.inv_m = 0;
    k.n = k.ui;
  }
  k.g = (p3(xj) + k.aj) - (p3(xi) + k.ai);
  // Conjugates: unit quaternions, and the log is scale invariant anyway. Eigen's product, whose
  // rounding a small relative rotation (a difference of O(1) products) inherits: 1e-9 rad comes
  // out to ~1e-7 relative by any order of the sums, and the textbook reference uses this one.
  k.rot = rotation_log(q4(qj * b.q_rel0.conjugate() * qi.conjugate()));
  return k;
}

// Energies, and the forces and moments on i (fi, ti) and j (fj = −fi, tj) of a bond in state k.
struct Loads {
  double e_tension, e_shear, e_bending, e_torsion;
  P3 fi, ti, tj;
};

// Gradient of U(g, n, θ) (see the header) and its chain rule to both bodies. Rotations are
// world-frame perturbations R → exp(δφ) R, torque τ = −∂U/∂δφ.
//   gap:   δg = δx_j + δφ_j×a_j − δx_i − δφ_i×a_i  ⇒ F_j = −G, F_i = G, τ_j = −a_j×G, τ_i = a_i×G
//   axis:  δu = δφ×u, ∂U/∂m = (I − n nᵀ) ∂U/∂n / |m|  ⇒ τ_{i,j} = −u_{i,j} × ∂U/∂m
//   rot.:  D = R_j R0⁻¹ R_iᵀ; exp(δφ_j) D ⇒ δθ = J_l⁻¹(θ) δφ_j; D exp(−δφ_i) ⇒ δθ = −J_l⁻ᵀ(θ) δφ_i
//          ⇒ τ_j = −J_l⁻ᵀ ∂U/∂θ, τ_i = +J_l⁻¹ ∂U/∂θ, with J_l⁻¹ y = y − ½ θ×y + c θ×(θ×y) and
//          J_l⁻ᵀ y = y + ½ θ×y + c θ×(θ×y) (K is skew, K² symmetric): no matrix is formed.
inline Loads loads(const BondStiffness& s, const Kinematics& k) {
  const P3& n = k.n;
  const P3& g = k.g;
  const P3& th = k.rot.theta;

  const double gn = dot(g, n);
  const P3 gs = g - gn * n;
  const double tn = dot(th, n);
  const P3 tb = th - tn * n;

  Loads r;
  r.e_tension = 0.5 * s.kn_area * gn * gn;
  r.e_shear = 0.5 * s.ks_area * dot(gs, gs);
  r.e_bending = 0.5 * s.kn_inertia * dot(tb, tb);
  r.e_torsion = 0.5 * s.ks_polar * tn * tn;

  const double kg = (s.kn_area - s.ks_area) * gn;
  const double kt = (s.ks_polar - s.kn_inertia) * tn;
  const P3 dU_dg = s.ks_area * g + kg * n;
  const P3 dU_dth = s.kn_inertia * th + kt * n;
  const P3 dU_dn = kg * g + kt * th;

  r.fi = dU_dg;
  r.ti = cross(k.ai, dU_dg);
  r.tj = cross(dU_dg, k.aj);

  if (k.inv_m > 0) {
    const P3 dU_dm = k.inv_m * (dU_dn - dot(n, dU_dn) * n);
    r.ti = r.ti - cross(k.ui, dU_dm);
    r.tj = r.tj - cross(k.uj, dU_dm);
  }

  const P3 p = cross(th, dU_dth);
  const P3 sym = dU_dth + k.rot.c * cross(th, p);
  r.ti = r.ti + (sym - 0.5 * p);
  r.tj = r.tj - (sym + 0.5 * p);
  return r;
}

inline Vec3 vec3(const P3& a) { return {a.x, a.y, a.z}; }
inline void add_to(Vec3& a, const P3& b) {
  a.x() += b.x;
  a.y() += b.y;
  a.z() += b.z;
}
inline void subtract_from(Vec3& a, const P3& b) {
  a.x() -= b.x;
  a.y() -= b.y;
  a.z() -= b.z;
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
  d.n = vec3(k.n);
  d.u_n = dot(k.g, k.n);
  d.u_s = vec3(k.g - d.u_n * k.n);
  d.theta_t = dot(k.rot.theta, k.n);
  d.theta_b = vec3(k.rot.theta - d.theta_t * k.n);
  return d;
}

BondResult bond_eval(const Bond& b, const Vec3& xi, const Quat& qi, const Vec3& xj,
                     const Quat& qj) {
  const Loads l = loads(b.k, kinematics(b, xi, qi, xj, qj));
  BondResult r;
  r.e_tension = l.e_tension;
  r.e_shear = l.e_shear;
  r.e_bending = l.e_bending;
  r.e_torsion = l.e_torsion;
  r.fi = vec3(l.fi);
  r.fj = -r.fi;
  r.ti = vec3(l.ti);
  r.tj = vec3(l.tj);
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
  rest_stale_ = true;
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
  if (sink.threads() < 1) throw std::logic_error("parallel_bond: force sink has no thread buffers");
  if (eval_ == BondEvaluation::Scalar)
    compute_scalar(el, sink);
  else
    compute_batched(el, sink);
}

// Bond by bond: the reference (bond_eval's kinematics and loads).
void ParallelBond::compute_scalar(const Elements& el, ForceSink& sink) const {
  const int nt = sink.threads();
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
#pragma omp for schedule(static) nowait
    for (std::size_t k = 0; k < nb; ++k) {
      const Bond& b = bonds_[k];
      const Loads l = loads(b.k, kinematics(b, x[b.i], q[b.i], dom.image(x[b.i], x[b.j]), q[b.j]));
      add_to(f[b.i], l.fi);
      subtract_from(f[b.j], l.fi);
      add_to(t[b.i], l.ti);
      add_to(t[b.j], l.tj);
      tally.tension += l.e_tension;
      tally.shear += l.e_shear;
      tally.bending += l.e_bending;
      tally.torsion += l.e_torsion;
    }
    tally.add_to(sink.energy(tid));
  }
}

void ParallelBond::build_rest() const {
  using namespace bond_simd;
  const std::size_t nb = bonds_.size();
  const std::size_t blocks = (nb + kMaxLanes - 1) / kMaxLanes;
  rest_index_.resize(2 * kMaxLanes * blocks);
  rest_.resize(kFields * kMaxLanes * blocks);
  for (std::size_t k = 0; k < blocks * kMaxLanes; ++k) {
    // Padding lanes: bond 0 again with zero stiffness (finite, never scattered).
    const Bond& b = k < nb ? bonds_[k] : bonds_[0];
    const std::size_t block = k / kMaxLanes, lane = k % kMaxLanes;
    rest_index_[2 * block * kMaxLanes + lane] = b.i;
    rest_index_[(2 * block + 1) * kMaxLanes + lane] = b.j;
    double* f = rest_.data() + block * kFields * kMaxLanes + lane;
    auto set = [&](Field field, double v) { f[field * kMaxLanes] = v; };
    for (int c = 0; c < 3; ++c) {
      set(static_cast<Field>(kCix + c), b.ci[c]);
      set(static_cast<Field>(kCjx + c), b.cj[c]);
      set(static_cast<Field>(kNix + c), b.ni[c]);
      set(static_cast<Field>(kNjx + c), b.nj[c]);
    }
    const Quat p = b.q_rel0.conjugate();
    set(kPw, p.w());
    set(kPx, p.x());
    set(kPy, p.y());
    set(kPz, p.z());
    const bool pad = k >= nb;
    set(kKnArea, pad ? 0.0 : b.k.kn_area);
    set(kKsArea, pad ? 0.0 : b.k.ks_area);
    set(kKnInertia, pad ? 0.0 : b.k.kn_inertia);
    set(kKsPolar, pad ? 0.0 : b.k.ks_polar);
  }
  rest_stale_ = false;
}

// In chunks of bond_simd::kChunk bonds (the threads take whole chunks, in order): the chunk's
// loads in SIMD lanes, the lanes the kernel leaves (large rotations, a 180° bend, NaN) by the
// scalar code, then scattered bond by bond in bond order. Energies summed per term: the kernel's
// lanes per lane over the chunk, then the chunk's scalar bonds, chunk after chunk (a fixed order
// for a given thread count and instruction set).
void ParallelBond::compute_batched(const Elements& el, ForceSink& sink) const {
  static_assert(sizeof(Vec3) == 3 * sizeof(double) && sizeof(Quat) == 4 * sizeof(double));
  if (rest_stale_) build_rest();
  const int nt = sink.threads();
  const std::size_t nb = bonds_.size();
  const Vec3* x = el.x.data();
  const Quat* q = el.q.data();
  const Domain& dom = domain();
  const bond_simd::Rest r{rest_index_.data(), rest_.data()};
  bond_simd::Bodies bodies{x[0].data(), q[0].coeffs().data(), dom.any_periodic(), {}, {}};
  const Vec3 len = dom.length();
  for (int a = 0; a < 3; ++a)
    if (dom.periodic(a)) {
      bodies.length[a] = len[a];
      bodies.inv_length[a] = 1.0 / len[a];
    }

  const long chunks = static_cast<long>((nb + bond_simd::kChunk - 1) / bond_simd::kChunk);
#pragma omp parallel num_threads(nt) if (static_cast <long>(nb) >= kParallelMinItems)
  {
    const int tid = omp_get_thread_num();
    Vec3* f = sink.force(tid);
    Vec3* t = sink.torque(tid);
    BondTally tally;
    bond_simd::Out out;
#pragma omp for schedule(static) nowait
    for (long c = 0; c < chunks; ++c) {
      const std::size_t begin = static_cast<std::size_t>(c) * bond_simd::kChunk;
      const std::size_t count = std::min(bond_simd::kChunk, nb - begin);
      const std::size_t lanes =
          (count + bond_simd::kMaxLanes - 1) / bond_simd::kMaxLanes * bond_simd::kMaxLanes;
      std::uint64_t scalar = bond_simd::evaluate(r, bodies, begin, lanes, out);
      scalar &= count == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << count) - 1;
      for (; scalar; scalar &= scalar - 1) {
        const int l = std::countr_zero(scalar);
        const Bond& b = bonds_[begin + l];
        const Loads s =
            loads(b.k, kinematics(b, x[b.i], q[b.i], dom.image(x[b.i], x[b.j]), q[b.j]));
        out.fx[l] = s.fi.x, out.fy[l] = s.fi.y, out.fz[l] = s.fi.z;
        out.tix[l] = s.ti.x, out.tiy[l] = s.ti.y, out.tiz[l] = s.ti.z;
        out.tjx[l] = s.tj.x, out.tjy[l] = s.tj.y, out.tjz[l] = s.tj.z;
        tally.tension += s.e_tension;
        tally.shear += s.e_shear;
        tally.bending += s.e_bending;
        tally.torsion += s.e_torsion;
      }
      for (std::size_t l = 0; l < count; ++l) {
        const std::int64_t* ij = r.index + 2 * (begin + l) - l % bond_simd::kMaxLanes;
        const std::int64_t bi = ij[0], bj = ij[bond_simd::kMaxLanes];
        const P3 fi{out.fx[l], out.fy[l], out.fz[l]};
        add_to(f[bi], fi);
        subtract_from(f[bj], fi);
        add_to(t[bi], {out.tix[l], out.tiy[l], out.tiz[l]});
        add_to(t[bj], {out.tjx[l], out.tjy[l], out.tjz[l]});
      }
      tally.tension += out.e_tension;
      tally.shear += out.e_shear;
      tally.bending += out.e_bending;
      tally.torsion += out.e_torsion;
    }
    tally.add_to(sink.energy(tid));
  }
}

const char* bond_simd_target() { return bond_simd::target_name(); }

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
