#pragma once
// What the engine benchmarks share: the timed loop of steps, its rate and phase counters.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "mdem/integrate/system.h"
#include "mdem/observe/percentile.h"

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

// The step's time split by phase (System::timers()), in ms per step, over the timed steps; the
// counters' names start with `prefix` (pair_ms, neighbor_ms, integrate_ms, updaters_ms).
inline void add_phase_counters(benchmark::State& state, const StepTimers& before,
                               const StepTimers& after, double steps,
                               const std::string& prefix = "") {
  state.counters[prefix + "pair_ms"] = (after.pair_s - before.pair_s) / steps * 1e3;
  state.counters[prefix + "neighbor_ms"] = (after.neighbor_s - before.neighbor_s) / steps * 1e3;
  state.counters[prefix + "integrate_ms"] = (after.integrate_s - before.integrate_s) / steps * 1e3;
  state.counters[prefix + "updaters_ms"] = (after.updaters_s - before.updaters_s) / steps * 1e3;
}

// Neighbour sub-list builds of sys so far, all sub-lists together.
inline double list_builds(const System& sys) {
  double b = 0;
  for (const auto& e : sys.pair_table().entries()) b += static_cast<double>(e.list->builds());
  return b;
}

// Time per step (ms) of several systems run in alternating windows of `steps` steps each, in one
// process: a cycle runs every system once, the first system of cycle c being c mod size (so no
// system always follows the same one). These VMs change speed by 20-30 % from minute to minute
// and move their two CPUs nearer or further apart; runs in separate processes, or one after the
// other, compare different machines. Returns each system's times by cycle.
inline std::vector<std::vector<double>> alternating_windows(const std::vector<System*>& systems,
                                                            long steps, int cycles) {
  std::vector<std::vector<double>> ms(systems.size());
  const std::size_t k = systems.size();
  for (int c = 0; c < cycles; ++c)
    for (std::size_t r = 0; r < k; ++r) {
      const std::size_t s = (static_cast<std::size_t>(c) + r) % k;
      const auto t0 = std::chrono::steady_clock::now();
      systems[s]->run(steps);
      const std::chrono::duration<double, std::milli> dt = std::chrono::steady_clock::now() - t0;
      ms[s].push_back(dt.count() / static_cast<double>(steps));
    }
  return ms;
}

// The median of v (the observables' percentile rule at 50: the mean of the middle two for an even
// count).
inline double median(const std::vector<double>& v) { return percentile(v, 50.0, "window times"); }

// Per cycle, a's time over b's (b's rate over a's when a, b are times per step).
inline std::vector<double> ratios(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> r;
  for (std::size_t c = 0; c < std::min(a.size(), b.size()); ++c) r.push_back(a[c] / b[c]);
  return r;
}

// 2 threads over 1, as built and in slabs (issue 13 item 4), in one process: `one` (1 thread,
// as built), `two` (2 threads, as built) and `slabs` (2 threads, MemoryOrder::Slabs) run in
// alternating windows of `steps` steps, `cycles` cycles per iteration. Counters: the medians
// over the cycles of each cycle's own rate ratio (two_over_one, slabs_over_one, slabs_over_two),
// each system's median time per step (one_ms, two_ms, slabs_ms) and its phases over all
// windows (<name>_pair_ms, _neighbor_ms, _integrate_ms, _updaters_ms), its neighbour sub-list
// builds per step and its reorderings since it was made.
inline void thread_windows(benchmark::State& state, System& one, System& two, System& slabs,
                           long steps, int cycles) {
  const std::vector<System*> sys{&one, &two, &slabs};
  const char* const names[3] = {"one", "two", "slabs"};
  std::vector<StepTimers> before;
  std::vector<long> steps0;
  std::vector<double> builds0;
  for (System* s : sys) {
    before.push_back(s->timers());
    steps0.push_back(s->steps());
    builds0.push_back(list_builds(*s));
  }
  std::vector<std::vector<double>> ms(3);
  for (auto _ : state) {
    const auto w = alternating_windows(sys, steps, cycles);
    for (int k = 0; k < 3; ++k) ms[k].insert(ms[k].end(), w[k].begin(), w[k].end());
  }
  state.counters["two_over_one"] = median(ratios(ms[0], ms[1]));
  state.counters["slabs_over_one"] = median(ratios(ms[0], ms[2]));
  state.counters["slabs_over_two"] = median(ratios(ms[1], ms[2]));
  state.counters["cycles"] = static_cast<double>(ms[0].size());
  for (int k = 0; k < 3; ++k) {
    const std::string name = names[k];
    state.counters[name + "_ms"] = median(ms[k]);
    const double n = static_cast<double>(sys[k]->steps() - steps0[k]);
    add_phase_counters(state, before[k], sys[k]->timers(), n, name + "_");
    state.counters[name + "_builds_per_step"] = (list_builds(*sys[k]) - builds0[k]) / n;
    state.counters[name + "_reorders"] = static_cast<double>(sys[k]->reorders());
  }
}

}  // namespace mdem::bench
