// The two-tube alignment demo (two_tube_alignment.h, tensile.md §3.7, thesis Fig. 5-7).
#include "mdem/scene/two_tube_alignment.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "mdem/core/cnt.h"
#include "mdem/job/tensile_job.h"
#include "mdem/observe/aligned_pairs.h"
#include "mdem/scene/nanoparticle.h"
#include "mdem/scene/tube_builder.h"

namespace mdem {
namespace {

[[noreturn]] void refuse(const std::string& what, const std::string& range, double got) {
  throw std::invalid_argument("two-tube alignment " + what + " must be " + range + ", got " +
                              std::to_string(got));
}

double half_angle(const TwoTubeAlignmentSpec& s) {
  return 0.5 * s.angle_deg * std::numbers::pi / 180.0;
}

}  // namespace

void TwoTubeAlignmentSpec::validate() const {
  if (segments < 2 || segments > 10000) refuse("segments", "in [2, 10000]", segments);
  if (!(std::isfinite(spacing) && spacing > 0 && spacing <= 10))
    refuse("spacing", "finite and in (0, 10] nm", spacing);
  if (!(std::isfinite(angle_deg) && angle_deg > 0 && angle_deg <= 90))
    refuse("angle_deg", "finite and in (0, 90]", angle_deg);
  if (nanoparticles < 0 || nanoparticles > 2) refuse("nanoparticles", "0, 1 or 2", nanoparticles);
  if (!(std::isfinite(np_rest_distance) && np_rest_distance > 0.5 * spacing &&
        np_rest_distance <= 20))
    refuse("np_rest_distance", "finite and in (spacing/2, 20] nm", np_rest_distance);
}

double two_tube_np_offset(const TwoTubeAlignmentSpec& s) {
  s.validate();
  const double h = s.np_rest_distance, z = 0.5 * s.spacing;
  return std::sqrt(h * h - z * z) / std::sin(half_angle(s));
}

void add_two_tube_alignment(Elements& el, const TwoTubeAlignmentSpec& s) {
  s.validate();
  const double a = half_angle(s), T = cnt::kSegmentLength;
  const int mid = s.segments / 2;
  const Vec3 dir_a(std::cos(a), std::sin(a), 0), dir_b(std::cos(a), -std::sin(a), 0);
  const Vec3 ca(0, 0, -0.5 * s.spacing), cb(0, 0, 0.5 * s.spacing);
  const int tube0 = static_cast<int>(el.topology.chains().size());
  add_straight_tube(el, ca - mid * T * dir_a, dir_a, s.segments, tube0);
  add_straight_tube(el, cb - mid * T * dir_b, dir_b, s.segments, tube0 + 1);
  if (s.nanoparticles == 0) return;
  const double d = two_tube_np_offset(s);
  el.add(nanoparticle(Vec3(d, 0, 0)));
  if (s.nanoparticles == 2) el.add(nanoparticle(Vec3(-d, 0, 0)));
}

AlignmentRun run_two_tube_alignment(const TwoTubeAlignmentSpec& spec, const AlignmentSettings& st,
                                    IntegratorSettings integrator) {
  spec.validate();
  if (!(std::isfinite(st.max_ps) && st.max_ps > 0)) refuse("max_ps", "finite and > 0", st.max_ps);
  if (!(std::isfinite(st.sample_every_ps) && st.sample_every_ps > 0 &&
        st.sample_every_ps <= st.max_ps))
    refuse("sample_every_ps", "finite and in (0, max_ps]", st.sample_every_ps);
  if (!(std::isfinite(st.dashpot_ratio) && st.dashpot_ratio >= 0 && st.dashpot_ratio <= 1))
    refuse("dashpot_ratio", "in [0, 1]", st.dashpot_ratio);
  if (st.target < 1) refuse("target", ">= 1", st.target);

  Elements el;
  add_two_tube_alignment(el, spec);
  FilmLaws laws;
  laws.dashpot_shear = st.dashpot_shear;
  auto sys = tensile_film_system(std::move(el), integrator, st.dashpot_ratio, nullptr, laws);
  sys->initialize();
  AlignmentRun r;
  r.dt = sys->dt();
  const long every = std::max(1L, std::lround(st.sample_every_ps / r.dt));
  auto sample = [&] {
    const AlignedPairCounts c = count_aligned_pairs(sys->elements());
    r.t.push_back(sys->time());
    r.thesis.push_back(c.thesis);
    r.registry_free.push_back(c.registry_free);
    if (!r.t_align && c.registry_free >= st.target) r.t_align = sys->time();
  };
  sample();
  while (!r.t_align && sys->time() < st.max_ps - 0.5 * r.dt) {
    sys->run(every);
    sample();
  }
  r.steps = sys->steps();
  return r;
}

}  // namespace mdem
