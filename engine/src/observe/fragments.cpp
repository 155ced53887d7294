#include "mdem/observe/fragments.h"

#include <algorithm>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/contact/np_cnt_contact.h"
#include "mdem/force/contact/np_np_contact.h"
#include "mdem/integrate/system.h"

namespace mdem {

Fragments count_fragments(std::size_t n, std::span<const Edge> edges, double min_fraction) {
  if (!(min_fraction >= 0 && min_fraction <= 1)) {
    std::ostringstream os;
    os << "count_fragments: min_fraction = " << min_fraction << "; it must lie in [0, 1]";
    throw std::invalid_argument(os.str());
  }
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto root = [&](std::uint32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];  // path halving
    return a;
  };
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const auto [a, b] = edges[k];
    if (a >= n || b >= n) {
      std::ostringstream os;
      os << "count_fragments: edge " << k << " (" << a << ", " << b
         << ") names an element outside 0.." << (n == 0 ? 0 : n - 1) << " (" << n << " elements)";
      throw std::invalid_argument(os.str());
    }
    const std::uint32_t ra = root(a), rb = root(b);
    if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
  }
  std::vector<std::size_t> size(n, 0);
  for (std::uint32_t i = 0; i < n; ++i) ++size[root(i)];
  Fragments f;
  const double min_size = min_fraction * static_cast<double>(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (size[i] == 0) continue;
    if (static_cast<double>(size[i]) < min_size) {
      ++f.ignored;
      f.ignored_elements += size[i];
    } else {
      f.sizes.push_back(size[i]);
    }
  }
  std::sort(f.sizes.begin(), f.sizes.end(), std::greater<>());
  f.count = f.sizes.size();
  return f;
}

namespace {

// The listed pairs of the system's pair model M with U < 0, by its own kernel (the one-pair
// physics the forces come from), with the minimum-image displacement the driver uses.
template <class M>
void add_attracting_pairs(const System& sys, std::vector<Edge>& edges) {
  const M* m = sys.find<M>();
  if (!m) return;
  const NeighborList* list = sys.neighbors(*m);
  if (!list) return;
  const Elements& el = sys.elements();
  const auto& off = list->offsets();
  const auto& nb = list->neighbors();
  if (off.size() != el.size() + 1) return;
  const auto& k = m->kernel();
  // The kernel's per-evaluation cache (the vdW axes), as the force evaluation fills it.
  if constexpr (requires { k.begin(el); }) k.begin(el);
  if constexpr (requires { k.prepare(el, 0L); })
    for (long i = 0; i < static_cast<long>(el.size()); ++i) k.prepare(el, i);
  const bool filter = !list_is_for(*list, *m);
  const Domain& domain = list->domain();
  for (std::size_t i = 0; i < el.size(); ++i)
    for (std::uint32_t p = off[i]; p < off[i + 1]; ++p) {
      const std::size_t j = nb[p];
      if (filter && (!m->kinds().has(el.kind[i], el.kind[j]) || k.excludes(el, i, j))) continue;
      PairForces f;
      if (k.pair(el, i, j, domain.delta(el.x[i], el.x[j]), f) && f.energy < 0)
        edges.emplace_back(static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j));
    }
}

}  // namespace

std::vector<Edge> film_fragment_edges(const System& sys) {
  if (!sys.initialized())
    throw std::logic_error("film_fragment_edges: the system was never initialized");
  std::vector<Edge> edges;
  if (const ParallelBond* b = sys.find<ParallelBond>())
    for (const Bond& bond : b->bonds()) edges.emplace_back(bond.i, bond.j);
  add_attracting_pairs<AnisotropicVdw>(sys, edges);
  add_attracting_pairs<NpCntContact>(sys, edges);
  add_attracting_pairs<NpNpContact>(sys, edges);
  return edges;
}

Fragments count_film_fragments(const System& sys, double min_fraction) {
  const std::vector<Edge> edges = film_fragment_edges(sys);
  return count_fragments(sys.elements().size(), edges, min_fraction);
}

}  // namespace mdem
