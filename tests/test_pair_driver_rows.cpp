// The pair driver's split of a neighbour list's rows among threads (pair_driver.h,
// balanced_rows): every row from the first to the last that holds pairs exactly once (the empty
// rows before and after are dealt to no one), in contiguous runs in thread order, and shares of
// the cost (4 per listed pair + 1 per row) within one row's cost of an even split.
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
  // The rows that hold pairs, by a plain scan: [r0, r1), empty when none does.
  long r0 = 0, r1 = 0;
  for (long i = 0; i < n; ++i)
    if (off[i + 1] > off[i]) {
      if (r1 == 0) r0 = i;
      r1 = i + 1;
    }
  EXPECT_EQ(pair_driver_detail::listed_rows(off), std::make_pair(r0, r1));
  const auto cost = [&](long a, long b) {
    return 4.0 * (off[b] - off[a]) + static_cast<double>(b - a);
  };
  const double total = cost(r0, r1);
  double max_row = 0;
  for (long i = r0; i < r1; ++i) max_row = std::max(max_row, cost(i, i + 1));
  long expected_first = r0;
  for (int t = 0; t < threads; ++t) {
    const auto [first, last] = balanced_rows(off, t, threads);
    EXPECT_EQ(first, expected_first) << "thread " << t << " of " << threads;
    EXPECT_LE(first, last) << "thread " << t << " of " << threads;
    EXPECT_LE(std::abs(cost(first, last) - total / threads), max_row + 1e-9)
        << "thread " << t << " of " << threads;
    expected_first = last;
  }
  EXPECT_EQ(expected_first, r1) << threads << " threads";
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

// A sub-list of a rare kind: its pairs in the last rows (NPs after the segments), or in a few
// rows in between.
TEST(PairDriverRows, EmptyRowsBeforeAndAfterAreDealtToNoOne) {
  std::vector<std::uint32_t> rows(10000, 0);
  for (std::size_t i = 9700; i < rows.size(); ++i) rows[i] = 1 + i % 7;
  for (int threads : {1, 2, 3}) expect_partition(offsets_of(rows), threads);
  const auto at_end = offsets_of(rows);
  EXPECT_EQ(balanced_rows(at_end, 0, 2).first, 9700);
  EXPECT_EQ(balanced_rows(at_end, 1, 2).second, 10000);
  std::vector<std::uint32_t> middle(5000, 0);
  middle[1234] = 3;
  middle[1240] = 2;
  middle[4000] = 9;
  for (int threads : {1, 2, 4}) expect_partition(offsets_of(middle), threads);
  EXPECT_EQ(balanced_rows(offsets_of(middle), 0, 1), std::make_pair(1234L, 4001L));
}

TEST(PairDriverRows, OneThreadTakesEverything) {
  const auto off = offsets_of({3, 1, 4, 1, 5, 9, 2, 6});
  const auto [first, last] = balanced_rows(off, 0, 1);
  EXPECT_EQ(first, 0);
  EXPECT_EQ(last, 8);
}
