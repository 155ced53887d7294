#pragma once
// Wall time spent in the parts of System::run, for the timing breakdown `mdem run` prints at the
// end of a job (LAMMPS's "Loop time" block). System adds to its StepTimers in run() only
// (steady_clock per part and step, never per pair or element: 7 clock reads a step) and exposes
// them as System::timers(); the client passes them to print_loop_timing
// (client/src/loop_timing.h), which splits its "engine steps" row by them. Wall time, not
// checkpointed: a resumed run counts from its resumption.
namespace mdem {

struct StepTimers {
  double pair_s = 0;       // the force evaluation: every model's forces, torques and energies
                           // (bonds, pair kernels, walls, dampers); the per-thread sums of a
                           // step are taken in the integrator's pass (integrate_s), those of a
                           // step under multiple time stepping here
  double neighbor_s = 0;   // neighbour-list checks and rebuilds
  double integrate_s = 0;  // kicks, drift, local damping, kinetic energy, the run guard (and
                           // the per-thread force sums, ForceSink::take)
  double updaters_s = 0;   // protocols and every-step observers (System::add_updater)
  double total() const { return pair_s + neighbor_s + integrate_s + updaters_s; }
};

}  // namespace mdem
