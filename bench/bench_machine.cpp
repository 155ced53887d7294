// What the machine's core can do, to read the engine's figures against: the 512-bit vector units'
// rates (multiply-add, square root, divide of 8 doubles) and the memory bandwidth one and two
// threads get streaming arrays far larger than the caches. The engine's kernels are bound by one
// or the other (docs/engine.md, "What the core can do"); a target in ns per pair or per element
// only means something against these.
//
// The vector benchmarks run on CPUs with AVX-512F (compiled for it per function, checked at run
// time) and are skipped elsewhere.
#include <benchmark/benchmark.h>
// GCC 12's AVX-512 intrinsics (_mm512_undefined_pd in _mm512_sqrt_pd) trip its own
// uninitialised-value warnings.
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <immintrin.h>
#include <omp.h>

#include <atomic>
#include <cstddef>
#include <vector>

namespace {

bool has_avx512() { return __builtin_cpu_supports("avx512f"); }

// kChains independent chains of one operation, n rounds: the rate, not the latency.
enum class Op { Fma, Sqrt, Div };
template <Op kOp, int kChains>
[[gnu::target("avx512f"), gnu::noinline]] double chains(long n, double start) {
  __m512d a[kChains];
  for (int k = 0; k < kChains; ++k) a[k] = _mm512_set1_pd(start + 0.01 * k);
  const __m512d m = _mm512_set1_pd(0.9999999), c = _mm512_set1_pd(1e-7);
  for (long i = 0; i < n; ++i)
    for (int k = 0; k < kChains; ++k) {
      if constexpr (kOp == Op::Fma) a[k] = _mm512_fmadd_pd(a[k], m, c);
      if constexpr (kOp == Op::Sqrt) a[k] = _mm512_sqrt_pd(a[k]);
      if constexpr (kOp == Op::Div) a[k] = _mm512_div_pd(m, a[k]);
    }
  __m512d s = a[0];
  for (int k = 1; k < kChains; ++k) s = _mm512_add_pd(s, a[k]);
  double out[8];
  _mm512_storeu_pd(out, s);
  return out[0];
}

// ns per instruction (8 doubles each) and, for the multiply-add, GFLOP/s (2 flops per lane).
template <Op kOp, int kChains>
void vector_rate(benchmark::State& state) {
  if (!has_avx512()) {
    state.SkipWithError("this CPU has no AVX-512F");
    return;
  }
  long n = 1 << 20;
  double start = 1.0;
  for (auto _ : state) {
    // Arguments the compiler cannot know, each time: the call is neither folded nor hoisted
    // (it is pure, and GCC would otherwise make it once).
    benchmark::DoNotOptimize(n);
    benchmark::DoNotOptimize(start);
    benchmark::DoNotOptimize(chains<kOp, kChains>(n, start));
  }
  const double instructions = static_cast<double>(n) * kChains * state.iterations();
  state.counters["ns_per_instruction"] = benchmark::Counter(
      instructions * 1e-9, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  if (kOp == Op::Fma)
    state.counters["gflops"] =
        benchmark::Counter(instructions * 16 * 1e-9, benchmark::Counter::kIsRate);
}
void BM_Fma512(benchmark::State& state) { vector_rate<Op::Fma, 12>(state); }
void BM_Sqrt512(benchmark::State& state) { vector_rate<Op::Sqrt, 8>(state); }
void BM_Div512(benchmark::State& state) { vector_rate<Op::Div, 8>(state); }
// One chain: the multiply-add's latency (ns per instruction = ns per dependent step).
void BM_Fma512Latency(benchmark::State& state) { vector_rate<Op::Fma, 1>(state); }
BENCHMARK(BM_Fma512);
BENCHMARK(BM_Fma512Latency);
BENCHMARK(BM_Sqrt512);
BENCHMARK(BM_Div512);

// Streaming 256 MB: a += b over two arrays of 128 MB (16 bytes read and 8 written per double, as
// the integrator's pass reads and writes its arrays), on `threads` threads each taking a
// contiguous block. gb_per_s counts the bytes the loop reads and writes (a write-allocate read of
// a's lines is not extra: a is read anyway).
void BM_MemoryUpdate(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const std::size_t n = std::size_t{1} << 24;  // doubles per array
  std::vector<double> a(n, 1.0), b(n, 1e-9);
  for (auto _ : state) {
#pragma omp parallel for schedule(static) num_threads(threads)
    for (std::size_t i = 0; i < n; ++i) a[i] += b[i];
    benchmark::ClobberMemory();
  }
  state.counters["gb_per_s"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * static_cast<double>(n) * 24 * 1e-9,
      benchmark::Counter::kIsRate);
}
BENCHMARK(BM_MemoryUpdate)->ArgName("threads")->Arg(1)->Arg(2)->UseRealTime();

// What the two threads of a 2-thread run pay to pass data between their cores, which two
// 1-thread processes never do (docs/engine.md, "Two threads against two processes"). A VM's two
// CPUs may sit on one core complex (a shared L3) or on two, and may move between hours; these
// two figures say which, next to a 2-thread benchmark run at the same time. Skipped unless the
// team has 2 threads on at least 2 CPUs (one spinning thread would wait out the other's time
// slices).
//
// Runs body(thread) on a team of exactly 2 threads, thread 0 and 1 (body may hold barriers);
// false, body not run, with fewer than 2 CPUs or a smaller team.
template <class Body>
bool on_two_threads(const Body& body) {
  if (omp_get_num_procs() < 2) return false;
  bool two = true;
#pragma omp parallel num_threads(2)
  {
    if (omp_get_num_threads() != 2) {
#pragma omp single
      two = false;
    } else {
      body(omp_get_thread_num());
    }
  }
  return two;
}
constexpr const char* kNeedsTwo = "needs a team of 2 threads on 2 CPUs";

// One cache line bounced between the two threads: round_trip_ns, the time for the line to go to
// the other core and come back (two handoffs).
void BM_LineRoundTrip(benchmark::State& state) {
  constexpr long kRounds = 20000;
  alignas(64) std::atomic<long> turn{0};
  for (auto _ : state) {
    turn.store(0);
    const bool ran = on_two_threads([&](long me) {
      for (long k = 0; k < kRounds; ++k) {
        const long mine = 2 * k + me;
        while (turn.load(std::memory_order_acquire) != mine) {
        }
        turn.store(mine + 1, std::memory_order_release);
      }
    });
    if (!ran) {
      state.SkipWithError(kNeedsTwo);
      break;
    }
  }
  if (state.error_occurred()) return;
  state.counters["round_trip_ns"] = benchmark::Counter(
      static_cast<double>(kRounds) * static_cast<double>(state.iterations()) * 1e-9,
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_LineRoundTrip)->UseRealTime();

// Reading 16 MB of doubles that a core has just written (as the integrator's pass reads the
// force sums the pair loop wrote): other:0 the same thread wrote them, other:1 the other thread
// did. gb_per_s counts the reads only, timed apart from the writes.
void BM_ReadAfterWrite(benchmark::State& state) {
  const int reader = state.range(0) != 0 ? 1 : 0;  // thread 0 writes
  const std::size_t n = std::size_t{1} << 21;      // 16 MB
  std::vector<double> a(n, 0.0);
  double read_s = 0, sink = 0;
  for (auto _ : state) {
    const bool ran = on_two_threads([&](int me) {
      if (me == 0)
        for (std::size_t i = 0; i < n; ++i) a[i] = static_cast<double>(i);
#pragma omp barrier
      if (me == reader) {
        const double t0 = omp_get_wtime();
        double s[8] = {};  // 8 chains: the loads, not one add's latency, set the rate
        for (std::size_t i = 0; i < n; i += 8)
          for (int k = 0; k < 8; ++k) s[k] += a[i + k];
        read_s += omp_get_wtime() - t0;
        for (double v : s) sink += v;
      }
    });
    if (!ran) {
      state.SkipWithError(kNeedsTwo);
      break;
    }
  }
  if (state.error_occurred()) return;
  benchmark::DoNotOptimize(sink);
  state.counters["gb_per_s"] = static_cast<double>(state.iterations()) *
                               static_cast<double>(n * sizeof(double)) * 1e-9 / read_s;
}
BENCHMARK(BM_ReadAfterWrite)->ArgName("other")->Arg(0)->Arg(1)->UseRealTime();

// Whether the two threads have a core each or share one (two hardware threads of one core, which
// a VM may not say: its lscpu reports what the hypervisor tells it). Thread 0 runs the multiply-add
// chains of BM_Fma512 alone, then both threads run them at once; share = the two threads'
// multiply-adds per second over one alone's. 12 chains keep one core's multiply-add units full, so
// share is ~2 with a core each and ~1 on one core's two hardware threads.
void BM_FmaShare(benchmark::State& state) {
  if (!has_avx512()) {
    state.SkipWithError("this CPU has no AVX-512F");
    return;
  }
  long n = 1 << 20;
  double alone_s = 0, both_s = 0, sink = 0;
  for (auto _ : state) {
    const bool ran = on_two_threads([&](int me) {
      double t0 = omp_get_wtime();
      if (me == 0) {
        sink += chains<Op::Fma, 12>(n, 1.0);
        alone_s += omp_get_wtime() - t0;
      }
#pragma omp barrier
      t0 = omp_get_wtime();
      const double v = chains<Op::Fma, 12>(n, 1.0 + me);
#pragma omp barrier
      if (me == 0) {
        both_s += omp_get_wtime() - t0;
        sink += v;
      }
    });
    if (!ran) {
      state.SkipWithError(kNeedsTwo);
      break;
    }
  }
  if (state.error_occurred()) return;
  benchmark::DoNotOptimize(sink);
  state.counters["share"] = 2 * alone_s / both_s;
}
BENCHMARK(BM_FmaShare)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
