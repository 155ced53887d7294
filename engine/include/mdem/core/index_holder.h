#pragma once
// What holds element indices across a reordering of the elements (Elements::reorder, done by a
// system whose IntegratorSettings::memory_order asks for it): force models and updaters.
#include <cstdint>
#include <span>

namespace mdem {

// A part of a system that may hold element indices between calls (a bond's two elements, a
// protocol's grip). When the system reorders its elements, tags staying with them, it calls
// reorder() with old_to_new[i], the new index of the element that was at i, and the part remaps
// what it holds. follows_reorder() says the part does so, or holds no indices at all; the default
// false makes the system refuse to reorder, naming the part, so a part written before reordering
// existed is never left holding stale indices.
class ElementIndexHolder {
 public:
  virtual ~ElementIndexHolder() = default;
  virtual bool follows_reorder() const { return false; }
  virtual void reorder(std::span<const std::uint32_t> /*old_to_new*/) {}
};

}  // namespace mdem
