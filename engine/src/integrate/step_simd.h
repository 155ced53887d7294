#pragma once
// The integrator's per-element arithmetic (step_kernels.h) for the FreeIsotropic class over
// lanes of consecutive elements, on the widest instruction set of the running CPU (Google
// Highway's dynamic dispatch, as the pair kernels). Each lane does the scalar kernel's operations
// in the scalar kernel's order (no fused multiply-adds: the file is compiled with
// -ffp-contract=off), and each element's share of the energy books is added to them in element
// order, so the results are the scalar path's bit for bit (test_step_fast_path).
//
// A chunk of lanes is run only when every element in it is isotropic, either free or clamped
// (translation prescribed, rotation fixed: a tensile grip's element, whose lanes take
// first_half_kick's and second_half_kick's Prescribed and Fixed branches), and takes the
// common branches (orientation drift below 0.1 rad, renormalisation by the series, finite
// velocities); otherwise nothing of the chunk is written and the caller runs it with the scalar
// kernels, which also name what went wrong.
#include <cstddef>

namespace mdem::step_simd {

// DofMode's values (static_assert in system.cpp): the free ones are 0.
inline constexpr unsigned char kDofFixed = 1, kDofPrescribed = 2;

// One pass over the elements: the arrays of Elements and of the system's damping buffers as
// doubles (a Vec3 is 3, a quaternion x, y, z, w), and the pass's settings.
struct Pass {
  double *x, *q, *v, *w, *f, *t, *fd, *td;
  const double *f_ext, *t_ext, *mass, *inv_mass, *inertia, *radius;  // f_ext, t_ext null: all zero
  const double* v_prescribed;                                        // read in clamped lanes only
  const unsigned char* dof;  // 6 DofMode bytes per element (Free = 0)
  // The force evaluation's per-thread buffers when its sums are still to be taken
  // (ForceSink::take): sink[k] for thread k, force, torque, and the damping force and torque
  // (null when the sink has no damping buffers; sink_td also when it has no damping torque
  // buffers, td then zero); sink_threads = 0 when f, t, fd, td hold them.
  double* const* sink_f = nullptr;
  double* const* sink_t = nullptr;
  double* const* sink_fd = nullptr;
  double* const* sink_td = nullptr;
  int sink_threads = 0;
  double dt = 0, h = 0;
  double alpha = 0;            // local damping (second pass only; 0 = off)
  bool model_damping = false;  // the model dampers wrote fd, td (else local damping zeroes them)
  // With second and first (one element's pass 2 and the next step's pass 1 in one go): whether
  // pass 2 stores the forces it kicks with (f, t, and fd, td where it changes them); false when
  // nothing reads them before a later pass stores them (Updater::reads_forces), which spares ~96
  // bytes of stores per element and step: pass 1 kicks with them from registers.
  bool keep_forces = true;
  bool second = false;  // 2.: take, local damping, second half kick, kinetic energy
  bool first = false;   // 1.: first half kick and drift (after 2. when both)
};

// Runs elements from i on, a chunk of lanes() at a time, while a whole chunk fits below e and
// can be run (see above); returns where it stopped (e, or the start of a chunk for the scalar
// kernels). second: the running sums work, diss, kt, kr of pass 2; first: work, diss of pass 1;
// each gets its elements' shares in element order, as from the scalar kernels. *runaway: set to the
// largest index that moved more than its radius or turned more than a radian in the drift (as the
// scalar kernel marks it; the element is still integrated).
long run(const Pass& p, long i, long e, double* second, double* first, long* runaway);

// The lanes of a chunk (8 with AVX-512) and the instruction set, e.g. "AVX3", "EMU128".
std::size_t lanes();
const char* target_name();

}  // namespace mdem::step_simd
