#pragma once
// Nanoparticles placed into a generated film (tensile.md §3.2): candidates drawn on the film's own
// NP stream, accepted only where they overlap nothing and sit in a non-repulsive place.
#include <cstddef>
#include <cstdint>
#include <random>
#include <vector>

#include "mdem/core/elements.h"
#include "mdem/force/contact/np_cnt_contact.h"

namespace mdem {

struct NpPlacementSpec {
  int count = 0;           // NPs to place, >= 0
  double side = 0;         // candidates' x, y uniform in [−side/2, side/2) (nm)
  double thickness = 11;   // candidates' z uniform in [−thickness/2, thickness/2] (nm)
  std::uint64_t seed = 0;  // the film's seed; the NPs use np_stream(seed)
  NpCntParams contact;     // the NP–CNT law of acceptance test (c)
};

struct NpPlacement {
  std::vector<std::size_t> indices;  // the NPs added, in order of acceptance
  long candidates = 0;               // candidates drawn
};

// The NP stream of a film seeded `seed`: std::mt19937_64 seeded from (seed, "np") through
// std::seed_seq (whose mixing the standard fixes), independent of the tubes' stream, so a pristine
// and a hybrid film of one seed share every tube.
std::mt19937_64 np_stream(std::uint64_t seed);

// The smallest NP–NP centre distance placement accepts: the NP–NP law's minimum, 2 r_NP + 0.4287
// = 5.4287 nm (acceptance test (a)).
double np_min_spacing();
// The smallest distance from an NP centre to a segment's axis line segment [c − (T/2)b, c + (T/2)b]
// placement accepts: r_NP + r_CNT = 3.178 nm (test (b)).
double np_min_axis_distance();
// Distance from p to the axis line segment of a CNT segment centred at c with unit axis b.
double distance_to_segment_axis(const Vec3& p, const Vec3& c, const Vec3& b);

// Adds spec.count NPs (scene/nanoparticle.h) to `el`. Candidates: x, y, z drawn in that order on
// np_stream(spec.seed); one is accepted when (a) no NP (placed before, or already in `el`) has its
// centre closer than np_min_spacing(), (b) no CNT segment's axis line segment is closer than
// np_min_axis_distance(), and (c) its total NP–CNT energy over the segments (NpCntKernel) is
// <= 0. Neighbours are found on a cell grid, so a candidate costs O(1). Deterministic.
// Throws std::invalid_argument, adding nothing, for a count outside [0, 10^7], a side or thickness
// not finite and > 0; when the count exceeds what can fit at all (centres np_min_spacing() apart
// in the slab widened by that spacing: at most √2·V/s³ of them); and when spec.count are not
// placed within 1000·count candidates (the message names how many were placed).
NpPlacement place_nanoparticles(Elements& el, const NpPlacementSpec& spec);

}  // namespace mdem
