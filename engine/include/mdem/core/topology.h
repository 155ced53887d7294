#pragma once
// Bond topology held with the elements (Elements::topology): which elements are bonded, by which
// kind of bond, and which elements make up each CNT tube, in order, open or closed. Elements are
// named by tag (Elements::tag), so the topology keeps naming the same elements however the arrays
// are reordered. A scene builder records its bonds and tubes here and needs no force-model type;
// the bond model is made from the topology afterwards (ParallelBond::from_topology), in the
// elements' configuration of that moment, which becomes the bonds' rest state.
//
// A tube's chain may be closed (a ring): its seam is the bond between its last and first segment,
// and the intra-tube exclusion (Elements::cnt_pair_excluded) counts index distance around the
// ring across the seam.
#include <cstdint>
#include <functional>
#include <string_view>
#include <unordered_set>
#include <utility>
#include <vector>

namespace mdem {

struct Elements;

// Kinds of bond the topology records. Only the CNT intra-tube bond goes through the topology
// today; grain bonds are formed by the compression job after packing, from the touching pairs of
// the packed particle (GrainBond), and stay outside it.
enum class BondType : std::uint8_t { Cnt = 0 };
inline constexpr int kBondTypeCount = 1;
std::string_view bond_type_name(BondType t);

struct TopologyBond {
  std::uint64_t a = 0, b = 0;  // element tags; a bond model is made from a to b
  BondType type = BondType::Cnt;
  friend bool operator==(const TopologyBond&, const TopologyBond&) = default;
};

// One CNT tube: its segments' tags in index order (consecutive indices, the first one's as built:
// a rope tube cut by a defect starts past 0).
struct Chain {
  std::int32_t tube = -1;  // Elements::tube, >= 0
  std::vector<std::uint64_t> tags;
  bool closed = false;       // a ring: the seam is the bond tags.back() -> tags.front()
  std::int32_t parent = -1;  // the tube this one was split from (a tube a film generator cut
                             // where it wrapped keeps its parent's id here); -1 when none
  friend bool operator==(const Chain&, const Chain&) = default;
};

class Topology {
 public:
  // Records a bond from element `a` to element `b` (tags). Throws std::invalid_argument, leaving
  // the topology unchanged, for an unknown tag, a == b, a pair bonded already (in either order),
  // or a CNT bond whose ends are not both CNT segments.
  void add_bond(const Elements& el, std::uint64_t a, std::uint64_t b, BondType type);
  // Declares a tube's chain. Throws std::invalid_argument, leaving the topology unchanged, for a
  // negative tube id or one declared already, no tags, an unknown tag, a position k that does not
  // hold the CNT segment of that tube with index (first index + k), a ring of fewer than 3
  // segments, or a parent that is neither -1 nor another tube's id.
  void add_chain(const Elements& el, Chain chain);
  // add_chain, and the chain's bonds of `type` from each segment to the next (and the seam,
  // last -> first, for a ring), all checked before any is recorded.
  void add_bonded_chain(const Elements& el, Chain chain, BondType type);

  const std::vector<TopologyBond>& bonds() const { return bonds_; }
  const std::vector<Chain>& chains() const { return chains_; }  // in declaration order
  // Tube `tube`'s chain, or null when it has none.
  const Chain* chain(std::int32_t tube) const;
  bool bonded(std::uint64_t a, std::uint64_t b) const;

  // Segments of tube `tube` when it is a ring, 0 otherwise (open or undeclared): O(1), read by
  // every exclusion test of a pair of one tube.
  int ring_length(std::int32_t tube) const {
    return tube >= 0 && static_cast<std::size_t>(tube) < ring_length_.size() ? ring_length_[tube]
                                                                             : 0;
  }
  bool empty() const { return bonds_.empty() && chains_.empty(); }

  friend bool operator==(const Topology& a, const Topology& b) {
    return a.bonds_ == b.bonds_ && a.chains_ == b.chains_;
  }

 private:
  void check_bond(const Elements& el, std::uint64_t a, std::uint64_t b, BondType type) const;
  void check_chain(const Elements& el, const Chain& c) const;
  void record_bond(std::uint64_t a, std::uint64_t b, BondType type);
  void record_chain(Chain c);

  struct PairHash {
    std::size_t operator()(const std::pair<std::uint64_t, std::uint64_t>& p) const {
      return std::hash<std::uint64_t>()(p.first * 0x9E3779B97F4A7C15ull ^ p.second);
    }
  };
  std::vector<TopologyBond> bonds_;
  std::unordered_set<std::pair<std::uint64_t, std::uint64_t>, PairHash> bonded_;  // (min, max)
  std::vector<Chain> chains_;
  std::vector<std::int32_t> chain_of_tube_;  // per tube id: index into chains_, -1 for none
  std::vector<std::int32_t> ring_length_;    // per tube id: segments of a ring, 0 otherwise
};

}  // namespace mdem
