// Grip reactions, film stress and its sampler (grip_stress.h).
#include "mdem/observe/grip_stress.h"

#include <cmath>
#include <stdexcept>

#include "mdem/core/units.h"
#include "mdem/io/state_io.h"

namespace mdem {
namespace {

double x_reaction(const System& sys, std::span<const std::size_t> ids) {
  const Elements& el = sys.elements();
  const std::vector<Vec3>& fd = sys.damping_forces();
  double f = 0;
  for (std::size_t i : ids) {
    if (i >= el.size()) throw std::out_of_range("grip_forces: element index out of range");
    f += el.f[i].x() + (i < fd.size() ? fd[i].x() : 0.0);
  }
  return f;
}

void require_positive(double v, const char* field, const char* unit) {
  if (!(std::isfinite(v) && v > 0))
    throw std::invalid_argument(std::string("grip stress ") + field + " must be finite and > 0 " +
                                unit + ", got " + std::to_string(v));
}

}  // namespace

GripForces grip_forces(const System& sys, std::span<const std::size_t> left,
                       std::span<const std::size_t> right) {
  return {x_reaction(sys, left), x_reaction(sys, right)};
}

double grip_stress_gpa(const GripForces& f, double width, double height) {
  require_positive(width, "width", "nm");
  require_positive(height, "height", "nm");
  return units::to_GPa((f.left - f.right) / (2.0 * width * height));
}

GripStressSampler::GripStressSampler(std::function<double(double)> strain, GripStressSettings s)
    : strain_(std::move(strain)), s_(std::move(s)) {
  if (!strain_) throw std::invalid_argument("grip stress sampler: no strain function");
  require_positive(s_.width, "width", "nm");
  require_positive(s_.height, "height", "nm");
  require_positive(s_.every, "every", "ps");
  if (s_.left_group.empty() || s_.right_group.empty())
    throw std::invalid_argument("grip stress sampler: the grip group names must not be empty");
}

void GripStressSampler::apply(System& sys, double t) {
  if (!have_prev_) {
    next_ = t;
  } else if (due()) {
    const Elements& el = sys.elements();
    const GripForces f =
        grip_forces(sys, el.group_indices(s_.left_group), el.group_indices(s_.right_group));
    samples_.push_back(
        {prev_t_, strain_(prev_t_), grip_stress_gpa(f, s_.width, s_.height), f.left, f.right});
    while (next_ <= prev_t_ + 1e-9 * s_.every) next_ += s_.every;
  }
  have_prev_ = true;
  prev_t_ = t;
}

bool GripStressSampler::due() const { return have_prev_ && prev_t_ >= next_ - 1e-9 * s_.every; }
bool GripStressSampler::reads_forces() const { return due(); }

std::vector<double> GripStressSampler::times() const {
  std::vector<double> v;
  for (const auto& s : samples_) v.push_back(s.t);
  return v;
}
std::vector<double> GripStressSampler::strains() const {
  std::vector<double> v;
  for (const auto& s : samples_) v.push_back(s.strain);
  return v;
}
std::vector<double> GripStressSampler::stresses() const {
  std::vector<double> v;
  for (const auto& s : samples_) v.push_back(s.stress);
  return v;
}

void GripStressSampler::save_state(StateWriter& w) const {
  w.begin("grip_stress");
  w.put(s_.width);
  w.put(s_.height);
  w.put(s_.every);
  w.put(have_prev_);
  w.put(prev_t_);
  w.put(next_);
  w.put(samples_);
}

void GripStressSampler::load_state(StateReader& r) {
  r.begin("grip_stress");
  const double width = r.get<double>("width"), height = r.get<double>("height"),
               every = r.get<double>("every");
  if (width != s_.width || height != s_.height || every != s_.every)
    r.fail("settings",
           "the checkpoint's grip stress settings (width, height, every) differ from this job's");
  have_prev_ = r.get_bool("have_prev");
  prev_t_ = r.get<double>("prev_t");
  next_ = r.get<double>("next");
  r.get(samples_, "samples");
}

}  // namespace mdem
