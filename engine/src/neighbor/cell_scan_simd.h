#pragma once
// The neighbour-list build's inner loop over vectors of candidates: the elements of one element's
// block of cells (their positions in cell order, structure of arrays) tested against the list's
// range, with the widest instruction set of the running CPU chosen at run time (Google Highway's
// dynamic dispatch). The scalar loop it replaced tested one candidate at a time, ~1.9 ns each:
// 98 % of a build on a film.
#include <cstddef>
#include <cstdint>

namespace mdem::cell_scan {

// Candidates in cell order: position (x, y, z) and element index of slot k. Each array holds
// the slots plus kPad more that may be read (never kept) by a vector that runs past a run's end.
struct Cells {
  const double *x, *y, *z;
  const std::uint32_t* elem;
};
inline constexpr std::size_t kPad = 8;

// The element whose candidates are scanned, and the list's range: its position, index, range²,
// and the box length and its inverse along each axis (both 0 along an open axis, where the
// displacement is then exactly x_j − x_i).
struct Probe {
  double x, y, z;
  std::uint32_t i;
  double range2;
  double length[3], inv_length[3];
  bool any_j = false;  // keep every j in range, not only j > i (candidates of other kinds than i's)
};

// Appends to `out`, in slot order over the runs [begin[r], end[r]) (r < runs), the element
// index j of every slot with j > i (every j with any_j) whose minimum-image displacement d from
// the probe has (d_x² + d_y²) + d_z² < range² (each product and sum rounded, no fused
// multiply-add; d along a periodic axis as Domain::delta takes it); returns the new end. `out` must
// have room for every candidate of the runs and kPad more (a vector is stored whole past the last
// kept).
std::uint32_t* scan(const Cells& c, const Probe& p, const std::uint32_t* begin,
                    const std::uint32_t* end, int runs, std::uint32_t* out);

// The instruction set scan() runs on this CPU, e.g. "AVX3", "AVX2", "EMU128".
const char* target_name();

}  // namespace mdem::cell_scan
