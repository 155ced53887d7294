#pragma once
// Cell list + Verlet list with a skin (half list: each pair once; see neighbors()).
// Rebuilt only when some element has moved more than half the skin since the last build.
// Distances are minimum images in the list's domain: along a periodic axis the cell grid spans the
// box and wraps, and a pair is listed when its minimum image is within cutoff + skin. A list may
// hold only some pairs of element kinds (a sub-list of the pair table): elements of other kinds
// are not even binned.
#include <cstdint>
#include <functional>
#include <vector>

#include "mdem/core/domain.h"
#include "mdem/core/elements.h"
#include "mdem/neighbor/kind_pairs.h"

namespace mdem {

class StateWriter;
class StateReader;
class ForceModel;

class NeighborList {
 public:
  // Pairs closer than cutoff + skin at build time are listed. Throws std::invalid_argument for a
  // non-positive cutoff, a negative skin, or a periodic axis shorter than 2·(cutoff + skin).
  NeighborList(double cutoff, double skin, Domain domain = {});

  // The kind pairs listed (default: all). Pairs of other kinds are left out.
  void set_kinds(KindPairs kinds) { kinds_ = kinds; }
  KindPairs kinds() const { return kinds_; }
  const Domain& domain() const { return domain_; }
  // The pair model this list was built for (its kinds and exclusion): that model, and the models
  // that belong to its pairs, need not filter the listed pairs again. Null: a list of any pairs.
  void set_owner(const ForceModel* m) { owner_ = m; }
  const ForceModel* owner() const { return owner_; }

  // Predicate that leaves a pair out of the list (true = exclude). Optional.
  using Exclusion = std::function<bool(const Elements&, std::size_t, std::size_t)>;
  void set_exclusion(Exclusion ex) { exclusion_ = std::move(ex); }

  // True when the list must be rebuilt before it can be trusted for el's current positions: some
  // element of a listed kind moved more than half the skin since the build (a list whose kinds
  // no two elements can form, e.g. NP-CNT without NPs, stays empty and never needs one while the
  // element count holds; element kinds never change).
  bool needs_rebuild(const Elements& el) const;
  // The list no longer matches the elements (they were reordered): needs_rebuild is true until
  // the next build.
  void invalidate() { x_at_build_.clear(); }
  // Builds the list (threaded over cells). Throws std::runtime_error on non-finite positions.
  void build(const Elements& el);

  double cutoff() const { return cutoff_; }
  double skin() const { return skin_; }
  std::size_t builds() const { return builds_; }
  std::size_t pair_count() const { return neighbors_.size(); }
  // Largest displacement of any element since the last build (nm).
  double max_displacement(const Elements& el) const;

  // Neighbours of element i: neighbors()[offsets()[i] .. offsets()[i+1]), ascending. Each pair
  // once: a pair of one kind under its lower index (j > i), a pair of two kinds under the
  // element of the kind with fewer elements (ties: the lower kind), e.g. an NP-CNT pair under
  // its NP, whatever the indices.
  const std::vector<std::uint32_t>& offsets() const { return offsets_; }
  const std::vector<std::uint32_t>& neighbors() const { return neighbors_; }

  // The list and the positions it was built at, for checkpoints: a resumed run rebuilds at the
  // same steps, and between rebuilds iterates the same pairs in the same order. load_state checks
  // cutoff and skin and that the list is well-formed for n_elements (throws CheckpointError).
  void save_state(StateWriter& w) const;
  void load_state(StateReader& r, std::size_t n_elements);
  // Bytes the list and its build scratch hold (capacities).
  std::size_t memory_bytes() const;

 private:
  double cutoff_, skin_;
  Domain domain_;
  KindPairs kinds_ = KindPairs::all();
  const ForceModel* owner_ = nullptr;
  Exclusion exclusion_;
  std::vector<Vec3> x_at_build_;
  std::vector<std::uint32_t> offsets_, neighbors_;
  std::size_t builds_ = 0;

  // Scratch of the build, kept between builds so a rebuild allocates nothing once warm.
  std::vector<std::uint32_t> cell_of_;     // cell of each element
  std::vector<std::uint32_t> cell_start_;  // CSR over cells: elements of cell c are
  std::vector<std::uint32_t> cell_elem_;   //   cell_elem_[cell_start_[c] .. cell_start_[c+1])
  std::vector<double> cell_px_, cell_py_, cell_pz_;  // positions in cell order (the scan's lanes)
  std::vector<std::vector<std::uint32_t>> cell_count_;  // per thread: its elements per cell
  std::vector<std::size_t> range_sum_;  // per thread's range: its cells' elements, rows' pairs
  std::vector<std::vector<std::uint32_t>> thread_neighbors_;  // per-thread output
  std::vector<std::size_t> chunk_pos_;  // each chunk's start in its thread's output

  // Which elements needs_rebuild checks: all (every element is of a listed kind); those of the
  // listed kinds, by index (check_idx_, ascending) when they are at most a quarter of all, or
  // (Kinds) by a pass over all that skips the others (a CNT-CNT list among NPs: an NP's motion
  // does not change it); none when no two elements can form a listed pair. Planned from the
  // elements' kinds at the first check after a build or a load_state, so a resumed run rebuilds
  // at the same steps.
  enum class CheckScope { All, Kinds, Listed, None };
  void plan_check(const Elements& el) const;
  // Largest displacement since the build of any element, or (of_kinds) of an element of a listed
  // kind (nm); infinite before the first build or when the element count changed.
  double largest_move(const Elements& el, bool of_kinds) const;
  mutable CheckScope check_scope_ = CheckScope::All;
  mutable bool check_planned_ = false;
  mutable std::vector<std::uint32_t> check_idx_;
};

// The instruction set the build's candidate test runs on, chosen at run time (Google Highway's
// dynamic dispatch over vectors of candidates), e.g. "AVX3", "AVX2", "EMU128".
const char* neighbor_scan_target();

}  // namespace mdem
