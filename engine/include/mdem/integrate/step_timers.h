#pragma once
// Wall time spent in the parts of System::run, for the timing breakdown `mdem run` prints at the
// end of a job (LAMMPS's "Loop time" block). Not wired yet: System does not fill it. The wiring
// the client expects: System holds one StepTimers, adds to it in run() (steady_clock around the
// force evaluation's pair loop, the neighbour-list rebuilds, the kicks and drift, and the
// updaters), and exposes it as `const StepTimers& timers() const`; the client then passes it to
// print_loop_timing (client/src/loop_timing.h), which splits its "engine steps" row by it.
namespace mdem {

struct StepTimers {
  double pair_s = 0;       // pair forces (contact, vdW, NP kernels) incl. their energies
  double neighbor_s = 0;   // neighbour-list checks and rebuilds
  double integrate_s = 0;  // kicks, drift, kinetic energy, the run guard
  double updaters_s = 0;   // protocols and every-step observers (System::add_updater)
  double total() const { return pair_s + neighbor_s + integrate_s + updaters_s; }
};

}  // namespace mdem
