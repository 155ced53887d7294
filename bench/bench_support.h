#pragma once
// What the engine benchmarks share: the timed loop of steps, its rate and phase counters.
#include <benchmark/benchmark.h>

#include "mdem/integrate/system.h"

namespace mdem::bench {

// Runs `per_iteration` steps of `sys` per benchmark iteration and sets the counters
// element_steps_per_s and elements; returns the steps run in the timed loop.
inline double timed_steps(benchmark::State& state, System& sys, long per_iteration) {
  const long steps0 = sys.steps();
  for (auto _ : state) sys.run(per_iteration);
  const double steps = static_cast<double>(sys.steps() - steps0);
  const double n = static_cast<double>(sys.elements().size());
  state.counters["element_steps_per_s"] =
      benchmark::Counter(n * steps, benchmark::Counter::kIsRate);
  state.counters["elements"] = n;
  return steps;
}

// The step's time split by phase (System::timers()), in ms per step, over the timed steps.
inline void add_phase_counters(benchmark::State& state, const StepTimers& before,
                               const StepTimers& after, double steps) {
  state.counters["pair_ms"] = (after.pair_s - before.pair_s) / steps * 1e3;
  state.counters["neighbor_ms"] = (after.neighbor_s - before.neighbor_s) / steps * 1e3;
  state.counters["integrate_ms"] = (after.integrate_s - before.integrate_s) / steps * 1e3;
  state.counters["updaters_ms"] = (after.updaters_s - before.updaters_s) / steps * 1e3;
}

}  // namespace mdem::bench
