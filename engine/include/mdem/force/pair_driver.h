#pragma once
// One driver for every pair model (HOOMD-blue's generic pair driver over small evaluators).
//
// A pair model is a *kernel*: its parameters and the physics of one pair, with no loop and no
// threading. The driver runs a kernel over its neighbour sub-list: threaded over the elements i,
// each thread writing into its own ForceSink slot (schedule fixed, so the summation order, and
// the result, are the same run to run at a fixed thread count), with the displacement of every
// pair taken from the list's domain (minimum image along periodic axes).
//
// A kernel K provides:
//   static constexpr bool kDissipative;   // velocity-dependent: writes the sink's damping slots
//   static constexpr bool kTorques;       // writes torques
//   static constexpr EnergyTerm kTerm;    // where the stored energy is booked (conservative)
//   std::string_view name() const;
//   double cutoff() const;                // nm, > 0
//   KindPairs kinds() const;              // the pairs of element kinds it acts on
//   bool excludes(const Elements&, i, j) const;  // kinds outside kinds(), topology exclusions
//   bool pair(const Elements&, i, j, const Vec3& d, PairForces& out) const;
//       // d = minimum-image x_j − x_i; fills out (forces and torques on i = 1 and j = 2, energy)
//       // and returns true, or returns false when the pair does not interact (beyond reach)
//   void stiffness(const Elements&, i, j, const Vec3& d, StiffnessSums&) const;
// and optionally:
//   std::string_view owner() const;       // the contact whose pairs a dashpot belongs to
//   bool active() const;                  // false: the model does nothing (a zero damping ratio)
//   void begin(const Elements&) const;    // per evaluation, serial (size a per-step cache)
//   void prepare(const Elements&, long i) const;  // per evaluation and element, threaded
//   bool batched() const;                 // with batch(): evaluate over PairBatch'es (SIMD)
//   void batch(const Elements&, PairBatch&) const;
//       // fills the outputs of the batch's n pairs (see PairBatch); the driver gathers only pairs
//       // closer than cutoff(), in list order, and adds the results in the same order, so a
//       // kernel with a batch path must not act beyond its cutoff, and f2 = −f1 (no external
//       // force on the pair)
//   void touch(const Elements&, std::uint32_t j) const;
//       // with batch(): prefetch what batch() reads of element j beyond x_j (the driver's own)
// PairModel<K> makes a ForceModel of it.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include "mdem/force/force_model.h"
#include "mdem/neighbor/neighbor_list.h"

namespace mdem {

// Forces f1, f2 and torques t1, t2 on the pair's elements i (1) and j (2), and its energy.
struct PairForces {
  double energy = 0;
  Vec3 f1 = Vec3::Zero(), f2 = Vec3::Zero(), t1 = Vec3::Zero(), t2 = Vec3::Zero();
};

// Coefficient c = 2·ratio·√(m_eff·k) of a viscous dashpot between masses mi and mj (m_eff their
// reduced mass) in a contact of normal stiffness k: critical damping times the ratio.
inline double dashpot_coefficient(double ratio, double mi, double mj, double k) {
  return 2.0 * ratio * std::sqrt(mi * mj / (mi + mj) * k);
}

// Pairs gathered for a batched kernel, in structure-of-arrays form: the driver fills i, j and the
// minimum-image displacement d = x_j − x_i of lanes [0, n); the kernel fills each lane's energy,
// force f on i (the force on j is −f) and torques t1 on i, t2 on j, all zero for a pair that
// does not interact. Lanes [n, kCapacity) are the kernel's scratch (e.g. padding to a whole
// number of vectors). kCapacity is a multiple of 8, the widest vector of doubles (512 bits).
struct PairBatch {
  static constexpr int kCapacity = 64;
  int n = 0;
  alignas(64) std::uint32_t i[kCapacity], j[kCapacity];
  alignas(64) double dx[kCapacity], dy[kCapacity], dz[kCapacity];
  alignas(64) double energy[kCapacity];
  alignas(64) double fx[kCapacity], fy[kCapacity], fz[kCapacity];
  alignas(64) double t1x[kCapacity], t1y[kCapacity], t1z[kCapacity];
  alignas(64) double t2x[kCapacity], t2y[kCapacity], t2z[kCapacity];

  // Writes lane p's outputs from a scalar kernel's result (its f2 is −f1, as the batch assumes).
  void store(int p, const PairForces& r) {
    energy[p] = r.energy;
    fx[p] = r.f1.x();
    fy[p] = r.f1.y();
    fz[p] = r.f1.z();
    t1x[p] = r.t1.x();
    t1y[p] = r.t1.y();
    t1z[p] = r.t1.z();
    t2x[p] = r.t2.x();
    t2y[p] = r.t2.y();
    t2z[p] = r.t2.z();
  }
};

namespace pair_driver_detail {

template <bool kPeriodic>
inline Vec3 displacement(const Domain& domain, const Vec3& xi, const Vec3& xj) {
  if constexpr (kPeriodic)
    return domain.delta(xi, xj);
  else
    return xj - xi;
}

// Whether a list's pairs are shared by the team (drive_pairs and drive_pairs_fused alike, so a
// fused pass's sums stay those of its two passes): from kParallelMinItems listed pairs, as every
// loop of the step. A pair costs 20-200 ns, so even the smallest such list (~40 us on one thread)
// outweighs a team's wake-up; at twice that, the tensile film's NP-NP pairs (4088 with 4000
// NPs, 0.2 ms a step) ran on one thread while the other waited.
inline bool team_for(const NeighborList& list) {
  return static_cast<long>(list.pair_count()) >= kParallelMinItems;
}

// The kernel's per-evaluation cache of every element (a worksharing loop of the calling team).
template <class K>
inline void prepare_all(const K& k, const Elements& el, long n) {
  if constexpr (requires { k.prepare(el, 0L); }) {
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i) k.prepare(el, i);
  }
}

// The thread's force and torque buffers: the damping slots for a dissipative kernel.
template <class K>
inline Vec3* force_buffer(ForceSink& sink, int tid) {
  return K::kDissipative ? sink.damping_force(tid) : sink.force(tid);
}
// Null for a kernel without torques (a sink has damping torque buffers only for a model that
// writes damping torques).
template <class K>
inline Vec3* torque_buffer(ForceSink& sink, int tid) {
  if constexpr (!K::kTorques)
    return nullptr;
  else
    return K::kDissipative ? sink.damping_torque(tid) : sink.torque(tid);
}

// The rows that hold pairs, [first non-empty, last non-empty + 1), from the row offsets `off` by
// two binary searches; an empty range (first == second) for a list without pairs. A sub-list of
// a rare kind (NP-NP, NP-CNT under its NPs) has its rows at the end of the element order, after
// ~10^5 empty rows of segments that a pass need not walk.
inline std::pair<long, long> listed_rows(const std::vector<std::uint32_t>& off) {
  if (off.size() < 2 || off.back() == 0) return {0, 0};
  const long first = (std::upper_bound(off.begin(), off.end(), 0u) - off.begin()) - 1;
  const long last = std::lower_bound(off.begin(), off.end(), off.back()) - off.begin();
  return {first, last};
}

// Thread tid's rows [first, second) of a list with row offsets `off`: contiguous, so each thread
// works on its part of the scene (its f_j, t_j mostly its own cache lines), and cut where the
// listed pairs (plus a quarter pair per row, the row's own cost) split evenly, so the threads
// finish together (64-row chunks dealt round robin left the busier thread 4 % more instructions
// on the dense film). Only the rows from the first to the last that hold pairs (listed_rows) are
// dealt. Depends on the list and the team size only: the sums stay deterministic.
inline std::pair<long, long> balanced_rows(const std::vector<std::uint32_t>& off, int tid,
                                           int threads) {
  const auto [r0, r1] = listed_rows(off);
  const auto cost = [&](long i) {
    return 4 * static_cast<std::uint64_t>(off[i]) + static_cast<std::uint64_t>(i - r0);
  };
  const auto cut = [&](int t) -> long {
    if (t <= 0) return r0;
    if (t >= threads) return r1;
    const std::uint64_t target =
        (cost(r1) - cost(r0)) * static_cast<std::uint64_t>(t) / threads + cost(r0);
    long lo = r0, hi = r1;  // the first row i with cost(i) >= target
    while (lo < hi) {
      const long mid = lo + (hi - lo) / 2;
      if (cost(mid) < target)
        lo = mid + 1;
      else
        hi = mid;
    }
    return lo;
  };
  return {cut(tid), cut(tid + 1)};
}

// flatten: the kernel's pair() inlines into the loop (GCC would otherwise call it per pair and
// pass the result through memory: 8 % more instructions on the twisted rope than the old
// hand-written loops; flattened, 3.5 % fewer).
template <bool kPeriodic, bool kFilter, class K>
[[gnu::flatten]] void run(const K& k, const Elements& el, const NeighborList& list, ForceSink& sink,
                          bool threaded) {
  const auto& off = list.offsets();
  const auto& nb = list.neighbors();
  const Domain& domain = list.domain();
  const long n = static_cast<long>(el.size());
#pragma omp parallel num_threads(sink.threads()) if (threaded)
  {
    prepare_all(k, el, n);
    const int tid = omp_get_thread_num();
    // The thread's own buffers alias nothing the kernel reads (positions, caches, parameters),
    // so the compiler may keep those in registers across the stores.
    Vec3* __restrict f = force_buffer<K>(sink, tid);
    Vec3* __restrict t = torque_buffer<K>(sink, tid);
    double energy = 0.0;
    const auto [first, last] = balanced_rows(off, tid, omp_get_num_threads());
    for (long i = first; i < last; ++i) {
      const std::uint32_t begin = off[i], end = off[i + 1];
      if (begin == end) continue;
      const Vec3 xi = el.x[i];
      Vec3 fi = Vec3::Zero(), ti = Vec3::Zero();
      for (std::uint32_t m = begin; m < end; ++m) {
        const std::uint32_t j = nb[m];
        if constexpr (kFilter) {
          if (k.excludes(el, i, j)) continue;
        }
        PairForces r;
        if (!k.pair(el, i, j, displacement<kPeriodic>(domain, xi, el.x[j]), r)) continue;
        if constexpr (!K::kDissipative) energy += r.energy;
        fi += r.f1;
        f[j] += r.f2;
        if constexpr (K::kTorques) {
          ti += r.t1;
          t[j] += r.t2;
        }
      }
      f[i] += fi;
      if constexpr (K::kTorques) t[i] += ti;
    }
    if constexpr (!K::kDissipative) sink.energy(tid).add(K::kTerm, energy);
  }
}

// Prefetch of the cache line(s) holding *p (a Vec3 of 24 bytes may straddle two lines).
template <int kWrite>
inline void prefetch_vec3(const Vec3* p) {
  __builtin_prefetch(p, kWrite, 3);
  __builtin_prefetch(reinterpret_cast<const char*>(p) + sizeof(Vec3) - 1, kWrite, 3);
}

// Prefetch of the line holding the last byte of *p only. The j of a row come in runs of
// consecutive elements (a tube's segments), so the first line of p[j] is the last line of p[j−1]
// and one prefetch per element covers a run but for the first element's first line.
template <int kWrite>
inline void prefetch_vec3_end(const Vec3* p) {
  __builtin_prefetch(reinterpret_cast<const char*>(p) + sizeof(Vec3) - 1, kWrite, 3);
}

// How far ahead in the neighbour list the gather prefetches x_j.
inline constexpr std::uint32_t kPrefetchAhead = 16;

// No companion kernel (run_batched's default).
struct NoCompanion {};

// Adds the results of the batch's first `lanes` pairs, as kernel K wrote them, to the thread's
// buffers f, t (K's own: the damping slots for a dissipative kernel) and to energy. The pairs of
// one i are consecutive: their forces on i are summed in registers and added to f_i, t_i once
// per run of i.
template <class K>
inline void scatter(const PairBatch& b, int lanes, Vec3* __restrict f, Vec3* __restrict t,
                    double& energy) {
  std::uint32_t ci = b.i[0];
  Vec3 fi = Vec3::Zero(), ti = Vec3::Zero();
  for (int p = 0; p < lanes; ++p) {
    if (b.i[p] != ci) {
      f[ci] += fi;
      if constexpr (K::kTorques) t[ci] += ti;
      ci = b.i[p];
      fi.setZero();
      ti.setZero();
    }
    const Vec3 fp(b.fx[p], b.fy[p], b.fz[p]);
    fi += fp;
    f[b.j[p]] -= fp;
    if constexpr (K::kTorques) {
      ti += Vec3(b.t1x[p], b.t1y[p], b.t1z[p]);
      t[b.j[p]] += Vec3(b.t2x[p], b.t2y[p], b.t2z[p]);
    }
    if constexpr (!K::kDissipative) energy += b.energy[p];
  }
  f[ci] += fi;
  if constexpr (K::kTorques) t[ci] += ti;
}

// The driver of a batched kernel: as run(), but the pairs within the cutoff are gathered into a
// per-thread PairBatch (in list order, branch-free) and evaluated a batch at a time; the results
// are added to the thread's buffers in the same order, so the sums are the same run to run.
// The j of a listed pair sit anywhere in memory (another tube), and waiting on their cache misses
// (x_j at the gather, f_j and t_j at the scatter, the kernel's own per-element data) was most of
// the driver's time: the gather prefetches x_j kPrefetchAhead pairs ahead, and, for each pair
// gathered, the lines the scatter and the kernel (touch()) will use once the batch is full.
// The loop works on raw pointers and a lane count held in a register: through the vectors and
// b.n, GCC reloaded el.x's data pointer and b.n from memory at every pair (the batch escapes
// into the kernel, so its stores may alias anything reached through a reference).
//
// With a companion kernel C (c non-null: a dashpot over its contact's pairs, same cutoff, same
// list), each batch is evaluated by k and then by c, each adding its results to its own buffers:
// one walk of the list, one gather and one set of cache misses on the j for both. Each kernel's
// sums are those of its own run_batched, bit for bit (the same lanes in the same order, into
// buffers the other does not write: c is dissipative, k is not).
template <bool kPeriodic, bool kFilter, class K, class C = NoCompanion>
void run_batched(const K& k, const Elements& el, const NeighborList& list, ForceSink& sink,
                 bool threaded, const C* c = nullptr) {
  constexpr bool kFused = !std::is_same_v<C, NoCompanion>;
  if constexpr (kFused) static_assert(C::kDissipative && !K::kDissipative && !kFilter);
  const std::uint32_t* const off = list.offsets().data();
  const std::uint32_t* const nb = list.neighbors().data();
  const Domain& domain = list.domain();
  const long n = static_cast<long>(el.size());
  const double rc2 = k.cutoff() * k.cutoff();
  const std::uint32_t listed = static_cast<std::uint32_t>(list.neighbors().size());
#pragma omp parallel num_threads(sink.threads()) if (threaded)
  {
    prepare_all(k, el, n);
    if constexpr (kFused) prepare_all(*c, el, n);
    const int tid = omp_get_thread_num();
    Vec3* __restrict f = force_buffer<K>(sink, tid);
    Vec3* __restrict t = torque_buffer<K>(sink, tid);
    Vec3* __restrict fc = nullptr;
    Vec3* __restrict tc = nullptr;
    if constexpr (kFused) {
      fc = force_buffer<C>(sink, tid);
      tc = torque_buffer<C>(sink, tid);
    }
    const Vec3* __restrict x = el.x.data();
    double energy = 0.0, unused = 0.0;
    PairBatch b;
    const auto flush = [&](int lanes) {
      b.n = lanes;
      k.batch(el, b);
      scatter<K>(b, lanes, f, t, energy);
      if constexpr (kFused) {
        c->batch(el, b);  // reads the gathered i, j, d, which k.batch leaves as they were
        scatter<C>(b, lanes, fc, tc, unused);
      }
    };
    std::uint32_t* const bi = b.i;
    std::uint32_t* const bj = b.j;
    double* const bx = b.dx;
    double* const by = b.dy;
    double* const bz = b.dz;
    int lanes = 0;
    const auto [first, last] = balanced_rows(list.offsets(), tid, omp_get_num_threads());
    for (long i = first; i < last; ++i) {
      const std::uint32_t begin = off[i], end = off[i + 1];
      if (begin == end) continue;  // (a sub-list of few kinds: most rows are empty)
      const Vec3 xi = x[i];
      for (std::uint32_t m = begin; m < end; ++m) {
        const std::uint32_t j = nb[m];
        prefetch_vec3_end<0>(x + nb[std::min(m + kPrefetchAhead, listed - 1)]);
        if constexpr (kFilter) {
          if (k.excludes(el, i, j)) continue;
        }
        prefetch_vec3_end<1>(f + j);
        if constexpr (K::kTorques) prefetch_vec3_end<1>(t + j);
        if constexpr (requires { k.touch(el, j); }) k.touch(el, j);
        if constexpr (kFused) {
          prefetch_vec3_end<1>(fc + j);
          if constexpr (C::kTorques) prefetch_vec3_end<1>(tc + j);
          if constexpr (requires { c->touch(el, j); }) c->touch(el, j);
        }
        const Vec3 d = displacement<kPeriodic>(domain, xi, x[j]);
        // Written to the next free lane, kept when within the cutoff (a NaN is kept too).
        bi[lanes] = static_cast<std::uint32_t>(i);
        bj[lanes] = j;
        bx[lanes] = d.x();
        by[lanes] = d.y();
        bz[lanes] = d.z();
        lanes += !(d.squaredNorm() >= rc2);
        if (lanes == PairBatch::kCapacity) {
          flush(lanes);
          lanes = 0;
        }
      }
    }
    if (lanes > 0) flush(lanes);
    if constexpr (!K::kDissipative) sink.energy(tid).add(K::kTerm, energy);
  }
}

template <bool kPeriodic, bool kFilter, class K>
void run_any(const K& k, const Elements& el, const NeighborList& list, ForceSink& sink,
             bool threaded) {
  if constexpr (requires(PairBatch & b) { k.batch(el, b); }) {
    if (k.batched()) return run_batched<kPeriodic, kFilter>(k, el, list, sink, threaded);
  }
  run<kPeriodic, kFilter>(k, el, list, sink, threaded);
}

}  // namespace pair_driver_detail

// Adds kernel k's forces, torques and energy over the pairs of `list` to the sink. filter: test
// k.excludes() on every listed pair (when the list was not built for this kernel's pairs).
template <class K>
void drive_pairs(const K& k, const Elements& el, const NeighborList& list, ForceSink& sink,
                 bool filter) {
  if (el.size() == 0) return;
  if (list.offsets().size() != el.size() + 1)
    throw std::logic_error(std::string(k.name()) +
                           ": neighbour list was not built for these elements");
  if (K::kDissipative && !sink.has_damping())
    throw std::logic_error(std::string(k.name()) + ": force sink has no damping buffers");
  // No pairs, nothing to add: not a pass over every row (an NP sub-list of a film without NPs).
  if (list.pair_count() == 0) return;
  if constexpr (requires { k.begin(el); }) k.begin(el);
  using namespace pair_driver_detail;
  const bool threaded = team_for(list);
  const bool periodic = list.domain().any_periodic();
  if (periodic) {
    if (filter)
      run_any<true, true>(k, el, list, sink, threaded);
    else
      run_any<true, false>(k, el, list, sink, threaded);
  } else {
    if (filter)
      run_any<false, true>(k, el, list, sink, threaded);
    else
      run_any<false, false>(k, el, list, sink, threaded);
  }
}

// Adds kernel k's and its companion c's forces over the pairs of `list`, which was built for
// both (no exclusion filter), in one pass (run_batched with a companion): as drive_pairs(k) and
// then drive_pairs(c), bit for bit. Both must be batched with one cutoff and c dissipative.
template <class K, class C>
void drive_pairs_fused(const K& k, const C& c, const Elements& el, const NeighborList& list,
                       ForceSink& sink) {
  if (el.size() == 0) return;
  if (list.offsets().size() != el.size() + 1)
    throw std::logic_error(std::string(k.name()) +
                           ": neighbour list was not built for these elements");
  if (!sink.has_damping())
    throw std::logic_error(std::string(c.name()) + ": force sink has no damping buffers");
  if (!k.batched() || !c.batched() || k.cutoff() != c.cutoff())
    throw std::logic_error(std::string(k.name()) + " and " + std::string(c.name()) +
                           ": a fused pass needs two batched kernels with one cutoff");
  if (list.pair_count() == 0) return;
  if constexpr (requires { k.begin(el); }) k.begin(el);
  if constexpr (requires { c.begin(el); }) c.begin(el);
  using namespace pair_driver_detail;
  const bool threaded = team_for(list);
  if (list.domain().any_periodic())
    run_batched<true, false>(k, el, list, sink, threaded, &c);
  else
    run_batched<false, false>(k, el, list, sink, threaded, &c);
}

// Adds kernel k's stiffness bounds over the pairs of `list` (serial, in list order).
template <class K>
void drive_stiffness(const K& k, const Elements& el, const NeighborList& list, StiffnessSums& s,
                     bool filter) {
  const auto& off = list.offsets();
  const auto& nb = list.neighbors();
  if (off.size() != el.size() + 1) return;
  const Domain& domain = list.domain();
  for (std::size_t i = 0; i < el.size(); ++i)
    for (std::uint32_t m = off[i]; m < off[i + 1]; ++m) {
      const std::size_t j = nb[m];
      if (filter && k.excludes(el, i, j)) continue;
      k.stiffness(el, i, j, domain.delta(el.x[i], el.x[j]), s);
    }
}

// Whether `list` holds exactly m's pairs (built for m, or for the contact m belongs to), so the
// driver need not test m's exclusion on each listed pair again.
inline bool list_is_for(const NeighborList& list, const ForceModel& m) {
  const ForceModel* o = list.owner();
  if (!o) return false;
  if (o == &m) return true;
  const std::string_view owner = m.pair_owner();
  return !owner.empty() && o->name() == owner;
}

// A ForceModel made of a pair kernel: everything a pair model is, from its one-pair physics.
template <class K>
class PairModel : public ForceModel {
 public:
  template <class... A>
  explicit PairModel(A&&... a) : k_(std::forward<A>(a)...) {}

  std::string_view name() const override { return k_.name(); }
  double cutoff() const override { return k_.cutoff(); }
  KindPairs kinds() const override { return k_.kinds(); }
  bool excludes(const Elements& el, std::size_t i, std::size_t j) const override {
    return k_.excludes(el, i, j);
  }
  bool dissipative() const override { return K::kDissipative; }
  bool damping_torques() const override { return K::kDissipative && K::kTorques; }
  Timescale timescale() const override {
    if constexpr (requires { K::kTimescale; })
      return K::kTimescale;
    else
      return Timescale::Fast;
  }
  // Kernels hold no element indices between evaluations (at most a per-evaluation cache, as the
  // vdW kernel's axes; the grain dashpots read the bond model, which remaps its own): a pair model
  // follows a reordering with nothing to remap, its pairs come from the rebuilt sub-list.
  bool follows_reorder() const override { return true; }
  std::string_view pair_owner() const override {
    if constexpr (requires { k_.owner(); })
      return k_.owner();
    else
      return {};
  }

  void compute(const Elements& el, const NeighborList* pairs, ForceSink& sink) const override {
    if (!active()) return;
    if (!pairs) throw std::logic_error(std::string(name()) + ": compute() needs a neighbour list");
    drive_pairs(k_, el, *pairs, sink, !list_is_for(*pairs, *this));
  }
  // A kernel whose pairs are another kernel's names the kernels it can belong to as
  // `using Owners = std::tuple<...>;` (a dashpot its contacts'): with this model's owner one of
  // them, both batched on one cutoff and the list theirs, one pass does both.
  bool compute_with(const ForceModel& owner, const Elements& el, const NeighborList* pairs,
                    ForceSink& sink) const override {
    if constexpr (requires { typename K::Owners; }) {
      if (!pairs || !active() || owner.name() != pair_owner()) return false;
      return fuse(owner, el, *pairs, sink, static_cast<typename K::Owners*>(nullptr));
    } else {
      return ForceModel::compute_with(owner, el, pairs, sink);
    }
  }
  void add_stiffness(const Elements& el, const NeighborList* pairs,
                     StiffnessSums& s) const override {
    if (!active() || !pairs) return;
    drive_stiffness(k_, el, *pairs, s, !list_is_for(*pairs, *this));
  }

  const K& kernel() const { return k_; }
  // False: the model does nothing (e.g. a dashpot with a zero damping ratio).
  bool active() const {
    if constexpr (requires { k_.active(); })
      return k_.active();
    else
      return true;
  }

 protected:
  K k_;

 private:
  // compute_with's pass with an owner whose kernel is one of O...
  template <class... O>
  bool fuse(const ForceModel& owner, const Elements& el, const NeighborList& pairs, ForceSink& sink,
            std::tuple<O...>*) const {
    return (fuse_as<O>(owner, el, pairs, sink) || ...);
  }
  template <class O>
  bool fuse_as(const ForceModel& owner, const Elements& el, const NeighborList& pairs,
               ForceSink& sink) const {
    const auto* o = dynamic_cast<const PairModel<O>*>(&owner);
    if (!o || !o->active()) return false;
    const O& ok = o->kernel();
    if (!k_.batched() || !ok.batched() || k_.cutoff() != ok.cutoff()) return false;
    if (!list_is_for(pairs, *this) || !list_is_for(pairs, *o)) return false;
    drive_pairs_fused(ok, k_, el, pairs, sink);
    return true;
  }
};

}  // namespace mdem
