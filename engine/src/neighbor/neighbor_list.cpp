#include "mdem/neighbor/neighbor_list.h"

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "mdem/core/capacity_bytes.h"
#include "mdem/force/force_model.h"
#include "mdem/io/state_io.h"
#include "neighbor/cell_scan_simd.h"

namespace mdem {

namespace {

// Below this many elements the build and the displacement check run on one thread (the team
// start-up would cost more than the work); the threshold the force loops use.
constexpr std::size_t kParallelMin = static_cast<std::size_t>(kParallelMinItems);

// Cells are made this much wider than cutoff + skin, so rounding in the cell index of a
// coordinate can never split a pair closer than cutoff + skin over two non-adjacent cells.
constexpr double kCellMargin = 1e-6;

// Cells are range / kReach wide and the search spans kReach cells either side. A finer grid
// (kReach = 2) scans less empty volume but in more, shorter runs; on a 50 000-segment film it was
// ~10 % slower than kReach = 1, so the plain 3×3×3 block is used.
constexpr long kReach = 1;

[[noreturn]] void throw_non_finite(const Elements& el, std::size_t i) {
  std::ostringstream m;
  m << "neighbour list: element " << i;
  if (i < el.tube.size() && el.tube[i] >= 0)
    m << " (tube " << el.tube[i] << ", index " << el.index[i] << ")";
  m << " has a non-finite position (" << el.x[i].x() << ", " << el.x[i].y() << ", " << el.x[i].z()
    << "); the run has diverged (time step too large or an unresolved overlap)";
  throw std::runtime_error(m.str());
}

// |x − x0|², infinite when not finite, so that a NaN position asks for a rebuild (std::max keeps
// its first argument against a NaN).
inline double moved2(const Vec3& x, const Vec3& x0) {
  const double d2 = (x - x0).squaredNorm();
  return d2 <= std::numeric_limits<double>::max() ? d2 : std::numeric_limits<double>::infinity();
}

// How many elements of each kind.
std::array<std::size_t, kElementKinds> kind_counts(const Elements& el) {
  std::array<std::size_t, kElementKinds> count{};
  for (const ElementKind k : el.kind) ++count[static_cast<int>(k)];
  return count;
}

}  // namespace

NeighborList::NeighborList(double cutoff, double skin, Domain domain)
    : cutoff_(cutoff), skin_(skin), domain_(domain) {
  if (!std::isfinite(cutoff) || cutoff <= 0)
    throw std::invalid_argument("neighbour list: cutoff must be finite and > 0");
  if (!std::isfinite(skin) || skin < 0)
    throw std::invalid_argument("neighbour list: skin must be finite and >= 0");
  if (const std::string e = domain_.check_reach(cutoff + skin); !e.empty())
    throw std::invalid_argument("neighbour list: " + e);
}

double NeighborList::max_displacement(const Elements& el) const { return largest_move(el, false); }

double NeighborList::largest_move(const Elements& el, bool of_kinds) const {
  const std::size_t n = el.size();
  if (builds_ == 0 || n != x_at_build_.size()) return std::numeric_limits<double>::infinity();
  const Vec3* x = el.x.data();
  const Vec3* x0 = x_at_build_.data();
  const long nl = static_cast<long>(n);
  // One pass, instantiated with a test that reads no kind byte when every element counts.
  const auto pass = [&](auto counts) {
    double m2 = 0.0;
#pragma omp parallel for schedule(static) reduction(max : m2) if (n >= kParallelMin)
    for (long i = 0; i < nl; ++i)
      if (counts(i)) m2 = std::max(m2, moved2(x[i], x0[i]));
    return std::sqrt(m2);
  };
  if (!of_kinds) return pass([](long) { return true; });
  bool counted[kElementKinds];
  for (int a = 0; a < kElementKinds; ++a) counted[a] = kinds_.involves(static_cast<ElementKind>(a));
  const ElementKind* kind = el.kind.data();
  return pass([&](long i) { return counted[static_cast<int>(kind[i])]; });
}

void NeighborList::plan_check(const Elements& el) const {
  check_idx_.clear();
  check_scope_ = CheckScope::All;
  if (kinds_.is_all()) return;
  const auto count = kind_counts(el);
  bool possible = false;
  std::size_t involved = 0;
  for (int a = 0; a < kElementKinds; ++a) {
    const auto ka = static_cast<ElementKind>(a);
    if (kinds_.involves(ka)) involved += count[a];
    for (int b = a; b < kElementKinds; ++b)
      if (kinds_.has(ka, static_cast<ElementKind>(b)) && count[a] > 0 && count[b] > (a == b))
        possible = true;
  }
  if (!possible) {
    check_scope_ = CheckScope::None;
  } else if (involved == el.size()) {
    check_scope_ = CheckScope::All;
  } else if (involved > el.size() / 4) {
    check_scope_ = CheckScope::Kinds;
  } else {
    check_scope_ = CheckScope::Listed;
    check_idx_.reserve(involved);
    for (std::size_t i = 0; i < el.size(); ++i)
      if (kinds_.involves(el.kind[i])) check_idx_.push_back(static_cast<std::uint32_t>(i));
  }
}

bool NeighborList::needs_rebuild(const Elements& el) const {
  if (builds_ == 0 || el.size() != x_at_build_.size()) return true;
  if (!check_planned_) {  // the first check since a build or a load_state
    plan_check(el);
    check_planned_ = true;
  }
  // Only the elements of the listed kinds can change the list: none when no two of them can pair
  // (an NP-CNT list without NPs), few for a list of a rare kind (NP-NP), not the NPs for a
  // CNT-CNT list (fast NPs rebuilt the vdW list of a film with NPs every 50 steps where the film
  // alone went 80). Written so that a NaN displacement asks for a rebuild (which then reports
  // the element).
  if (check_scope_ == CheckScope::None) return false;
  double moved = 0.0;
  if (check_scope_ == CheckScope::Listed) {
    for (const std::uint32_t i : check_idx_)
      moved = std::max(moved, moved2(el.x[i], x_at_build_[i]));
    moved = std::sqrt(moved);
  } else {
    moved = largest_move(el, check_scope_ == CheckScope::Kinds);
  }
  return !(moved <= 0.5 * skin_);
}

void NeighborList::build(const Elements& el) {
  const std::size_t n = el.size();
  if (n >= std::numeric_limits<std::uint32_t>::max())
    throw std::runtime_error("neighbour list: more than 2^32 - 1 elements");
  const double range = cutoff_ + skin_;
  const double range2 = range * range;
  const bool all_kinds = kinds_.is_all();
  const bool periodic = domain_.any_periodic();
  // Elements of kinds no listed pair involves are not binned (cell kNone).
  auto binned = [&](std::size_t i) { return all_kinds || kinds_.involves(el.kind[i]); };
  // A list of some kind pairs bins each kind it involves in a layer of its own (the same grid),
  // and an element scans only the layers of its partner kinds: an NP-CNT list then looks at the
  // few NPs around a segment, not at the thousands of segments it would reject. A list of all
  // kinds has one layer.
  int layer_of[kElementKinds];
  int layers = 0;
  for (int a = 0; a < kElementKinds; ++a)
    layer_of[a] = all_kinds ? 0 : kinds_.involves(static_cast<ElementKind>(a)) ? layers++ : -1;
  if (all_kinds) layers = 1;
  // A pair of one kind is listed under its lower index (j > i); a pair of two kinds under the
  // element of the kind with fewer elements (ties: the lower kind), whatever the indices: an
  // NP-CNT list has a row per NP holding its segments. The driver then walks a few thousand
  // full rows and prefetches the segments (the far elements of each row), not the segments'
  // rows with an NP or two each, whose own lines it cannot prefetch (x_i at the row, f_i and t_i
  // at the scatter were most of that pass's time on the medium film with 4000 NPs).
  std::array<std::size_t, kElementKinds> kind_count{};
  if (!all_kinds) kind_count = kind_counts(el);
  const auto row_kind = [&](int a, int b) {  // whether pairs of kinds a ≠ b are rows of a
    return kind_count[a] != kind_count[b] ? kind_count[a] < kind_count[b] : a < b;
  };
  int partners[kElementKinds][kElementKinds];     // per kind: the layers it scans, then -1
  bool other_kind[kElementKinds][kElementKinds];  // ... and whether that layer is of another kind
  for (int a = 0; a < kElementKinds; ++a) {
    int m = 0;
    for (int b = 0; b < kElementKinds; ++b) {
      const bool scans =
          all_kinds ? b == 0
                    : kinds_.has(static_cast<ElementKind>(a), static_cast<ElementKind>(b)) &&
                          (a == b || row_kind(a, b));
      if (!scans) continue;
      other_kind[a][m] = !all_kinds && a != b;
      partners[a][m++] = layer_of[b];
    }
    for (; m < kElementKinds; ++m) partners[a][m] = -1;
  }

  // Bounding box of the current positions (wrapped into the box along periodic axes, where the
  // grid spans the box); every position must be finite. Threaded: min and max are exact, so the
  // box does not depend on the thread count.
  const long nl = static_cast<long>(n);
  const bool threaded = n >= kParallelMin;
  double lx = std::numeric_limits<double>::max(), ly = lx, lz = lx;
  double hx = std::numeric_limits<double>::lowest(), hy = hx, hz = hx;
  long n_binned_l = 0, first_bad = nl;
#pragma omp parallel for schedule(static) if (threaded) \
    reduction(min : lx, ly, lz, first_bad) reduction(max : hx, hy, hz) reduction(+ : n_binned_l)
  for (long i = 0; i < nl; ++i) {
    const Vec3& p = el.x[i];
    if (!p.allFinite()) first_bad = std::min(first_bad, i);
    if (!binned(static_cast<std::size_t>(i))) continue;
    ++n_binned_l;
    lx = std::min(lx, p.x());
    ly = std::min(ly, p.y());
    lz = std::min(lz, p.z());
    hx = std::max(hx, p.x());
    hy = std::max(hy, p.y());
    hz = std::max(hz, p.z());
  }
  if (first_bad < nl) throw_non_finite(el, static_cast<std::size_t>(first_bad));
  const std::size_t n_binned = static_cast<std::size_t>(n_binned_l);
  Vec3 lo(lx, ly, lz), hi(hx, hy, hz);
  if (n_binned == 0) lo = hi = Vec3::Zero();
  for (int d = 0; d < 3; ++d)
    if (domain_.periodic(d)) {
      lo[d] = domain_.lo()[d];
      hi[d] = domain_.hi()[d];
    }
  const Vec3 ext = hi - lo;

  // Cell grid: cells at least range / kReach wide (a pair closer than `range` is then at most
  // kReach cells apart along each axis), at most max(64, 4N) cells in all (a sparse cloud over a
  // large box gets wider cells instead of a huge empty grid).
  // The keys (layer, cell) must fit 32 bits below the kNone mark.
  const double max_cells = std::min(std::max(64.0, 4.0 * static_cast<double>(n_binned)),
                                    4.0e9 / static_cast<double>(layers));
  double cell = range / kReach * (1.0 + kCellMargin);
  long dims[3];
  auto grid = [&](double c) {
    double total = 1.0;
    for (int d = 0; d < 3; ++d) {
      // At most 1e6 cells along an axis; one cell along an axis whose extent overflowed.
      const double k = ext[d] / c;
      dims[d] = k < 1e6 ? std::max(1L, static_cast<long>(k)) : std::isfinite(k) ? 1000000L : 1L;
      total *= static_cast<double>(dims[d]);
    }
    return total;
  };
  for (double total = grid(cell); total > max_cells; total = grid(cell))
    cell *= std::max(1.01, std::cbrt(total / max_cells));
  const long nx = dims[0], ny = dims[1], nz = dims[2];
  const std::size_t n_cells = static_cast<std::size_t>(nx * ny * nz);
  // Inverse cell widths; each width ext/dims >= cell.
  Vec3 inv_w;
  for (int d = 0; d < 3; ++d) inv_w[d] = ext[d] > 0 ? static_cast<double>(dims[d]) / ext[d] : 0.0;

  // Counting sort of the elements into cells (keys layer · n_cells + cell), stable in element
  // index, on the team: each thread takes a contiguous range of the elements (its part of the
  // cells' contents in element order) and counts their cells; a cell's elements are laid out thread
  // by thread, so in element order, the starts found by a scan over the cells in ranges (each
  // thread's range summed, the ranges' sums added in order, each range scanned from its base); each
  // thread then places its own elements. The result is the serial sort's, whatever the thread count
  // (it was serial; on the team alone it made a 2-thread film build 6 % faster).
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  cell_of_.resize(n);
  const std::size_t n_keys = static_cast<std::size_t>(layers) * n_cells;
  cell_start_.resize(n_keys + 1);
  // Padded so that the scan's vectors may read past a run's end (the padding is never kept).
  cell_elem_.resize(n_binned + cell_scan::kPad, 0u);
  cell_px_.resize(n_binned + cell_scan::kPad, 0.0);
  cell_py_.resize(n_binned + cell_scan::kPad, 0.0);
  cell_pz_.resize(n_binned + cell_scan::kPad, 0.0);
  const int sort_threads = threaded ? omp_get_max_threads() : 1;
  if (cell_count_.size() < static_cast<std::size_t>(sort_threads)) cell_count_.resize(sort_threads);
  for (int t = 0; t < sort_threads; ++t) cell_count_[t].resize(n_keys);
  range_sum_.assign(static_cast<std::size_t>(std::max(sort_threads, omp_get_max_threads())) + 1, 0);
  const long nc = static_cast<long>(n_keys);
  const long nc_grid = static_cast<long>(n_cells);
#pragma omp parallel num_threads(sort_threads)
  {
    const int nt = omp_get_num_threads();
    const int tid = omp_get_thread_num();
    const long a = nl * tid / nt, b = nl * (tid + 1) / nt;
    std::vector<std::uint32_t>& count = cell_count_[tid];
    std::fill(count.begin(), count.end(), 0u);
    for (long i = a; i < b; ++i) {
      if (!binned(static_cast<std::size_t>(i))) {
        cell_of_[i] = kNone;
        continue;
      }
      const Vec3 r = ((periodic ? domain_.wrap(el.x[i]) : el.x[i]) - lo).cwiseProduct(inv_w);
      const long cx = std::clamp(static_cast<long>(r.x()), 0L, nx - 1);
      const long cy = std::clamp(static_cast<long>(r.y()), 0L, ny - 1);
      const long cz = std::clamp(static_cast<long>(r.z()), 0L, nz - 1);
      const long layer = layer_of[static_cast<int>(el.kind[i])];
      const auto c = static_cast<std::uint32_t>(layer * nc_grid + cx + nx * (cy + ny * cz));
      cell_of_[i] = c;
      ++count[c];
    }
#pragma omp barrier
    // This thread's range of cells: their elements over all threads, summed.
    const long ca = nc * tid / nt, cb = nc * (tid + 1) / nt;
    std::size_t sum = 0;
    for (long c = ca; c < cb; ++c)
      for (int t = 0; t < nt; ++t) sum += cell_count_[t][c];
    range_sum_[tid + 1] = sum;
#pragma omp barrier
    std::uint32_t at = 0;
    for (int t = 0; t <= tid; ++t) at += static_cast<std::uint32_t>(range_sum_[t]);
    // Each thread's count becomes where its next element of the cell goes.
    for (long c = ca; c < cb; ++c) {
      cell_start_[c] = at;
      for (int t = 0; t < nt; ++t) {
        const std::uint32_t k = cell_count_[t][c];
        cell_count_[t][c] = at;
        at += k;
      }
    }
    if (tid == nt - 1) cell_start_[n_keys] = at;
#pragma omp barrier
    for (long i = a; i < b; ++i) {
      const std::uint32_t c = cell_of_[i];
      if (c == kNone) continue;
      const std::uint32_t k = count[c]++;
      cell_elem_[k] = static_cast<std::uint32_t>(i);
      cell_px_[k] = el.x[i].x();
      cell_py_[k] = el.x[i].y();
      cell_pz_[k] = el.x[i].z();
    }
  }

  // The cells within kReach of cell c along one axis, as at most two runs [first, last]: one run
  // clipped at the grid's ends on an open axis; on a periodic axis the run wraps (split in two at
  // the end of the grid), and an axis of at most 2·kReach + 1 cells is scanned whole, once.
  struct Runs {
    long first[2], last[2];
    int count;
  };
  auto runs = [&](long c, long dim, bool wraps) {
    Runs r{};
    if (!wraps) {
      r.first[0] = std::max(c - kReach, 0L);
      r.last[0] = std::min(c + kReach, dim - 1);
      r.count = 1;
    } else if (dim <= 2 * kReach + 1) {
      r.first[0] = 0;
      r.last[0] = dim - 1;
      r.count = 1;
    } else if (c - kReach < 0) {
      r = {{0, c - kReach + dim}, {c + kReach, dim - 1}, 2};
    } else if (c + kReach > dim - 1) {
      r = {{c - kReach, 0}, {dim - 1, c + kReach - dim}, 2};
    } else {
      r.first[0] = c - kReach;
      r.last[0] = c + kReach;
      r.count = 1;
    }
    return r;
  };
  const bool wrap_x = domain_.periodic(0), wrap_y = domain_.periodic(1),
             wrap_z = domain_.periodic(2);

  // Neighbours of each i: scan the block of cells within kReach of i's cell. Cells adjacent in x
  // are adjacent in memory, so each (y, z) row of the block is one contiguous run (two where it
  // wraps). The elements are dealt to the threads in chunks of kChunk, round robin (contiguous
  // halves left one thread with 44 % more work on a generated film: its dense regions are not
  // spread evenly over the element order); each thread collects into its own buffer and notes
  // where each of its chunks starts. The per-i lists are sorted and copied to their place, so
  // the result does not depend on the thread count or scheduling.
  offsets_.resize(n + 1);
  offsets_[0] = 0;
  const int max_threads = n >= kParallelMin ? omp_get_max_threads() : 1;
  if (thread_neighbors_.size() < static_cast<std::size_t>(max_threads))
    thread_neighbors_.resize(max_threads);
  constexpr std::size_t kChunk = 256;
  const std::size_t n_chunks = (n + kChunk - 1) / kChunk;
  chunk_pos_.resize(n_chunks);
  const Exclusion* exclusion = exclusion_ ? &exclusion_ : nullptr;
  std::string error;
  const cell_scan::Cells cells{cell_px_.data(), cell_py_.data(), cell_pz_.data(),
                               cell_elem_.data()};
  cell_scan::Probe probe_0{};
  probe_0.range2 = range2;
  for (int d = 0; d < 3; ++d)
    if (domain_.periodic(d)) {
      probe_0.length[d] = domain_.length()[d];
      probe_0.inv_length[d] = 1.0 / domain_.length()[d];
    }
  x_at_build_.resize(n);  // filled by the team once the list is built

#pragma omp parallel num_threads(max_threads)
  {
    const int nt = omp_get_num_threads();
    const int tid = omp_get_thread_num();
    // `out` is used as a raw buffer: its size is its usable capacity, `used` the filled part.
    std::vector<std::uint32_t>& out = thread_neighbors_[tid];
    std::size_t used = 0;
    cell_scan::Probe probe = probe_0;
    try {
      for (std::size_t chunk = static_cast<std::size_t>(tid); chunk < n_chunks; chunk += nt) {
        chunk_pos_[chunk] = used;
        const std::size_t chunk_end = std::min(n, (chunk + 1) * kChunk);
        for (std::size_t i = chunk * kChunk; i < chunk_end; ++i) {
          const std::uint32_t c = cell_of_[i];
          if (c == kNone) {
            offsets_[i + 1] = 0;
            continue;
          }
          const long cell = c % nc_grid;
          const long cx = cell % nx, cy = (cell / nx) % ny, cz = cell / (nx * ny);
          const Runs rx = runs(cx, nx, wrap_x), ry = runs(cy, ny, wrap_y),
                     rz = runs(cz, nz, wrap_z);
          // The contiguous runs of candidates in the block: at most 2 × 3 × 3 per partner
          // layer (wrapping axes split a run in two); group 0 the layer of i's own kind (j > i
          // kept), group 1 the layers of other kinds (every j kept).
          std::uint32_t run_begin[2][18 * kElementKinds], run_end[2][18 * kElementKinds];
          int n_runs[2] = {0, 0};
          std::size_t candidates = 0;
          const int* partner = partners[static_cast<int>(el.kind[i])];
          for (int p = 0; p < kElementKinds && partner[p] >= 0; ++p) {
            const int g = other_kind[static_cast<int>(el.kind[i])][p] ? 1 : 0;
            for (int a = 0; a < rz.count; ++a)
              for (long z = rz.first[a]; z <= rz.last[a]; ++z)
                for (int b = 0; b < ry.count; ++b)
                  for (long y = ry.first[b]; y <= ry.last[b]; ++y) {
                    const long base = partner[p] * nc_grid + nx * (y + ny * z);
                    for (int e = 0; e < rx.count; ++e) {
                      const std::uint32_t kb = cell_start_[base + rx.first[e]],
                                          ke = cell_start_[base + rx.last[e] + 1];
                      if (kb == ke) continue;
                      run_begin[g][n_runs[g]] = kb;
                      run_end[g][n_runs[g]++] = ke;
                      candidates += ke - kb;
                    }
                  }
          }
          // Room for every candidate and a vector more, so the scan can store before it counts.
          const std::size_t room = used + candidates + cell_scan::kPad;
          if (out.size() < room) out.resize(std::max(2 * out.size(), room));
          probe.x = el.x[i].x();
          probe.y = el.x[i].y();
          probe.z = el.x[i].z();
          probe.i = static_cast<std::uint32_t>(i);
          std::uint32_t* const first = out.data() + used;
          std::uint32_t* o = first;
          for (int g = 0; g < 2; ++g) {
            if (n_runs[g] == 0) continue;
            probe.any_j = g == 1;
            o = cell_scan::scan(cells, probe, run_begin[g], run_end[g], n_runs[g], o);
          }
          if (exclusion) {  // one pass over the pairs within range (of partner kinds only)
            std::uint32_t* w = first;
            for (std::uint32_t* r = first; r != o; ++r)
              if (!(*exclusion)(el, i, *r)) *w++ = *r;
            o = w;
          }
          // Insertion sort: a few to a few dozen entries, in ascending runs (one per cell).
          for (std::uint32_t* r = first + 1; r < o; ++r) {
            const std::uint32_t v = *r;
            std::uint32_t* w = r;
            for (; w != first && w[-1] > v; --w) *w = w[-1];
            *w = v;
          }
          offsets_[i + 1] = static_cast<std::uint32_t>(o - first);
          used += static_cast<std::size_t>(o - first);
        }
      }
    } catch (const std::exception& e) {
#pragma omp critical(mdem_neighbor_list_error)
      if (error.empty()) error = e.what();
    } catch (...) {
#pragma omp critical(mdem_neighbor_list_error)
      if (error.empty()) error = "neighbour list: the exclusion predicate threw";
    }
#pragma omp barrier
    // The offsets: a scan of the rows' lengths over contiguous ranges of the elements, as the
    // cells' above (it was a serial loop).
    const std::size_t ea = n * tid / nt, eb = n * (tid + 1) / nt;
    std::size_t part = 0;
    for (std::size_t i = ea; i < eb; ++i) part += offsets_[i + 1];
    range_sum_[tid + 1] = part;
#pragma omp barrier
    std::size_t total = 0, base = 0;
    for (int t = 1; t <= nt; ++t) {
      if (t <= tid) base += range_sum_[t];
      total += range_sum_[t];
    }
    const bool fits = total < std::numeric_limits<std::uint32_t>::max();
    if (error.empty() && fits)
      for (std::size_t i = ea; i < eb; ++i) {
        base += offsets_[i + 1];
        offsets_[i + 1] = static_cast<std::uint32_t>(base);
      }
#pragma omp single
    {
      if (error.empty()) {
        if (!fits)
          error = "neighbour list: more than 2^32 - 1 pairs";
        else
          neighbors_.resize(total);
      }
    }  // implicit barrier
    if (error.empty()) {
      for (std::size_t chunk = static_cast<std::size_t>(tid); chunk < n_chunks; chunk += nt) {
        const std::size_t first = offsets_[chunk * kChunk];
        const std::size_t last = offsets_[std::min(n, (chunk + 1) * kChunk)];
        std::copy_n(out.begin() + static_cast<std::ptrdiff_t>(chunk_pos_[chunk]), last - first,
                    neighbors_.begin() + static_cast<std::ptrdiff_t>(first));
      }
      std::copy(el.x.begin() + static_cast<std::ptrdiff_t>(ea),
                el.x.begin() + static_cast<std::ptrdiff_t>(eb),
                x_at_build_.begin() + static_cast<std::ptrdiff_t>(ea));
    }
  }
  if (!error.empty()) {
    builds_ = 0;  // the list is not usable
    throw std::runtime_error(error);
  }
  check_planned_ = false;  // planned at the next check
  ++builds_;
}

void NeighborList::save_state(StateWriter& w) const {
  w.begin("neighbor_list");
  w.put(cutoff_);
  w.put(skin_);
  w.put(static_cast<std::uint64_t>(builds_));
  w.put(x_at_build_);
  w.put(offsets_);
  w.put(neighbors_);
}

void NeighborList::load_state(StateReader& r, std::size_t n) {
  r.begin("neighbor_list");
  const auto cutoff = r.get<double>("cutoff"), skin = r.get<double>("skin");
  if (cutoff != cutoff_ || skin != skin_)
    r.fail("cutoff", "list of cutoff " + std::to_string(cutoff) + " nm and skin " +
                         std::to_string(skin) + " nm, this job uses " + std::to_string(cutoff_) +
                         " and " + std::to_string(skin_) + " nm");
  const auto builds = r.get<std::uint64_t>("builds");
  std::vector<Vec3> x;
  std::vector<std::uint32_t> offsets, neighbors;
  r.get(x, "x_at_build", n);
  r.get(offsets, "offsets", n + 1);
  r.get(neighbors, "neighbors");
  // A corrupt list would send the pair loops out of bounds: check the CSR before using it.
  if (offsets[0] != 0 || offsets[n] != neighbors.size())
    r.fail("offsets", "do not span the neighbour array");
  for (std::size_t i = 0; i < n; ++i) {
    if (offsets[i] > offsets[i + 1]) r.fail("offsets", "decrease at element " + std::to_string(i));
    for (std::uint32_t k = offsets[i]; k < offsets[i + 1]; ++k)
      if (neighbors[k] == i || neighbors[k] >= n)
        r.fail("neighbors", "entry " + std::to_string(k) + " of element " + std::to_string(i) +
                                " is not another element of the " + std::to_string(n));
  }
  builds_ = static_cast<std::size_t>(builds);
  check_planned_ = false;  // planned from the elements at the next check
  x_at_build_ = std::move(x);
  offsets_ = std::move(offsets);
  neighbors_ = std::move(neighbors);
}

const char* neighbor_scan_target() { return cell_scan::target_name(); }

std::size_t NeighborList::memory_bytes() const {
  return capacity_bytes(x_at_build_) + capacity_bytes(offsets_) + capacity_bytes(neighbors_) +
         capacity_bytes(cell_of_) + capacity_bytes(cell_start_) + capacity_bytes(cell_elem_) +
         capacity_bytes(cell_px_) + capacity_bytes(cell_py_) + capacity_bytes(cell_pz_) +
         capacity_bytes(cell_count_) + capacity_bytes(range_sum_) +
         capacity_bytes(thread_neighbors_) + capacity_bytes(chunk_pos_) +
         capacity_bytes(check_idx_);
}

}  // namespace mdem
