#include "mdem/core/elements.h"

#include <stdexcept>
#include <string>

namespace mdem {

namespace {
void require(bool ok, const char* field, const char* allowed) {
  if (!ok) throw std::invalid_argument(std::string("element ") + field + ": " + allowed);
}
}  // namespace

std::size_t Elements::add(const ElementInit& e) {
  require(e.x.allFinite(), "position", "must be finite");
  require(e.v.allFinite(), "velocity", "must be finite");
  require(e.w.allFinite(), "angular velocity", "must be finite");
  require(e.q.coeffs().allFinite() && e.q.norm() > 1e-12, "orientation",
          "must be a finite, non-zero quaternion");
  require(std::isfinite(e.mass) && e.mass > 0, "mass", "must be finite and > 0");
  require(e.inertia.allFinite() && (e.inertia.array() > 0).all(), "inertia",
          "must be finite and > 0 about every principal axis");
  require(std::isfinite(e.radius) && e.radius > 0, "radius", "must be finite and > 0");

  tag.push_back(next_tag++);
  x.push_back(e.x);
  q.push_back(e.q.normalized());
  v.push_back(e.v);
  w.push_back(e.w);
  mass.push_back(e.mass);
  inv_mass.push_back(1.0 / e.mass);
  inertia.push_back(e.inertia);
  radius.push_back(e.radius);
  kind.push_back(e.kind);
  tube.push_back(e.tube);
  index.push_back(e.index);
  std::array<DofMode, 6> free;
  free.fill(DofMode::Free);
  dof.push_back(free);
  v_prescribed.push_back(Vec3::Zero());
  w_prescribed.push_back(Vec3::Zero());
  f_ext.push_back(Vec3::Zero());
  t_ext.push_back(Vec3::Zero());
  f.push_back(Vec3::Zero());
  t.push_back(Vec3::Zero());
  return x.size() - 1;
}

std::size_t Elements::index_of(std::uint64_t t) const {
  // Elements not reordered since they were built sit at their tag; otherwise search.
  if (t < tag.size() && tag[t] == t) return static_cast<std::size_t>(t);
  for (std::size_t i = 0; i < tag.size(); ++i)
    if (tag[i] == t) return i;
  throw std::out_of_range("no element has tag " + std::to_string(t) + " (" +
                          std::to_string(tag.size()) + " elements)");
}

std::vector<std::size_t> Elements::group_indices(std::string_view name) const {
  const std::vector<std::uint64_t>& tags = groups.get(name);
  std::vector<std::size_t> out;
  out.reserve(tags.size());
  for (std::uint64_t t : tags) out.push_back(index_of(t));
  return out;
}

}  // namespace mdem
