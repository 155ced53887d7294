#pragma once
// The two-tube alignment demo of thesis Fig. 5-7 (L754–756; tensile.md §3.7): two 50-segment
// (67.8 nm) (10,10) tubes whose middle segments lie side by side 1.71 nm apart, crossing at 30°,
// with 0, 1 or 2 Si nanoparticles in the acute wedges between their arms, left to relax
// hands-off with contact dashpots until the tubes zip into alignment. Thesis: aligned at about
// 0.75 ns without NP, about 1.5 ns with one, 2.3 ns with two.
//
// Geometry: tube A along (cos ½γ, sin ½γ, 0) through (0, 0, −s/2), tube B along
// (cos ½γ, −sin ½γ, 0) through (0, 0, +s/2), γ the crossing angle, s the spacing; segment
// `segments/2` of each sits on the z axis. The acute wedges open along ±x; an NP sits on the
// wedge's bisector in the plane z = 0, at the distance d from the origin where its distance to
// either tube's axis is the NP–tube rest distance h (3.462 nm, model.md §5):
// (d sin ½γ)² + (s/2)² = h². One NP: the +x wedge; two: both.
#include <optional>
#include <vector>

#include "mdem/core/elements.h"
#include "mdem/integrate/system.h"

namespace mdem {

struct TwoTubeAlignmentSpec {
  int segments = 50;                // per tube, in [2, 10000]
  double spacing = 1.71;            // s (nm): between the middle segments' axes, in (0, 10]
  double angle_deg = 30;            // γ, in (0, 90]
  int nanoparticles = 0;            // 0, 1 or 2
  double np_rest_distance = 3.462;  // h (nm): NP centre to tube axis, in (s/2, 20]
  // Throws std::invalid_argument naming the field and its allowed range.
  void validate() const;
};

// Appends the scene to `el` (tubes as chains 0 and 1 with their bonds, then the NPs).
void add_two_tube_alignment(Elements& el, const TwoTubeAlignmentSpec& spec);
// Where the NPs go: d of the header's rule (nm).
double two_tube_np_offset(const TwoTubeAlignmentSpec& spec);

struct AlignmentSettings {
  double max_ps = 3000;         // the run ends at this time or at alignment (> 0)
  double sample_every_ps = 10;  // aligned pairs counted this often (> 0)
  double dashpot_ratio = 0.03;  // ψ of the contact dashpots, in [0, 1]
  bool dashpot_shear = false;   // the CNT dashpot damps shear too (ContactDampingParams::shear)
  int target = 45;              // registry-free count that counts as aligned (90 % of 50), >= 1
};

struct AlignmentRun {
  std::optional<double> t_align;  // ps: first sample at which registry_free >= target
  std::vector<double> t;          // sample times (ps)
  std::vector<long> thesis, registry_free;
  long steps = 0;
  double dt = 0;
};

// Relaxes the scene hands-off (tensile_film_system's force loop: bonds, CNT–CNT, NP–CNT and
// NP–NP contacts, their dashpots) from rest and reports t_align, the first sampled time at which
// the registry-free aligned-pair count reaches settings.target. Throws std::invalid_argument for
// a bad spec or settings, NumericalError if the run goes unstable.
AlignmentRun run_two_tube_alignment(const TwoTubeAlignmentSpec& spec,
                                    const AlignmentSettings& settings = {},
                                    IntegratorSettings integrator = {});

}  // namespace mdem
