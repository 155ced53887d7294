#pragma once
// A set of unordered pairs of element kinds (CntSegment, Nanoparticle, Grain, Wall): which pairs of
// kinds a pair model acts on, and which a neighbour sub-list holds.
#include <cstdint>
#include <string>

#include "mdem/core/elements.h"

namespace mdem {

inline constexpr int kElementKinds = 4;

class KindPairs {
 public:
  constexpr KindPairs() = default;
  // Every pair of kinds.
  static constexpr KindPairs all() {
    KindPairs k;
    k.bits_ = 0xFFFF;
    return k;
  }
  static constexpr KindPairs of(ElementKind a, ElementKind b) { return KindPairs().add(a, b); }

  constexpr KindPairs& add(ElementKind a, ElementKind b) {
    bits_ |= static_cast<std::uint16_t>(bit(a, b) | bit(b, a));
    return *this;
  }
  constexpr bool has(ElementKind a, ElementKind b) const { return (bits_ & bit(a, b)) != 0; }
  // Whether some pair of the set has kind a on one side.
  constexpr bool involves(ElementKind a) const {
    return (bits_ & (0xFu << (4 * static_cast<int>(a)))) != 0;
  }
  constexpr bool is_all() const { return bits_ == 0xFFFF; }
  constexpr bool empty() const { return bits_ == 0; }
  constexpr bool operator==(const KindPairs&) const = default;
  constexpr std::uint16_t bits() const { return bits_; }
  // "CntSegment-CntSegment, Nanoparticle-CntSegment", or "all kinds".
  std::string describe() const;

 private:
  static constexpr std::uint16_t bit(ElementKind a, ElementKind b) {
    return static_cast<std::uint16_t>(1u << (4 * static_cast<int>(a) + static_cast<int>(b)));
  }
  std::uint16_t bits_ = 0;
};

const char* kind_name(ElementKind k);

}  // namespace mdem
