#include "mdem/core/elements.h"

#include <algorithm>
#include <limits>
#include <numeric>
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

  if (x.size() >= std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("elements: more than 2^32 - 1 elements");
  if (next_tag >= std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("elements: tags beyond 2^32 - 1");
  if (index_of_tag_.size() < next_tag)
    index_of_tag_.resize(next_tag, std::numeric_limits<std::uint32_t>::max());
  index_of_tag_.push_back(static_cast<std::uint32_t>(x.size()));
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
  if (t < index_of_tag_.size()) {
    const std::size_t i = index_of_tag_[t];
    if (i < tag.size() && tag[i] == t) return i;
  }
  // The map is stale only after a hand edit of `tag`: search the arrays themselves.
  for (std::size_t i = 0; i < tag.size(); ++i)
    if (tag[i] == t) return i;
  throw std::out_of_range("no element has tag " + std::to_string(t) + " (" +
                          std::to_string(tag.size()) + " elements)");
}

bool is_permutation_of(std::span<const std::uint32_t> new_to_old, std::size_t n) {
  if (new_to_old.size() != n) return false;
  std::vector<char> seen(n, 0);
  for (std::uint32_t i : new_to_old) {
    if (i >= n || seen[i]) return false;
    seen[i] = 1;
  }
  return true;
}

bool is_identity_order(std::span<const std::uint32_t> new_to_old) {
  for (std::size_t k = 0; k < new_to_old.size(); ++k)
    if (new_to_old[k] != k) return false;
  return true;
}

std::vector<std::uint32_t> invert_permutation(std::span<const std::uint32_t> new_to_old) {
  std::vector<std::uint32_t> old_to_new(new_to_old.size());
  for (std::size_t k = 0; k < new_to_old.size(); ++k)
    old_to_new[new_to_old[k]] = static_cast<std::uint32_t>(k);
  return old_to_new;
}

void Elements::reorder(std::span<const std::uint32_t> new_to_old) {
  if (!is_permutation_of(new_to_old, size()))
    throw std::invalid_argument("elements: a reordering must list each of the " +
                                std::to_string(size()) + " element indices exactly once");
  permute(tag, new_to_old);
  permute(x, new_to_old);
  permute(q, new_to_old);
  permute(v, new_to_old);
  permute(w, new_to_old);
  permute(mass, new_to_old);
  permute(inv_mass, new_to_old);
  permute(inertia, new_to_old);
  permute(radius, new_to_old);
  permute(kind, new_to_old);
  permute(tube, new_to_old);
  permute(index, new_to_old);
  permute(dof, new_to_old);
  permute(v_prescribed, new_to_old);
  permute(w_prescribed, new_to_old);
  permute(f_ext, new_to_old);
  permute(t_ext, new_to_old);
  permute(f, new_to_old);
  permute(t, new_to_old);
  for (std::size_t k = 0; k < tag.size(); ++k)
    if (tag[k] < index_of_tag_.size()) index_of_tag_[tag[k]] = static_cast<std::uint32_t>(k);
}

std::vector<std::uint32_t> Elements::tag_order() const {
  // Tags are 0 .. next_tag-1 without gaps (add() gives them): O(n) through the map.
  if (next_tag == size()) {
    std::vector<std::uint32_t> order(size());
    bool mapped = true;
    for (std::uint64_t t = 0; t < next_tag && mapped; ++t) {
      order[t] = t < index_of_tag_.size() ? index_of_tag_[t] : 0;
      mapped = order[t] < size() && tag[order[t]] == t;
    }
    if (mapped) return order;
  }
  std::vector<std::uint32_t> order(size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(),
                   [this](std::uint32_t a, std::uint32_t b) { return tag[a] < tag[b]; });
  return order;
}

std::vector<std::size_t> Elements::group_indices(std::string_view name) const {
  const std::vector<std::uint64_t>& tags = groups.get(name);
  std::vector<std::size_t> out;
  out.reserve(tags.size());
  for (std::uint64_t t : tags) out.push_back(index_of(t));
  return out;
}

}  // namespace mdem
