#pragma once
// Named sets of elements (a rope's grips, a compression's platens), held with the elements as
// sets of element tags (Elements::tag), so they keep naming the same elements however the
// elements are later reordered. A scene or job declares its groups when it builds them; a
// protocol or observable reads a group's elements by name.
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace mdem {

class Groups {
 public:
  // Declares group `name` holding `tags` (stored sorted). Throws std::invalid_argument for an
  // empty name, a name already declared, no tags, or a tag listed twice.
  void add(std::string name, std::vector<std::uint64_t> tags);

  bool has(std::string_view name) const { return groups_.find(name) != groups_.end(); }
  // The sorted tags of group `name`. Throws std::invalid_argument naming the known groups when
  // there is none of that name.
  const std::vector<std::uint64_t>& get(std::string_view name) const;
  // Declared names, sorted.
  std::vector<std::string> names() const;
  std::size_t size() const { return groups_.size(); }

 private:
  std::map<std::string, std::vector<std::uint64_t>, std::less<>> groups_;
};

}  // namespace mdem
