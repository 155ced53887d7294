#pragma once
// The tensile job's film (tensile.md §3.1–3.2, thesis Table 5-1): straight (10,10) tubes grown
// in an L × L × H slab with at most 2° tilt, contained in the slab, wrapped in x and y during
// generation and cut where they wrap (each piece keeps its generated tube as parent), optionally
// filled with Si nanoparticles on their own random stream.
#include <cstdint>
#include <string_view>

#include "mdem/core/elements.h"
#include "mdem/scene/film_builder.h"
#include "mdem/scene/np_placement.h"

namespace mdem {

// Table 5-1's sizes.
enum class FilmSize { Small, Medium, Large };
// "small", "medium" or "large"; anything else throws std::invalid_argument naming the three.
FilmSize film_size_from_name(std::string_view name);
std::string_view film_size_name(FilmSize s);

struct TensileFilmSpec {
  double side = 300;                // L = W (nm), in (0, 10000]
  double thickness = 11;            // H (nm), in (0, 1000]
  int tubes = 200;                  // generated tubes, in [1, 100000]
  int segments_per_tube = 200;      // in [1, 100000]; tubes × segments ≤ 10^7
  double max_out_of_plane_deg = 2;  // in [0, 90]
  bool contain = true;              // every segment centre inside the slab (§3.1)
  int nanoparticles = 0;            // in [0, 10^7]
  std::uint64_t seed = 0;           // tubes: mt19937_64(seed); NPs: np_stream(seed)

  // Table 5-1: small 300 nm, 200 tubes of 200 segments; medium 500 nm, 350 of 350; large
  // 1000 nm, 500 of 700; all 11 nm thick, 2°, contained, no NPs.
  static TensileFilmSpec of_size(FilmSize s);
  // Throws std::invalid_argument naming the field and its allowed range.
  void validate() const;
  // The tubes' generator settings (FilmSpec with periodic_split on).
  FilmSpec tubes_spec() const;
};

struct TensileFilm {
  TubeIndices pieces;  // element indices of each tube piece, in order of generation
  NpPlacement nps;     // the NPs added (none when spec.nanoparticles = 0)
};

// Appends the film to `el` (validate() first): the tubes by add_random_film(el, tubes_spec()),
// then spec.nanoparticles NPs by place_nanoparticles on the film's NP stream, so the tubes of a
// seed do not depend on the NP count. The same spec gives the same elements and topology bit for
// bit. Throws std::invalid_argument, leaving `el` unchanged, for a bad spec or NPs that do not fit.
TensileFilm add_tensile_film(Elements& el, const TensileFilmSpec& spec);

}  // namespace mdem
