#pragma once
// Memory order of the elements (issue 13 items 3 and 4): a space-filling curve over the cell grid
// of the neighbour search, so that elements near in space are near in memory (the pair loops then
// find a pair's second element in cache lines they have just used), or slabs of space, one per
// thread, so that each thread's contiguous share of the elements is one region of space and the
// threads share little data.
#include <cstdint>
#include <string_view>
#include <vector>

#include "mdem/core/domain.h"
#include "mdem/core/elements.h"

namespace mdem {

// How a system orders its elements in memory (IntegratorSettings::memory_order).
enum class MemoryOrder : std::uint8_t {
  AsBuilt = 0,  // the order the scene added them in (tag order), never changed
  Morton = 1,   // along a Morton (Z-order) curve over cells, redone at neighbour-list rebuilds
  Slabs = 2,    // one slab of space per thread (slab_order), redone at neighbour-list rebuilds
};

std::string_view to_string(MemoryOrder m);

// The Morton order of el's elements over a grid of cubic cells `cell` nm wide spanning their
// bounding box (the box itself along domain's periodic axes, positions wrapped into it): the
// reordering (new_to_old, for Elements::reorder) that sorts the elements by the Morton key of
// their cell, the elements of one cell in tag order (a tube's segments in a run, as generated):
// the result depends on positions and tags only, not on the current order or on threads. Throws
// std::invalid_argument for a cell that is not finite and > 0, and std::runtime_error naming the
// element for a non-finite position.
std::vector<std::uint32_t> morton_order(const Elements& el, double cell, const Domain& domain = {});

// The slab order of el's elements: `slabs` slabs across the widest axis (a periodic axis's box
// length, else the extent of the positions; positions wrapped into the box along periodic axes),
// cut at the positions' quantiles so that the slabs hold equal numbers of elements (to within
// elements at a cut's very position), in order along the axis, the elements of one slab in tag
// order (a tube's segments stay in runs, cut only where the tube crosses a slab's face). One slab
// is the tag order. With one slab per thread, a thread's contiguous share of the elements (the
// integrator's even split, the pair lists' rows cut by their cost, the bonds sorted by their
// elements) is one slab: it reads and writes the data of its own region, and only pairs and bonds
// across a slab's faces reach another thread's. Depends on positions, tags and `slabs` only.
// Throws std::invalid_argument for slabs < 1 or > 2^16, and std::runtime_error naming the element
// for a non-finite position.
std::vector<std::uint32_t> slab_order(const Elements& el, int slabs, const Domain& domain = {});

}  // namespace mdem
