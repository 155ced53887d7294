#include "mdem/scene/tensile_film.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace mdem {

namespace {

[[noreturn]] void refuse(const std::string& field, const std::string& allowed, double got) {
  std::ostringstream m;
  m << "tensile film: " << field << " must be " << allowed << ", got " << got;
  throw std::invalid_argument(m.str());
}

void check_range(const char* field, double v, double lo, double hi, bool lo_open,
                 const char* unit) {
  const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && v <= hi;
  if (!ok) {
    std::ostringstream a;
    a << "finite and in " << (lo_open ? "(" : "[") << lo << ", " << hi << "]" << unit;
    refuse(field, a.str(), v);
  }
}

}  // namespace

FilmSize film_size_from_name(std::string_view name) {
  if (name == "small") return FilmSize::Small;
  if (name == "medium") return FilmSize::Medium;
  if (name == "large") return FilmSize::Large;
  throw std::invalid_argument("tensile film: size must be one of small, medium, large; got \"" +
                              std::string(name) + "\"");
}

std::string_view film_size_name(FilmSize s) {
  switch (s) {
    case FilmSize::Small:
      return "small";
    case FilmSize::Medium:
      return "medium";
    case FilmSize::Large:
      return "large";
  }
  return "unknown";
}

TensileFilmSpec TensileFilmSpec::of_size(FilmSize s) {
  TensileFilmSpec f;
  switch (s) {
    case FilmSize::Small:
      f.side = 300, f.tubes = 200, f.segments_per_tube = 200;
      break;
    case FilmSize::Medium:
      f.side = 500, f.tubes = 350, f.segments_per_tube = 350;
      break;
    case FilmSize::Large:
      f.side = 1000, f.tubes = 500, f.segments_per_tube = 700;
      break;
  }
  return f;
}

void TensileFilmSpec::validate() const {
  check_range("side", side, 0, 10000, true, " nm");
  check_range("thickness", thickness, 0, 1000, true, " nm");
  check_range("tubes", tubes, 1, 100000, false, "");
  check_range("segments_per_tube", segments_per_tube, 1, 100000, false, "");
  if (static_cast<double>(tubes) * segments_per_tube > 1e7)
    refuse("tubes x segments_per_tube", "at most 10000000", 1.0 * tubes * segments_per_tube);
  check_range("max_out_of_plane_deg", max_out_of_plane_deg, 0, 90, false, " deg");
  check_range("nanoparticles", nanoparticles, 0, 1e7, false, "");
}

FilmSpec TensileFilmSpec::tubes_spec() const {
  FilmSpec f;
  f.side = side;
  f.thickness = thickness;
  f.tubes = tubes;
  f.segments_per_tube = segments_per_tube;
  f.max_out_of_plane_deg = max_out_of_plane_deg;
  f.seed = seed;
  f.contain = contain;
  f.periodic_split = true;
  return f;
}

TensileFilm add_tensile_film(Elements& el, const TensileFilmSpec& spec) {
  spec.validate();
  // Built on a copy, so a film refused half-way (NPs that do not fit) leaves `el` as it was.
  Elements work = el;
  TensileFilm film;
  film.pieces = add_random_film(work, spec.tubes_spec());
  NpPlacementSpec np;
  np.count = spec.nanoparticles;
  np.side = spec.side;
  np.thickness = spec.thickness;
  np.seed = spec.seed;
  film.nps = place_nanoparticles(work, np);
  el = std::move(work);
  return film;
}

}  // namespace mdem
