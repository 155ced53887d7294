#include "mdem/observe/fragments.h"

#include <algorithm>
#include <numeric>
#include <sstream>
#include <stdexcept>

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

}  // namespace mdem
