#pragma once
// Fragments of a film at large strain (tensile.md §3.5): the connected components of the graph on
// the elements whose edges the caller gives (its bonds plus the vdW and NP pairs with U < 0),
// found by union–find. Components of fewer than min_fraction of the elements are not counted.
// Definitions and tests: docs/tensile.md.
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

namespace mdem {

using Edge = std::pair<std::uint32_t, std::uint32_t>;

struct Fragments {
  std::size_t count = 0;             // components of ≥ min_fraction·n elements
  std::vector<std::size_t> sizes;    // their sizes, largest first
  std::size_t ignored = 0;           // smaller components left out
  std::size_t ignored_elements = 0;  // elements in them
};

// Throws std::invalid_argument for an edge naming an element ≥ n, or min_fraction outside [0, 1].
Fragments count_fragments(std::size_t n, std::span<const Edge> edges, double min_fraction = 0.01);

class System;

// The edges of a film's fragment graph (tensile.md §3.5): its parallel bonds, and the pairs of its
// CNT–CNT vdW, NP–CNT and NP–NP contacts whose energy is below zero (attracting; a pair within
// the cutoff on the repulsive branch, U ≥ 0, is no link) in the system's last neighbour lists.
// The system must be initialized.
std::vector<Edge> film_fragment_edges(const System& sys);
// count_fragments over film_fragment_edges.
Fragments count_film_fragments(const System& sys, double min_fraction = 0.01);

}  // namespace mdem
