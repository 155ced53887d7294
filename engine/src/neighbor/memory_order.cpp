#include "mdem/neighbor/memory_order.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace mdem {

std::string_view to_string(MemoryOrder m) {
  switch (m) {
    case MemoryOrder::AsBuilt:
      return "as_built";
    case MemoryOrder::Morton:
      return "morton";
    case MemoryOrder::Slabs:
      return "slabs";
  }
  return "unknown";
}

namespace {

// The low 21 bits of v spread to every third bit (bit k of v to bit 3k).
std::uint64_t spread3(std::uint64_t v) {
  v &= 0x1fffffULL;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

// The elements' positions, wrapped into the box along the domain's periodic axes, and their
// lowest and highest corner (the box's along periodic axes). Throws std::runtime_error for more
// than 2^32 - 1 elements, and naming the first element whose position is not finite.
struct Positions {
  std::vector<Vec3> p;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::max()), hi = -lo;
};
Positions checked_positions(const Elements& el, const Domain& domain, const char* who) {
  const std::size_t n = el.size();
  if (n >= std::numeric_limits<std::uint32_t>::max())
    throw std::runtime_error(std::string(who) + ": more than 2^32 - 1 elements");
  const bool periodic = domain.any_periodic();
  Positions r;
  r.p.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& x = el.x[i];
    if (!x.allFinite()) {
      std::ostringstream m;
      m << who << ": element " << i << " (tag " << el.tag[i] << ") has a non-finite position ("
        << x.x() << ", " << x.y() << ", " << x.z() << "); the run has diverged";
      throw std::runtime_error(m.str());
    }
    r.p[i] = periodic ? domain.wrap(x) : x;
    r.lo = r.lo.cwiseMin(r.p[i]);
    r.hi = r.hi.cwiseMax(r.p[i]);
  }
  for (int d = 0; d < 3; ++d)
    if (domain.periodic(d)) {
      r.lo[d] = domain.lo()[d];
      r.hi[d] = domain.hi()[d];
    }
  return r;
}

}  // namespace

std::vector<std::uint32_t> morton_order(const Elements& el, double cell, const Domain& domain) {
  if (!std::isfinite(cell) || cell <= 0)
    throw std::invalid_argument("morton_order: the cell width must be finite and > 0 nm, got " +
                                std::to_string(cell));
  const std::size_t n = el.size();
  const Positions pos = checked_positions(el, domain, "morton_order");
  const Vec3 lo = pos.lo;
  // Cell coordinates clamp at 2^21 - 1 per axis (a box over 2 million cells wide keeps the order
  // of its far end as it was: correct, only less local).
  constexpr double kMaxCell = static_cast<double>((1u << 21) - 1);
  const double inv = 1.0 / cell;
  std::vector<std::uint64_t> key(n);
  std::uint64_t all_bits = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 r = (pos.p[i] - lo) * inv;
    std::uint64_t k = 0;
    for (int d = 0; d < 3; ++d)
      k |= spread3(static_cast<std::uint64_t>(std::clamp(r[d], 0.0, kMaxCell))) << d;
    key[i] = k;
    all_bits |= k;
  }
  // Stable LSD radix sort on the key's used bytes, from the elements in tag order: the elements
  // of one cell stay in tag order (a generated tube's segments in a run, as built), so the order
  // depends on positions and tags only, not on the order the elements were in before.
  std::vector<std::uint32_t> order = el.tag_order(), tmp(n);
  for (int shift = 0; shift < 64 && (all_bits >> shift) != 0; shift += 8) {
    std::size_t count[257] = {};
    for (std::uint32_t i : order) ++count[((key[i] >> shift) & 0xff) + 1];
    for (int b = 0; b < 256; ++b) count[b + 1] += count[b];
    for (std::uint32_t i : order) tmp[count[(key[i] >> shift) & 0xff]++] = i;
    order.swap(tmp);
  }
  return order;
}

std::vector<std::uint32_t> slab_order(const Elements& el, int slabs, const Domain& domain) {
  if (slabs < 1 || slabs > (1 << 16))
    throw std::invalid_argument("slab_order: the number of slabs must be in [1, 65536], got " +
                                std::to_string(slabs));
  const std::size_t n = el.size();
  const Positions pos = checked_positions(el, domain, "slab_order");
  const Vec3 width = pos.hi - pos.lo;
  int axis = 0;
  for (int d = 1; d < 3; ++d)
    if (width[d] > width[axis]) axis = d;
  // The cuts: the positions of rank n·s/slabs along the axis; an element at or past cut s lies in
  // slab s or beyond.
  std::vector<double> sorted(n);
  for (std::size_t i = 0; i < n; ++i) sorted[i] = pos.p[i][axis];
  std::vector<double> cuts;
  for (int s = 1; s < slabs && n > 0; ++s) {
    const auto rank = sorted.begin() + static_cast<long>(n * static_cast<std::size_t>(s) / slabs);
    std::nth_element(sorted.begin(), rank, sorted.end());
    cuts.push_back(*rank);
  }
  // A counting sort by slab from the tag order: stable, so tag order within each slab.
  std::vector<std::uint32_t> slab(n);
  std::vector<std::size_t> start(static_cast<std::size_t>(slabs) + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    slab[i] = static_cast<std::uint32_t>(
        std::upper_bound(cuts.begin(), cuts.end(), pos.p[i][axis]) - cuts.begin());
    ++start[slab[i] + 1];
  }
  for (int s = 0; s < slabs; ++s) start[s + 1] += start[s];
  std::vector<std::uint32_t> order(n);
  for (std::uint32_t i : el.tag_order()) order[start[slab[i]]++] = i;
  return order;
}

}  // namespace mdem
