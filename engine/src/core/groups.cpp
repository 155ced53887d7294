#include "mdem/core/groups.h"

#include <algorithm>
#include <stdexcept>

namespace mdem {

void Groups::add(std::string name, std::vector<std::uint64_t> tags) {
  if (name.empty()) throw std::invalid_argument("group name: must not be empty");
  if (has(name)) throw std::invalid_argument("group '" + name + "': already declared");
  if (tags.empty()) throw std::invalid_argument("group '" + name + "': must hold an element");
  std::sort(tags.begin(), tags.end());
  const auto dup = std::adjacent_find(tags.begin(), tags.end());
  if (dup != tags.end())
    throw std::invalid_argument("group '" + name + "': lists element tag " + std::to_string(*dup) +
                                " twice");
  groups_.emplace(std::move(name), std::move(tags));
}

const std::vector<std::uint64_t>& Groups::get(std::string_view name) const {
  const auto it = groups_.find(name);
  if (it != groups_.end()) return it->second;
  std::string known;
  for (const auto& [n, t] : groups_) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("no group '" + std::string(name) +
                              "'; known groups: " + (known.empty() ? "(none)" : known));
}

std::vector<std::string> Groups::names() const {
  std::vector<std::string> out;
  for (const auto& [n, t] : groups_) out.push_back(n);
  return out;
}

}  // namespace mdem
