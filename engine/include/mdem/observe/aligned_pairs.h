#pragma once
// Aligned CNT segment pairs (tensile.md §3.4, thesis L738) in two forms, and the stabilisation
// time of a count series. A pair is two CNT segments of different tubes, or of one tube at least
// `exclusion` indices apart (Elements::cnt_pair_excluded), counted once, from the side of the
// lower element index i (segment 1) with j (segment 2); γ is the acute angle between their axes
// b_i, b_j and R = x_j − x_i (the domain's minimum image).
//   thesis count:        γ < max_angle and |R| < max_distance;
//   registry-free count: γ < max_angle, |R − (R·b_i) b_i| < max_distance and |R·b_i| ≤ half_length.
// Pairs are found with the engine's neighbour list (cell list), not by trying every pair: a list of
// its own, or one the caller keeps (the overload taking a NeighborList).
// Definitions and tests: docs/tensile.md.
#include <optional>
#include <span>

#include "mdem/core/cnt.h"
#include "mdem/core/domain.h"
#include "mdem/core/elements.h"
#include "mdem/neighbor/neighbor_list.h"

namespace mdem {

struct AlignedPairCriteria {
  double max_angle_deg = 10.0;                     // γ <
  double max_distance = 1.8;                       // nm
  double half_length = 0.5 * cnt::kSegmentLength;  // T/2 (nm), the registry-free axial reach
  int exclusion = 20;                              // intra-tube index exclusion
};

struct AlignedPairCounts {
  long thesis = 0;
  long registry_free = 0;
};

// Throws std::invalid_argument for criteria that are not finite and positive (angle in (0, 90]).
AlignedPairCounts count_aligned_pairs(const Elements& el, const AlignedPairCriteria& c = {},
                                      const Domain& domain = kOpenDomain);

// The same counts over the candidate pairs of a neighbour list the caller already keeps (the
// system's CNT–CNT vdW list, say), in the list's domain, without building one: a Verlet list that
// is current for el (needs_rebuild false) with a cutoff ≥ √(d² + (T/2)²) over CNT–CNT pairs holds
// every pair either count can take. The list's own exclusion must not leave out pairs that
// c.exclusion keeps (the criteria's exclusion is applied here again). std::nullopt when the list
// cannot serve (stale, too short a cutoff, no CNT–CNT pairs, built for other elements): then
// count with the overload above. Throws std::invalid_argument as that one does.
std::optional<AlignedPairCounts> count_aligned_pairs(const Elements& el,
                                                     const NeighborList& candidates,
                                                     const AlignedPairCriteria& c = {});

// The stabilisation time of a count N(t) sampled at increasing times: the earliest t_k with
// N_end − N(t_k) ≤ fraction·(N_end − N_0), N_0 and N_end the first and last samples (a falling
// count is mirrored: N(t_k) − N_end ≤ fraction·(N_0 − N_end)). Throws
// std::invalid_argument for empty, unequal or non-finite series, times that do not increase, or
// a fraction outside [0, 1].
double stabilisation_time(std::span<const double> t, std::span<const double> count,
                          double fraction = 0.05);

}  // namespace mdem
