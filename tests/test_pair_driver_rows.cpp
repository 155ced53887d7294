// The pair driver's split of a neighbour list's rows among threads (pair_driver.h,
// balanced_rows): every row exactly once, in contiguous runs in thread order, and shares of the
// cost (4 per listed pair + 1 per row) within one row's cost of an even split.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "mdem/force/pair_driver.h"

using namespace mdem;
using pair_driver_detail::balanced_rows;

namespace {

// Row offsets of a list with the given pairs per row.
std::vector<std::uint32_t> offsets_of(const std::vector<std::uint32_t>& pairs) {
  std::vector<std::uint32_t> off(pairs.size() + 1, 0);
  for (std::size_t i = 0; i < pairs.size(); ++i) off[i + 1] = off[i] + pairs[i];
  return off;
}

void expect_partition(const std::vector<std::uint32_t>& off, int threads) {
  const long n = static_cast<long>(off.size()) - 1;
  const auto cost = [&](long a, long b) {
    return 4.0 * (off[b] - off[a]) + static_cast<double>(b - a);
  };
  const double total = cost(0, n);
  double max_row = 0;
  for (long i = 0; i < n; ++i) max_row = std::max(max_row, cost(i, i + 1));
  long expected_first = 0;
  for (int t = 0; t < threads; ++t) {
    const auto [first, last] = balanced_rows(off, t, threads);
    EXPECT_EQ(first, expected_first) << "thread " << t << " of " << threads;
    EXPECT_LE(first, last) << "thread " << t << " of " << threads;
    EXPECT_LE(std::abs(cost(first, last) - total / threads), max_row + 1e-9)
        << "thread " << t << " of " << threads;
    expected_first = last;
  }
  EXPECT_EQ(expected_first, n) << threads << " threads";
}

}  // namespace

TEST(PairDriverRows, EveryRowOnceContiguousAndBalanced) {
  std::mt19937 g(13);
  std::uniform_int_distribution<std::uint32_t> pairs(0, 12);
  std::vector<std::uint32_t> rows(5000);
  for (auto& r : rows) r = pairs(g);
  // Uneven along the element order: a dense half and a sparse half, as a generated film's
  // regions are.
  for (std::size_t i = 0; i < rows.size() / 2; ++i) rows[i] *= 3;
  const auto off = offsets_of(rows);
  for (int threads : {1, 2, 3, 4, 7}) expect_partition(off, threads);
}

TEST(PairDriverRows, EmptyListsAndMoreThreadsThanRows) {
  expect_partition(offsets_of({}), 2);                     // no elements
  expect_partition(offsets_of({0, 0, 0, 0}), 2);           // elements, no pairs
  expect_partition(offsets_of({5, 0, 3}), 8);              // more threads than rows
  expect_partition(offsets_of({1000, 0, 0, 0, 0, 0}), 2);  // one row holds almost everything
}

TEST(PairDriverRows, OneThreadTakesEverything) {
  const auto off = offsets_of({3, 1, 4, 1, 5, 9, 2, 6});
  const auto [first, last] = balanced_rows(off, 0, 1);
  EXPECT_EQ(first, 0);
  EXPECT_EQ(last, 8);
}
