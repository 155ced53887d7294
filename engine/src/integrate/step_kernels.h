#pragma once
// The per-element arithmetic of System::run's step: velocity Verlet's half kicks and drift with
// the energy books, PFC local damping, kinetic energy and the run guard's per-element checks.
//
// Every kernel is a template on the element's class. General reads the element's DOF modes and
// inertia and takes today's per-DOF branches (free, prescribed, fixed; isotropic or not);
// FreeIsotropic is the common element (all six DOFs free, isotropic inertia: every CNT segment of
// a film), for which the same code, with the modes and isotropy known at compile time, folds to a
// straight line without switches or per-DOF tests and without loading the prescribed velocities.
// It is one piece of code, so the two classes give the same results bit for bit
// (test_step_fast_path compares them on a scene mixing every kind of element).
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "mdem/core/elements.h"
#include "mdem/force/force_model.h"
#include "mdem/integrate/respa.h"

namespace mdem::step {

// The kernels are inlined into the pass over the elements, so its sums stay in registers and the
// class's constants fold (left to itself GCC calls them, with every sum through memory).
#define MDEM_STEP_KERNEL inline __attribute__((always_inline))

enum class ElementClass { General, FreeIsotropic };

// Whether element i may take the FreeIsotropic kernels. Read from its DOF modes at every pass
// (six bytes), not cached: protocols change the modes between any two steps (grips held and
// released, platens prescribed), and a caller may edit them between runs.
MDEM_STEP_KERNEL bool free_isotropic(const Elements& E, std::size_t i) {
  static_assert(static_cast<int>(DofMode::Free) == 0 && sizeof(E.dof[i]) == 6);
  std::uint32_t a;
  std::uint16_t b;
  std::memcpy(&a, E.dof[i].data(), 4);
  std::memcpy(&b, E.dof[i].data() + 4, 2);
  return (a | b) == 0 && E.is_isotropic(i);
}

// What the kernels read besides the elements; one per pass, copied into each thread's registers.
struct StepContext {
  Elements* E;
  Vec3* fd;  // damping force / torque per element (model dampers + local damping)
  Vec3* td;
  double dt, h;  // step, half step
  // Local damping in the second half kick: α (0 = off), whether the model dampers wrote fd/td
  // (else local damping starts them from zero), and multiple time stepping's held slow forces
  // with their weight (RespaSplit::net_weight; null when off).
  double alpha = 0;
  bool model_damping = false;
  const RespaSplit* net = nullptr;
  double w_net = 0;
  // The force evaluation's sink when its per-thread sums are still to be taken (ForceSink::take):
  // the second half kick then takes element i's forces (and model damping forces) first, in place
  // of a separate reduction pass. Null: E.f, E.t, fd, td hold them already.
  ForceSink* sink = nullptr;
};

// Free rotation of a rigid body with principal inertia I (body frame) over time h, by the
// symmetric splitting of Dullweber, Leimkuhler and McLachlan: each step is an exact rotation
// about one body axis, so the scheme stays stable and norm-preserving under fast spin.
inline void free_rotor(Quat& q, Vec3& L_world, const Vec3& I, double h) {
  Vec3 Lb = q.conjugate() * L_world;
  auto sub = [&](int axis, double tau) {
    const double phi = Lb[axis] / I[axis] * tau;
    Vec3 e = Vec3::Zero();
    e[axis] = phi;
    const Quat r = quat_exp(e);
    q = q * r;
    Lb = r.conjugate() * Lb;
  };
  sub(0, 0.5 * h);
  sub(1, 0.5 * h);
  sub(2, h);
  sub(1, 0.5 * h);
  sub(0, 0.5 * h);
  q.normalize();
  L_world = q * Lb;
}

inline Vec3 world_inertia_times(const Quat& q, const Vec3& I, const Vec3& w) {
  return q * (I.cwiseProduct(q.conjugate() * w));
}

inline Vec3 world_inertia_inverse_times(const Quat& q, const Vec3& I, const Vec3& L) {
  return q * ((q.conjugate() * L).cwiseQuotient(I));
}

// First half kick of one scalar DOF with inertia m (a mass, or an isotropic moment of inertia):
// the force at t_n acts for h = dt/2. Books the damping power at v_n, and half of the coming
// drift's work of the external load (free DOF) or of the constraint (prescribed DOF, including
// the kinetic energy it injects when its velocity changes).
MDEM_STEP_KERNEL void first_half_kick(DofMode mode, double& v, double F, double F_ext,
                                      double F_damp, double v_presc, double m, double inv_m,
                                      double h, double& work, double& diss) {
  const double v0 = v;
  diss -= F_damp * v0 * h;
  switch (mode) {
    case DofMode::Free:
      v = v0 + h * (F + F_ext + F_damp) * inv_m;
      work += F_ext * v * h;
      break;
    case DofMode::Prescribed:
      work += 0.5 * m * (v_presc * v_presc - v0 * v0);
      v = v_presc;
      work -= (F + F_damp) * v * h;
      break;
    case DofMode::Fixed:
      v = 0;
      break;
  }
}

// Second half kick of one scalar DOF with the forces at t_{n+1}: the other half of the drift's
// work, then the damping power at v_{n+1}.
MDEM_STEP_KERNEL void second_half_kick(DofMode mode, double& v, double F, double F_ext,
                                       double F_damp, double v_presc, double m, double inv_m,
                                       double h, double& work, double& diss) {
  switch (mode) {
    case DofMode::Free:
      work += F_ext * v * h;
      v += h * (F + F_ext + F_damp) * inv_m;
      break;
    case DofMode::Prescribed:
      work -= (F + F_damp) * v * h;
      work += 0.5 * m * (v_presc * v_presc - v * v);
      v = v_presc;
      break;
    case DofMode::Fixed:
      v = 0;
      break;
  }
  diss -= F_damp * v * h;
}

// Half kick of the angular momentum of an anisotropic body (all rotational DOFs free).
inline void kick_anisotropic(const Quat& q, const Vec3& I, Vec3& w, const Vec3& torque, double h) {
  const Vec3 L = world_inertia_times(q, I, w) + h * torque;
  w = world_inertia_inverse_times(q, I, L);
}

// DOF k's mode (k < 3 translation, else rotation about axis k − 3): Free for the FreeIsotropic
// class, where it is known at compile time and every switch on it folds away.
template <ElementClass C>
MDEM_STEP_KERNEL DofMode mode_of(const std::array<DofMode, 6>& dof, int k) {
  if constexpr (C == ElementClass::FreeIsotropic)
    return DofMode::Free;
  else
    return dof[k];
}

template <ElementClass C>
MDEM_STEP_KERNEL bool isotropic(const Elements& E, std::size_t i) {
  return C == ElementClass::FreeIsotropic || E.is_isotropic(i);
}

// sign(v) as 1, −1 or 0 (also for −0 and NaN), without a branch on the velocity's sign, which
// is random in a thermal system and would be mispredicted half of the time.
MDEM_STEP_KERNEL double sign_of(double v) { return static_cast<double>((v > 0) - (v < 0)); }

// PFC local damping on the unbalanced force of every free DOF of element i: F_k -= α|F_k|
// sign(v_k), added to the model dampers' forces in fd, td (or to zero without them).
// With multiple time stepping, net (kNet) adds w·(the held slow forces) to the unbalanced
// force: the net force F_fast + F_slow, not the kick's impulse (RespaSplit::net_weight).
// kNet: whether net is non-null, a template argument so that the per-DOF test folds.
template <ElementClass C, bool kNet>
MDEM_STEP_KERNEL void local_damping(const Elements& E, std::size_t i, double a, bool model_damping,
                                    Vec3& fd, Vec3& td, const RespaSplit* net, double w) {
  Vec3 nf = Vec3::Zero(), nt = Vec3::Zero();
  if constexpr (kNet) {
    nf = w * (net->f[i] + net->fd[i]);
    nt = w * (net->t[i] + net->td[i]);
  }
  if (!model_damping) {
    fd.setZero();
    td.setZero();
  }
  const auto& dof = E.dof[i];
  for (int k = 0; k < 3; ++k) {
    if (mode_of<C>(dof, k) == DofMode::Free) {
      double F = E.f[i][k] + E.f_ext[i][k] + fd[k];
      if constexpr (kNet) F += nf[k];
      fd[k] -= a * std::abs(F) * sign_of(E.v[i][k]);
    }
    if (mode_of<C>(dof, k + 3) == DofMode::Free) {
      double M = E.t[i][k] + E.t_ext[i][k] + td[k];
      if constexpr (kNet) M += nt[k];
      td[k] -= a * std::abs(M) * sign_of(E.w[i][k]);
    }
  }
}

// Kinetic energies of element i (translational, rotational).
MDEM_STEP_KERNEL double kinetic_translational(const Elements& E, std::size_t i) {
  return 0.5 * E.mass[i] * E.v[i].squaredNorm();
}
// An isotropic body's (the integrator's isotropic branch, moment of inertia I.x()) without the
// two quaternion rotations of the general form.
MDEM_STEP_KERNEL double kinetic_rotational(const Elements& E, std::size_t i, bool isotropic) {
  if (isotropic) return 0.5 * E.inertia[i].x() * E.w[i].squaredNorm();
  return 0.5 * E.w[i].dot(world_inertia_times(E.q[i], E.inertia[i], E.w[i]));
}

// The drift of an isotropic body's orientation, exp(φ) q with φ = ω dt, renormalised. Below
// |φ| = 0.1 rad (every step of a stable run: the runaway check stops at 1 rad) cos(|φ|/2) and
// sin(|φ|/2)/|φ| come from their Taylor series in x = |φ|²/4 (first omitted terms below 1e-19
// relative), without the square root, sine and cosine of quat_exp; the renormalisation of a
// product of unit quaternions (|q|² = 1 + e, |e| ~ 1e-16) from 1/√(1+e) = 1 − e/2 + 3e²/8 (exact to
// round-off below |e| = 1e-6), without a square root and divisions. Results equal quat_exp and
// normalized() to round-off.
MDEM_STEP_KERNEL Quat drift_orientation(const Vec3& phi, const Quat& q) {
  const double a2 = phi.squaredNorm();
  Quat r;
  if (a2 < 0.01) {
    const double x = 0.25 * a2;
    const double c =
        1 + x * (-1.0 / 2 +
                 x * (1.0 / 24 + x * (-1.0 / 720 + x * (1.0 / 40320 + x * (-1.0 / 3628800)))));
    const double s =
        0.5 * (1 + x * (-1.0 / 6 + x * (1.0 / 120 + x * (-1.0 / 5040 + x * (1.0 / 362880)))));
    r = Quat(c, s * phi.x(), s * phi.y(), s * phi.z());
  } else {
    r = quat_exp(phi);
  }
  Quat out = r * q;
  const double e = out.squaredNorm() - 1;
  if (std::abs(e) < 1e-6)
    out.coeffs() *= 1 + e * (-0.5 + 0.375 * e);
  else
    out.normalize();
  return out;
}

// The half kicks of element i's six DOFs, with the forces at t_n before the drift (kFirst) or
// with those at t_{n+1} after it, and their work and damping books; isotropic bodies DOF by DOF,
// anisotropic ones (all rotational DOFs free, checked in initialize) by their angular momentum.
// Returns whether the body is isotropic.
template <ElementClass C, bool kFirst>
MDEM_STEP_KERNEL bool half_kicks(const StepContext& c, std::size_t i, double& work, double& diss) {
  Elements& E = *c.E;
  const double h = c.h;
  auto kick = [&](DofMode mode, double& v, double F, double F_ext, double F_damp, double v_presc,
                  double m, double inv_m) __attribute__((always_inline)) {
    if constexpr (kFirst)
      first_half_kick(mode, v, F, F_ext, F_damp, v_presc, m, inv_m, h, work, diss);
    else
      second_half_kick(mode, v, F, F_ext, F_damp, v_presc, m, inv_m, h, work, diss);
  };
  const auto& dof = E.dof[i];
  for (int k = 0; k < 3; ++k)
    kick(mode_of<C>(dof, k), E.v[i][k], E.f[i][k], E.f_ext[i][k], c.fd[i][k], E.v_prescribed[i][k],
         E.mass[i], E.inv_mass[i]);
  const bool iso = isotropic<C>(E, i);
  if (iso) {
    const double I = E.inertia[i].x(), iI = 1.0 / I;
    for (int k = 0; k < 3; ++k)
      kick(mode_of<C>(dof, k + 3), E.w[i][k], E.t[i][k], E.t_ext[i][k], c.td[i][k],
           E.w_prescribed[i][k], I, iI);
  } else if (kFirst) {  // damping power at ω_n, the kick, half the load's work over the drift
    diss -= c.td[i].dot(E.w[i]) * h;
    kick_anisotropic(E.q[i], E.inertia[i], E.w[i], E.t[i] + E.t_ext[i] + c.td[i], h);
    work += E.t_ext[i].dot(E.w[i]) * h;
  } else {  // the other half of the work, the kick, the damping power at ω_{n+1}
    work += E.t_ext[i].dot(E.w[i]) * h;
    kick_anisotropic(E.q[i], E.inertia[i], E.w[i], E.t[i] + E.t_ext[i] + c.td[i], h);
    diss -= c.td[i].dot(E.w[i]) * h;
  }
  return iso;
}

// 1. First half kick of element i with the forces at t_n; books half of the work of external
//    loads and constraints over the coming drift, and the power of damping at v_n. Then the
//    drift: position, and orientation by the exact exponential map (isotropic bodies, where ω
//    is constant in free rotation) or the DLM splitting (anisotropic). False when the element
//    moved more than its radius or turned more than a radian: it is not being integrated any
//    more (the run guard stops the run).
template <ElementClass C>
MDEM_STEP_KERNEL bool first_element(const StepContext& c, std::size_t i, double& work,
                                    double& diss) {
  Elements& E = *c.E;
  const double dt = c.dt;
  double wk = 0, ds = 0;  // this element's share, then added to the sums (see second_element)
  const bool iso = half_kicks<C, true>(c, i, wk, ds);
  work += wk;
  diss += ds;
  const Vec3 dx = E.v[i] * dt;
  E.x[i] += dx;
  if (iso) {
    E.q[i] = drift_orientation(E.w[i] * dt, E.q[i]);
  } else {
    Vec3 L = world_inertia_times(E.q[i], E.inertia[i], E.w[i]);
    free_rotor(E.q[i], L, E.inertia[i], dt);
    E.w[i] = world_inertia_inverse_times(E.q[i], E.inertia[i], L);
  }
  const double r = E.radius[i];
  return (dx.squaredNorm() <= r * r) & (E.w[i].squaredNorm() * (dt * dt) <= 1.0);
}

// 2. Local damping of element i's new forces (with c.alpha > 0), second half kick with the
//    forces at t_{n+1}, the rest of the work and damping books, and the kinetic energy at
//    t_{n+1}. False for a non-finite velocity.
template <ElementClass C>
MDEM_STEP_KERNEL bool second_element(const StepContext& c, std::size_t i, double& work,
                                     double& diss, double& kt, double& kr) {
  Elements& E = *c.E;
  if (c.sink) c.sink->take(i, E.f[i], E.t[i], c.fd + i, c.td + i);
  if (c.alpha > 0 && c.net)
    local_damping<C, true>(E, i, c.alpha, c.model_damping, c.fd[i], c.td[i], c.net, c.w_net);
  else if (c.alpha > 0)
    local_damping<C, false>(E, i, c.alpha, c.model_damping, c.fd[i], c.td[i], nullptr, 0);
  // The element's terms are summed first and then added to the pass's sums, one addition per
  // sum and element (the lanes, step_simd.h, add their elements' shares in element order).
  double wk = 0, ds = 0;
  const bool iso = half_kicks<C, false>(c, i, wk, ds);
  work += wk;
  diss += ds;
  kt += kinetic_translational(E, i);
  kr += kinetic_rotational(E, i, iso);
  // Finite iff 0·v and 0·w are all zero (0·inf and 0·NaN are NaN): one test, not six.
  const Vec3& v = E.v[i];
  const Vec3& w = E.w[i];
  const double z =
      0.0 * v.x() + 0.0 * v.y() + 0.0 * v.z() + 0.0 * w.x() + 0.0 * w.y() + 0.0 * w.z();
  return z == 0.0;
}

#undef MDEM_STEP_KERNEL

}  // namespace mdem::step
