#pragma once
// Multiple time stepping: the reversible reference system propagator (r-RESPA) of Tuckerman, Berne
// and Martyna (J. Chem. Phys. 97, 1990 (1992)) in its velocity-Verlet form. The models split by
// their Timescale (force_model.h): fast ones act every inner step dt, slow ones once per outer
// step of k inner steps, as two impulses of (k·dt/2)·F_slow at the outer step's start and end:
//
//   v += (k·dt/2)·F_slow/m;  k × [v += (dt/2)·F_fast/m; x += dt·v; F_fast(x); v +=
//   (dt/2)·F_fast/m]; F_slow(x); v += (k·dt/2)·F_slow/m
//
// The system's integrator stays velocity Verlet on an effective force: F_fast + k·F_slow at an
// evaluation that closes an outer step (and so opens the next), F_fast in between. Its kicks,
// constraints, local damping and energy books then carry the slow impulses without a second path,
// and k = 1 is the plain integrator bit for bit (System::compute_forces takes the one-sink path).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mdem/core/energy.h"
#include "mdem/core/math.h"
#include "mdem/force/force_model.h"

namespace mdem {

class RespaSplit {
 public:
  // k inner steps per outer step (1 = off) for n elements; checked by the system's initialize.
  void setup(int k, std::size_t n);
  int k() const { return k_; }
  bool on() const { return k_ > 1; }
  // Whether the force evaluation after `step` steps (0: the initial state) closes an outer step.
  bool closes_outer_step(long step) const { return step % k_ == 0; }
  // Whether model m is evaluated with the inner (fast) forces: every model when off.
  bool inner(const ForceModel& m) const { return !on() || m.timescale() == Timescale::Fast; }
  bool slow(const ForceModel& m) const { return on() && m.timescale() == Timescale::Slow; }

  // The slow models' forces of the last outer evaluation (ForceSink::reduce fills them), held
  // through the outer step, in the element order of `tags`.
  std::vector<Vec3> f, t, fd, td;
  std::vector<std::uint64_t> tags;
  // Their energy at the last outer evaluation: the stored energy stands for them in between.
  EnergyTally tally;

  // Adds k·(f, t) to (ef, et), and k·(fd, td) to (efd, etd) with damping: the effective force.
  void add_impulse(std::vector<Vec3>& ef, std::vector<Vec3>& et, std::vector<Vec3>& efd,
                   std::vector<Vec3>& etd, bool damping) const;
  // Local damping acts on the net force F_fast + F_slow, not on the impulse the kick applies:
  // the weight of the held slow forces to add to the effective force after the evaluation that
  // ends step `step`: 1 - k where it holds k·F_slow, 1 in between (0 when off: k = 1).
  double net_weight(long step) const { return closes_outer_step(step) ? 1.0 - k_ : 1.0; }
  // Puts the held forces in el's element order (after a reordering of the elements).
  void follow(const Elements& el);
  // The slow models' stored energy between outer evaluations: what they released was booked
  // once, at their evaluation.
  EnergyTally held() const {
    EnergyTally e = tally;
    e.released = 0;
    return e;
  }

 private:
  int k_ = 1;
};

}  // namespace mdem
