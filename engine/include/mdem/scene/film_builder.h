#pragma once
// Scene generators for CNT networks: a seeded random, nearly in-plane film (scenes.md, tensile;
// thesis Ch. 5, Table 5-1) and a seven-tube hexagonal bundle (a 1 + 6 rope along x).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mdem/core/elements.h"

namespace mdem {

// A square film in the xy plane, centred on the origin: x, y in [−side/2, side/2], z in
// [−thickness/2, thickness/2] (tube centres; a tilted tube's ends may leave the slab by up to
// ½·length·sin(max_out_of_plane_deg)).
struct FilmSpec {
  double side = 0;            // nm
  double thickness = 11;      // nm
  int tubes = 0;              // number of tubes grown
  int segments_per_tube = 0;  // segments of each tube (length = n·T)
  double max_out_of_plane_deg = 2;
  std::uint64_t seed = 0;
  // tensile.md §3.1 (both off: the film described below, unchanged).
  // contain: every segment centre inside the slab, |z| ≤ thickness/2. With contain or
  // periodic_split the draws of a tube follow §3.1's order: centre x, y, the azimuth φ, then the
  // axis's z component s uniform in [−sin a, sin a], redrawn while h = ½(n−1)T|s| > thickness/2,
  // then centre z uniform in [−(thickness/2 − h), thickness/2 − h] (uncontained: s drawn once, z in
  // the whole slab).
  bool contain = false;
  // periodic_split: the segment centres, c_j = centre + (j − (n−1)/2)·T·b, are wrapped in x and
  // y into [−side/2, side/2), and a tube is cut wherever a coordinate wrapped between consecutive
  // segments, so no bond crosses the box. Each piece is a tube of its own (new id, indices from
  // 0, its own open chain and bonds) whose Chain::parent is the generated tube's id. Generated
  // tube k gets id base + k (base = one past the largest tube id already in `el`), an id no
  // chain takes; its pieces get ids base + tubes, base + tubes + 1, ... in order of generation.
  bool periodic_split = false;
};

// Element indices of each tube added, in tube order (segment order within a tube).
using TubeIndices = std::vector<std::vector<std::size_t>>;

// Grows spec.tubes straight tubes of spec.segments_per_tube segments: each tube's centre (the
// midpoint of its axis) uniform in the square, its z uniform in [−thickness/2, thickness/2], its
// direction uniform over the band of directions at most max_out_of_plane_deg out of the xy plane
// (azimuth uniform in [0, 2π), axis z-component uniform in [−sin a, sin a]). Tubes are added with
// add_straight_tube (tube ids continue after the largest id already in `el`), which records each
// tube and its intra-tube bonds in el.topology. Deterministic: std::mt19937_64 seeded with
// spec.seed and a fixed mapping of its output to [0, 1), so the same seed gives the same film on
// every standard library. Tubes may cross or overlap (a pre-relaxation under the finite-overlap vdW
// law removes that). Throws std::invalid_argument for a non-positive side, tube or segment count, a
// negative thickness or an angle outside [0°, 90°], and, with contain, when a tube fits the slab
// with a chance below 1e-3 per draw (a tube too long for the thickness at any allowed tilt).
// Returns one entry per tube added: per piece with periodic_split.
TubeIndices add_random_film(Elements& el, const FilmSpec& spec);

// A seven-tube rope along x: a centre tube on the x axis and six around it on a triangular
// lattice, centre-to-centre `spacing` nm apart, at angles 0°, 60°, …, 300° about x starting from
// +y (tube k ≥ 1 at y = spacing·cos((k−1)·60°), z = spacing·sin((k−1)·60°)). Each tube has
// `segments` segments, the first centred at x = −(segments − 1)·T/2 so the rope is centred on the
// origin; the centre tube is added first. Tube ids continue after the largest id already in
// `el`; tubes and bonds are recorded in el.topology. (A single tube is add_straight_tube.) Throws
// std::invalid_argument unless segments ≥ 1 and spacing > 0.
TubeIndices add_seven_tube_bundle(Elements& el, int segments, double spacing);

// The generator's mapping of a 64-bit random word to [0, 1): the top 53 bits times 2^-53.
inline double unit_interval(std::uint64_t word) {
  return static_cast<double>(word >> 11) * 0x1.0p-53;
}

}  // namespace mdem
