// The integrator's FreeIsotropic kernels (step_kernels.h) over lanes of consecutive elements
// (step_simd.h). Every expression below is the scalar kernel's, operation for operation, named
// after the function it mirrors; where Eigen fixes an order (squared norms, the quaternion
// product of its SSE2 path), the lanes take that order.
#include "integrate/step_simd.h"

#include <cstdint>
#include <cstring>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "integrate/step_simd.cpp"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"

HWY_BEFORE_NAMESPACE();
namespace mdem::step_simd {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::ScalableTag<double>;
using V = hn::Vec<D>;
constexpr std::size_t kMax = HWY_MAX_BYTES / sizeof(double);

struct V3 {
  V x, y, z;
};

HWY_INLINE V3 load3(const double* p, long i) {
  const D d;
  V3 r;
  hn::LoadInterleaved3(d, p + 3 * i, r.x, r.y, r.z);
  return r;
}
HWY_INLINE void store3(const V3& a, double* p, long i) {
  hn::StoreInterleaved3(a.x, a.y, a.z, D(), p + 3 * i);
}
// The three vectors' worth of doubles of a chunk's Vec3 array set to zero (ForceSink::take).
HWY_INLINE void zero3(double* p, long i) {
  const D d;
  const std::size_t n = hn::Lanes(d);
  const V z = hn::Zero(d);
  hn::StoreU(z, d, p + 3 * i);
  hn::StoreU(z, d, p + 3 * i + n);
  hn::StoreU(z, d, p + 3 * i + 2 * n);
}
// ForceSink::take's sum of the threads' buffers b[0 .. nt), in thread order.
HWY_INLINE V3 thread_sum(double* const* b, int nt, long i) {
  V3 s = load3(b[0], i);
  for (int k = 1; k < nt; ++k) {
    const V3 o = load3(b[k], i);
    s = {s.x + o.x, s.y + o.y, s.z + o.z};
  }
  return s;
}
// Eigen's Vector3d::squaredNorm(): (x² + y²) + z².
HWY_INLINE V sq3(const V3& a) { return (a.x * a.x + a.y * a.y) + a.z * a.z; }

// sign_of(v): 1, −1 or 0 (also for −0 and NaN).
HWY_INLINE V sign_of(V v) {
  const D d;
  const V zero = hn::Zero(d);
  return hn::IfThenElse(hn::Gt(v, zero), hn::Set(d, 1.0),
                        hn::IfThenElseZero(hn::Lt(v, zero), hn::Set(d, -1.0)));
}

// One component of local_damping: fd −= α|F| sign(v), F = f + f_ext + fd.
HWY_INLINE V damp(V f, V fe, V fd, V v, V a) {
  const V F = (f + fe) + fd;
  return fd - (a * hn::Abs(F)) * sign_of(v);
}

// The terms each pass adds to its books, per DOF in the scalar kernels' order (translation x, y,
// z, then rotation x, y, z), one vector per term.
struct Terms {
  V work[6], diss[6];
};

// One DOF's half kick, Free, with the terms of its books: first_half_kick books the damping at
// v_n and the load at the kicked velocity, second_half_kick the load at the velocity before the
// kick and the damping after it (work += F_ext v h, diss −= F_damp v h; v += h (F + F_ext +
// F_damp)/m).
template <bool kFirst>
HWY_INLINE void kick(V& v, V F, V Fe, V Fd, V inv_m, V h, V& work, V& diss) {
  const V v0 = v;
  v = v0 + (h * ((F + Fe) + Fd)) * inv_m;
  work = (Fe * (kFirst ? v : v0)) * h;
  diss = (Fd * (kFirst ? v0 : v)) * h;
}

template <bool kFirst>
HWY_INLINE void kicks(V3& v, V3& w, const V3& f, const V3& t, const V3& fe, const V3& te,
                      const V3& fd, const V3& td, V inv_m, V inv_I, V h, Terms& s) {
  kick<kFirst>(v.x, f.x, fe.x, fd.x, inv_m, h, s.work[0], s.diss[0]);
  kick<kFirst>(v.y, f.y, fe.y, fd.y, inv_m, h, s.work[1], s.diss[1]);
  kick<kFirst>(v.z, f.z, fe.z, fd.z, inv_m, h, s.work[2], s.diss[2]);
  kick<kFirst>(w.x, t.x, te.x, td.x, inv_I, h, s.work[3], s.diss[3]);
  kick<kFirst>(w.y, t.y, te.y, td.y, inv_I, h, s.work[4], s.diss[4]);
  kick<kFirst>(w.z, t.z, te.z, td.z, inv_I, h, s.work[5], s.diss[5]);
}

// The lanes' shares of a pass's work and dissipation: each lane's terms summed in the scalar
// kernels' order from zero (their w, d), the dissipation terms subtracted.
HWY_INLINE void shares(const Terms& s, V& work, V& diss) {
  const V zero = hn::Zero(D());
  work = zero;
  diss = zero;
  for (int k = 0; k < 6; ++k) {
    work = work + s.work[k];
    diss = diss - s.diss[k];
  }
}
// Adds the lanes of each vector to its running sum, lane by lane (element order): the scalar
// loop's sequence of additions.
template <int K>
HWY_INLINE void book(const V (&v)[K], double* const (&sum)[K]) {
  const D d;
  const std::size_t n = hn::Lanes(d);
  HWY_ALIGN double b[K * kMax];
  for (int k = 0; k < K; ++k) hn::Store(v[k], d, b + k * n);
  double acc[K];
  for (int k = 0; k < K; ++k) acc[k] = *sum[k];
  for (std::size_t l = 0; l < n; ++l)
    for (int k = 0; k < K; ++k) acc[k] += b[k * n + l];
  for (int k = 0; k < K; ++k) *sum[k] = acc[k];
}

// Whether the chunk at i has isotropic inertia (set to the chunk's).
HWY_INLINE bool isotropic(const Pass& p, long i, V3& inertia) {
  const D d;
  inertia = load3(p.inertia, i);
  const V tol = hn::Set(d, 1e-12) * inertia.x;
  const auto iso = hn::And(hn::Le(hn::Abs(inertia.x - inertia.y), tol),
                           hn::Le(hn::Abs(inertia.x - inertia.z), tol));
  return hn::AllTrue(d, iso);
}

// Whether no element of the chunk at i has a DOF other than free (step::free_isotropic's test).
HWY_INLINE bool all_free(const Pass& p, long i) {
  const std::size_t n = hn::Lanes(D());
  unsigned char any = 0;
  for (std::size_t b = 0; b < 6 * n; ++b) any |= p.dof[6 * i + b];
  return any == 0;
}

// Whether every element of the chunk at i is free or clamped (translation prescribed, rotation
// fixed: a tensile grip's element); clamped is set to 1 in the clamped lanes and 0 in the others.
HWY_INLINE bool free_or_clamped(const Pass& p, long i, V& clamped) {
  const D d;
  const std::size_t n = hn::Lanes(d);
  constexpr unsigned char P = kDofPrescribed, F = kDofFixed;
  constexpr unsigned char kClamp[6] = {P, P, P, F, F, F};
  HWY_ALIGN double c[kMax];
  for (std::size_t l = 0; l < n; ++l) {
    const unsigned char* m = p.dof + 6 * (i + static_cast<long>(l));
    unsigned char any = 0;
    for (int k = 0; k < 6; ++k) any |= m[k];
    if (any != 0 && std::memcmp(m, kClamp, 6) != 0) return false;
    c[l] = any != 0 ? 1.0 : 0.0;
  }
  clamped = hn::Load(d, c);
  return true;
}

// A clamped element's half kick of its translation (first_half_kick / second_half_kick,
// Prescribed: the velocity set to vp, the constraint's work and the kinetic energy it injects
// booked in the scalar kernels' order; its rotation, Fixed, books no work) and the share of its
// work book; the damping terms are the free kicks' expressions at the clamped velocities.
template <bool kFirst>
HWY_INLINE V clamped_kick(V3& v, const V3& f, const V3& fd, const V3& vp, V m, V h) {
  const V half_m = hn::Set(D(), 0.5) * m;
  V work = hn::Zero(D());
  V* vs[3] = {&v.x, &v.y, &v.z};
  const V* fs[3] = {&f.x, &f.y, &f.z};
  const V* fds[3] = {&fd.x, &fd.y, &fd.z};
  const V* vps[3] = {&vp.x, &vp.y, &vp.z};
  for (int k = 0; k < 3; ++k) {
    const V v0 = *vs[k], p = *vps[k];
    const V injected = half_m * ((p * p) - (v0 * v0));  // ½ m (vp² − v0²)
    // The constraint's work, −(F + F_damp) v h, at the velocity after the kick (first half) or
    // before it (second half).
    const V constraint = ((*fs[k] + *fds[k]) * (kFirst ? p : v0)) * h;
    work = kFirst ? (work + injected) - constraint : (work - constraint) + injected;
    *vs[k] = p;
  }
  return work;
}

// The chunk at i, whose lanes are isotropic (inertia I3) and free, or with kClamped free or
// clamped (the lanes of `clamped`); without kClamped none of the clamped arithmetic is compiled
// in. False (nothing written) when a lane leaves the common branches.
template <bool kSecond, bool kFirst, bool kClamped>
HWY_INLINE bool chunk(const Pass& p, long i, const V3& I3, hn::Mask<D> clamped, double* s2,
                      double* s1, long* runaway) {
  const D d;
  const V h = hn::Set(d, p.h);
  const V zero = hn::Zero(d);
  const V m = hn::LoadU(d, p.mass + i), inv_m = hn::LoadU(d, p.inv_mass + i);
  const V I = I3.x, inv_I = hn::Set(d, 1.0) / I;
  V3 v = load3(p.v, i), w = load3(p.w, i);
  const V3 none{zero, zero, zero};
  const V3 fe = p.f_ext ? load3(p.f_ext, i) : none, te = p.t_ext ? load3(p.t_ext, i) : none;
  // Loads of what the sink may replace; its buffers are zeroed only once the chunk is known good.
  const bool sink = kSecond && p.sink_threads > 0;
  const bool sink_damp = sink && p.sink_fd != nullptr;
  const int nt = p.sink_threads;
  const V3 f = sink ? thread_sum(p.sink_f, nt, i) : load3(p.f, i);
  const V3 t = sink ? thread_sum(p.sink_t, nt, i) : load3(p.t, i);
  const bool damped = kSecond && p.alpha > 0;
  // Local damping without model dampers starts fd, td from zero (local_damping): not loaded.
  const bool fd_from_zero = damped && !p.model_damping;
  V3 fd = fd_from_zero ? none : sink_damp ? thread_sum(p.sink_fd, nt, i) : load3(p.fd, i);
  V3 td = fd_from_zero           ? none
          : !sink_damp           ? load3(p.td, i)
          : p.sink_td != nullptr ? thread_sum(p.sink_td, nt, i)
                                 : none;
  const V3 vp = kClamped ? load3(p.v_prescribed, i) : none;
  // The clamped lanes' kicks (clamped_kick) replace the free ones' results in those lanes: the
  // velocities (the rotation's zero), the damping terms and the share of the work book (cw).
  const auto clamp = [&]<bool kF>(V3 & vel, V3 & ang, const V3& v_in, const V3& w_in, Terms& s,
                                  V& cw) __attribute__((always_inline)) {
    V3 vc = v_in;
    cw = clamped_kick<kF>(vc, f, fd, vp, m, h);
    const V3* dv = kF ? &v_in : &vc;  // the damping's velocity: before or after the kick
    const V3 dw = kF ? w_in : none;
    const V cd[6] = {(fd.x * dv->x) * h, (fd.y * dv->y) * h, (fd.z * dv->z) * h,
                     (td.x * dw.x) * h,  (td.y * dw.y) * h,  (td.z * dw.z) * h};
    for (int k = 0; k < 6; ++k) s.diss[k] = hn::IfThenElse(clamped, cd[k], s.diss[k]);
    vel = {hn::IfThenElse(clamped, vc.x, vel.x), hn::IfThenElse(clamped, vc.y, vel.y),
           hn::IfThenElse(clamped, vc.z, vel.z)};
    ang = {hn::IfThenZeroElse(clamped, ang.x), hn::IfThenZeroElse(clamped, ang.y),
           hn::IfThenZeroElse(clamped, ang.z)};
  };
  Terms t2, t1;
  V cw2 = zero, cw1 = zero;  // the clamped lanes' work shares
  V kt = zero, kr = zero;
  if constexpr (kSecond) {
    if (damped) {  // local_damping, of the free DOFs only
      const V a = hn::Set(d, p.alpha);
      const V3 fd0 = fd, td0 = td;
      fd = {damp(f.x, fe.x, fd.x, v.x, a), damp(f.y, fe.y, fd.y, v.y, a),
            damp(f.z, fe.z, fd.z, v.z, a)};
      td = {damp(t.x, te.x, td.x, w.x, a), damp(t.y, te.y, td.y, w.y, a),
            damp(t.z, te.z, td.z, w.z, a)};
      if constexpr (kClamped) {
        fd = {hn::IfThenElse(clamped, fd0.x, fd.x), hn::IfThenElse(clamped, fd0.y, fd.y),
              hn::IfThenElse(clamped, fd0.z, fd.z)};
        td = {hn::IfThenElse(clamped, td0.x, td.x), hn::IfThenElse(clamped, td0.y, td.y),
              hn::IfThenElse(clamped, td0.z, td.z)};
      }
    }
    const V3 v_in = v, w_in = w;
    kicks<false>(v, w, f, t, fe, te, fd, td, inv_m, inv_I, h, t2);
    if constexpr (kClamped) clamp.template operator()<false>(v, w, v_in, w_in, t2, cw2);
    const V half = hn::Set(d, 0.5);
    kt = (half * m) * sq3(v);
    kr = (half * I) * sq3(w);
    // Finite iff 0·v and 0·w are all zero.
    const V z = ((((zero * v.x + zero * v.y) + zero * v.z) + zero * w.x) + zero * w.y) + zero * w.z;
    if (!hn::AllTrue(d, hn::Eq(z, zero))) return false;
  }
  V3 x{}, dx{};
  V qx = zero, qy = zero, qz = zero, qw = zero;
  if constexpr (kFirst) {
    const V3 v_in = v, w_in = w;
    kicks<true>(v, w, f, t, fe, te, fd, td, inv_m, inv_I, h, t1);
    if constexpr (kClamped) clamp.template operator()<true>(v, w, v_in, w_in, t1, cw1);
    const V dt = hn::Set(d, p.dt);
    dx = {v.x * dt, v.y * dt, v.z * dt};
    x = load3(p.x, i);
    x = {x.x + dx.x, x.y + dx.y, x.z + dx.z};
    // drift_orientation(ω dt, q), series branch.
    const V3 phi{w.x * dt, w.y * dt, w.z * dt};
    const V a2 = sq3(phi);
    if (!hn::AllTrue(d, hn::Lt(a2, hn::Set(d, 0.01)))) return false;
    const V xs = hn::Set(d, 0.25) * a2;
    auto c_ = [&](double k) { return hn::Set(d, k); };
    const V c =
        c_(1) + xs * (c_(-1.0 / 2) +
                      xs * (c_(1.0 / 24) + xs * (c_(-1.0 / 720) + xs * (c_(1.0 / 40320) +
                                                                        xs * c_(-1.0 / 3628800)))));
    const V s =
        c_(0.5) *
        (c_(1) + xs * (c_(-1.0 / 6) +
                       xs * (c_(1.0 / 120) + xs * (c_(-1.0 / 5040) + xs * c_(1.0 / 362880)))));
    const V rw = c, rx = s * phi.x, ry = s * phi.y, rz = s * phi.z;
    V bx, by, bz, bw;
    hn::LoadInterleaved4(d, p.q + 4 * i, bx, by, bz, bw);
    // Eigen's quaternion product r * q (its SSE2 path, Geometry_SIMD.h).
    qx = (rw * bx + ry * bz) - (rz * by - rx * bw);
    qy = (rw * by + ry * bw) + (rz * bx - rx * bz);
    qz = (rw * bz - ry * bx) + (rz * bw + rx * by);
    qw = (rw * bw - ry * by) - (rz * bz + rx * bx);
    // Eigen's Vector4d::squaredNorm(): (x² + z²) + (y² + w²).
    const V e = ((qx * qx + qz * qz) + (qy * qy + qw * qw)) - c_(1);
    if (!hn::AllTrue(d, hn::Lt(hn::Abs(e), c_(1e-6)))) return false;
    const V g = c_(1) + e * (c_(-0.5) + c_(0.375) * e);
    qx = qx * g;
    qy = qy * g;
    qz = qz * g;
    qw = qw * g;
  }
  // The chunk is good: write it (the forces only where they are kept, Pass::keep_forces).
  const bool keep = !(kSecond && kFirst) || p.keep_forces;
  if (sink) {
    for (int k = 0; k < p.sink_threads; ++k) {
      zero3(p.sink_f[k], i);
      zero3(p.sink_t[k], i);
      if (sink_damp) zero3(p.sink_fd[k], i);
      if (sink_damp && p.sink_td != nullptr) zero3(p.sink_td[k], i);
    }
    if (keep) {
      store3(f, p.f, i);
      store3(t, p.t, i);
    }
  }
  if ((sink_damp || damped) && keep) {
    store3(fd, p.fd, i);
    store3(td, p.td, i);
  }
  store3(v, p.v, i);
  store3(w, p.w, i);
  // Each pass's shares: the clamped lanes' work from clamped_kick.
  const auto pass_shares = [&](const Terms& s, V cw, V& work, V& diss)
      __attribute__((always_inline)) {
    shares(s, work, diss);
    if constexpr (kClamped) work = hn::IfThenElse(clamped, cw, work);
  };
  if constexpr (kSecond && kFirst) {
    V w2, d2, w1, d1;
    pass_shares(t2, cw2, w2, d2);
    pass_shares(t1, cw1, w1, d1);
    book<6>({w2, d2, kt, kr, w1, d1}, {s2, s2 + 1, s2 + 2, s2 + 3, s1, s1 + 1});
  } else if constexpr (kSecond) {
    V w2, d2;
    pass_shares(t2, cw2, w2, d2);
    book<4>({w2, d2, kt, kr}, {s2, s2 + 1, s2 + 2, s2 + 3});
  } else {
    V w1, d1;
    pass_shares(t1, cw1, w1, d1);
    book<2>({w1, d1}, {s1, s1 + 1});
  }
  if constexpr (kFirst) {
    store3(x, p.x, i);
    hn::StoreInterleaved4(qx, qy, qz, qw, d, p.q + 4 * i);
    // The runaway check of first_element.
    const V r = hn::LoadU(d, p.radius + i);
    const V dt = hn::Set(d, p.dt);
    const auto ok = hn::And(hn::Le(sq3(dx), r * r), hn::Le(sq3(w) * (dt * dt), hn::Set(d, 1.0)));
    if (!hn::AllTrue(d, ok)) {
      HWY_ALIGN double okb[kMax];
      hn::Store(hn::IfThenElseZero(ok, hn::Set(d, 1.0)), d, okb);
      for (std::size_t l = 0; l < hn::Lanes(d); ++l)
        if (okb[l] == 0) *runaway = i + static_cast<long>(l);
    }
  }
  return true;
}

// A chunk with an element that is not free: run in lanes when every element is free or clamped
// (and isotropic). Out of line, so that the free chunks' loop stays as compact as without it.
template <bool kSecond, bool kFirst>
HWY_NOINLINE bool clamped_chunk(const Pass& p, long i, double* s2, double* s1, long* runaway) {
  V clamped;
  V3 inertia;
  if (!free_or_clamped(p, i, clamped) || !isotropic(p, i, inertia)) return false;
  return chunk<kSecond, kFirst, true>(p, i, inertia, hn::Gt(clamped, hn::Zero(D())), s2, s1,
                                      runaway);
}

// The chunk at i, whichever its lanes' classes; false when it goes to the scalar kernels.
template <bool kSecond, bool kFirst>
HWY_INLINE bool any_chunk(const Pass& p, long i, double* s2, double* s1, long* runaway) {
  if (!all_free(p, i)) return clamped_chunk<kSecond, kFirst>(p, i, s2, s1, runaway);
  V3 inertia;
  if (!isotropic(p, i, inertia)) return false;
  return chunk<kSecond, kFirst, false>(p, i, inertia, hn::FirstN(D(), 0), s2, s1, runaway);
}

template <bool kSecond, bool kFirst>
long RunChunks(const Pass& p, long i, long e, double* s2, double* s1, long* runaway) {
  const long n = static_cast<long>(hn::Lanes(D()));
  while (i + n <= e && any_chunk<kSecond, kFirst>(p, i, s2, s1, runaway)) i += n;
  return i;
}

long Run(const Pass& p, long i, long e, double* s2, double* s1, long* runaway) {
  if (p.second && p.first) return RunChunks<true, true>(p, i, e, s2, s1, runaway);
  if (p.second) return RunChunks<true, false>(p, i, e, s2, s1, runaway);
  if (p.first) return RunChunks<false, true>(p, i, e, s2, s1, runaway);
  return i;
}

std::size_t Lanes() { return hn::Lanes(D()); }
const char* TargetName() { return hwy::TargetName(HWY_TARGET); }

}  // namespace HWY_NAMESPACE
}  // namespace mdem::step_simd
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace mdem::step_simd {

HWY_EXPORT(Run);
HWY_EXPORT(Lanes);
HWY_EXPORT(TargetName);

long run(const Pass& p, long i, long e, double* second, double* first, long* runaway) {
  return HWY_DYNAMIC_DISPATCH(Run)(p, i, e, second, first, runaway);
}
std::size_t lanes() { return HWY_DYNAMIC_DISPATCH(Lanes)(); }
const char* target_name() { return HWY_DYNAMIC_DISPATCH(TargetName)(); }

}  // namespace mdem::step_simd
#endif
