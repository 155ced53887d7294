// Steps of the twist job's 91-tube rope (Table 4-1: N = 6, 50 segments, 4550 elements) in the
// twist-relaxation hold under the per-element load, by grip hold: hold:0 the grips' positions held
// and their spins free (HOLD_POSITIONS), hold:1 positions and spins held (HOLD_POSITIONS_AND_SPINS:
// 182 elements with all six DOFs prescribed). The ramp is made short (64 nN·nm at 100 nN·nm/ps,
// 0.64 ps) so that every timed step is in the hold; local damping 0.1 as in the Table 4-1 runs.
// What it measures: whether prescribed rotational DOFs on the grips cost anything per step.
//   bench_twist_hold --benchmark_filter=TwistRopeHold
#include <benchmark/benchmark.h>

#include "bench_support.h"
#include "mdem/core/units.h"
#include "mdem/job/twist_job.h"

namespace mdem {
namespace {

void BM_TwistRopeHold(benchmark::State& state) {
  TwistJobSpec spec;
  spec.loading.torque_max = units::nNnm(64);
  spec.loading.rate = units::nNnm(100);
  spec.loading.hold = 1000;
  spec.loading.boundary = TwistBoundary::TwistRelaxation;
  spec.loading.grip_load = GripLoad::PerElement;
  spec.loading.grip_hold = state.range(1) ? GripHold::PositionsAndSpins : GripHold::Positions;
  IntegratorSettings set;
  set.threads = static_cast<int>(state.range(0));
  set.local_damping = 0.1;
  TwistJob job(spec, set);
  System& sys = job.system();
  sys.initialize();
  while (sys.time() < job.protocol().ramp_time() + 0.1) sys.run(16);  // into the hold
  if (job.protocol().phase_at(sys.time()) != TwistPhase::Holding) {
    state.SkipWithError("not in the hold");
    return;
  }
  bench::timed_steps(state, sys, 48);
}
BENCHMARK(BM_TwistRopeHold)
    ->ArgNames({"threads", "hold"})
    ->ArgsProduct({{1, 2}, {0, 1}})
    ->Iterations(4)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace mdem

BENCHMARK_MAIN();
