#pragma once
// Memory order of the elements: a space-filling curve over the cell grid of the neighbour search,
// so that elements near in space are near in memory (issue 13 item 3). The pair loops then find
// a pair's second element, and the integrator its neighbours' data, in cache lines they have
// just used; the bonds of a tube, whose segments are neighbours along it, likewise.
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

}  // namespace mdem
