#pragma once
// Scenes the step tests share (fast path, force sums, r-RESPA): a film large enough to run the
// threaded loops, and a thermal kick of random velocities and spins.
#include <random>

#include "mdem/core/elements.h"
#include "mdem/scene/film_builder.h"

namespace mdem::testing {

// A 2400-segment film (24 tubes of 100 segments in 60 × 60 × 6 nm, seed 5): above the threading
// threshold of 2048 items, with bonds and vdW pairs.
inline void add_step_film(Elements& el) {
  FilmSpec f;
  f.side = 60;
  f.thickness = 6;
  f.tubes = 24;
  f.segments_per_tube = 100;
  f.seed = 5;
  add_random_film(el, f);
}

// Random velocities and spins, 0.03 nm/ps and rad/ps per component (~300 K for a segment), from
// the stream SEED.
inline void thermal_kick(Elements& el, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 0.03);  // nm/ps, rad/ps
  for (std::size_t i = 0; i < el.size(); ++i) {
    el.v[i] = Vec3(g(rng), g(rng), g(rng));
    el.w[i] = Vec3(g(rng), g(rng), g(rng));
  }
}

}  // namespace mdem::testing
