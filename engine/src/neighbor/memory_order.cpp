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

}  // namespace

std::vector<std::uint32_t> morton_order(const Elements& el, double cell, const Domain& domain) {
  if (!std::isfinite(cell) || cell <= 0)
    throw std::invalid_argument("morton_order: the cell width must be finite and > 0 nm, got " +
                                std::to_string(cell));
  const std::size_t n = el.size();
  if (n >= std::numeric_limits<std::uint32_t>::max())
    throw std::runtime_error("morton_order: more than 2^32 - 1 elements");
  const bool periodic = domain.any_periodic();
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::max());
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& p = el.x[i];
    if (!p.allFinite()) {
      std::ostringstream m;
      m << "morton_order: element " << i << " (tag " << el.tag[i] << ") has a non-finite position ("
        << p.x() << ", " << p.y() << ", " << p.z() << "); the run has diverged";
      throw std::runtime_error(m.str());
    }
    lo = lo.cwiseMin(periodic ? domain.wrap(p) : p);
  }
  for (int d = 0; d < 3; ++d)
    if (domain.periodic(d)) lo[d] = domain.lo()[d];
  // Cell coordinates clamp at 2^21 - 1 per axis (a box over 2 million cells wide keeps the order
  // of its far end as it was: correct, only less local).
  constexpr double kMaxCell = static_cast<double>((1u << 21) - 1);
  const double inv = 1.0 / cell;
  std::vector<std::uint64_t> key(n);
  std::uint64_t all_bits = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 r = ((periodic ? domain.wrap(el.x[i]) : el.x[i]) - lo) * inv;
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

}  // namespace mdem
