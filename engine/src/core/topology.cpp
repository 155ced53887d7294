#include "mdem/core/topology.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "mdem/core/elements.h"

namespace mdem {

namespace {

[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("topology: " + what);
}

std::size_t known(const Elements& el, std::uint64_t tag, const char* role) {
  try {
    return el.index_of(tag);
  } catch (const std::out_of_range&) {
    fail(std::string(role) + " tag " + std::to_string(tag) + " names no element (" +
         std::to_string(el.size()) + " elements, tags 0.." +
         std::to_string(el.next_tag == 0 ? 0 : el.next_tag - 1) + ")");
  }
}

std::pair<std::uint64_t, std::uint64_t> key(std::uint64_t a, std::uint64_t b) {
  return {std::min(a, b), std::max(a, b)};
}

}  // namespace

std::string_view bond_type_name(BondType t) {
  switch (t) {
    case BondType::Cnt:
      return "cnt";
  }
  return "unknown";
}

void Topology::check_bond(const Elements& el, std::uint64_t a, std::uint64_t b,
                          BondType type) const {
  if (static_cast<int>(type) >= kBondTypeCount)
    fail("unknown bond type " + std::to_string(static_cast<int>(type)));
  const std::size_t i = known(el, a, "bond end"), j = known(el, b, "bond end");
  if (a == b) fail("element tag " + std::to_string(a) + " cannot be bonded to itself");
  if (bonded(a, b))
    fail("elements tagged " + std::to_string(a) + " and " + std::to_string(b) +
         " are bonded already (one bond per pair)");
  if (type == BondType::Cnt &&
      (el.kind[i] != ElementKind::CntSegment || el.kind[j] != ElementKind::CntSegment))
    fail("a cnt bond joins two CNT segments; element tagged " +
         std::to_string(el.kind[i] != ElementKind::CntSegment ? a : b) + " is not one");
}

void Topology::check_chain(const Elements& el, const Chain& c) const {
  const std::string which = "tube " + std::to_string(c.tube);
  if (c.tube < 0) fail("a chain's tube id must be >= 0, got " + std::to_string(c.tube));
  if (chain(c.tube)) fail(which + " has a chain already");
  if (c.tags.empty()) fail(which + ": a chain needs at least 1 segment");
  if (c.closed && c.tags.size() < 3)
    fail(which + ": a ring needs at least 3 segments, got " + std::to_string(c.tags.size()));
  if (c.parent != -1 && (c.parent < 0 || c.parent == c.tube))
    fail(which + ": parent must be -1 (none) or another tube's id, got " +
         std::to_string(c.parent));
  // Consecutive indices (a tube cut by a rope defect starts past 0), so that index differences
  // are distances along the chain, as the exclusion reads them.
  std::int32_t first = 0;
  for (std::size_t k = 0; k < c.tags.size(); ++k) {
    const std::size_t i = known(el, c.tags[k], (which + " segment").c_str());
    if (k == 0) first = el.index[i];
    const std::int32_t want = first + static_cast<std::int32_t>(k);
    if (el.kind[i] != ElementKind::CntSegment || el.tube[i] != c.tube || el.index[i] != want)
      fail(which + ": position " + std::to_string(k) + " must hold the CNT segment of tube " +
           std::to_string(c.tube) + ", index " + std::to_string(want) + "; element tagged " +
           std::to_string(c.tags[k]) + " is " +
           (el.kind[i] == ElementKind::CntSegment ? "" : "no CNT segment, ") + "tube " +
           std::to_string(el.tube[i]) + ", index " + std::to_string(el.index[i]));
  }
}

void Topology::record_bond(std::uint64_t a, std::uint64_t b, BondType type) {
  bonds_.push_back({a, b, type});
  bonded_.insert(key(a, b));
}

void Topology::record_chain(Chain c) {
  const auto t = static_cast<std::size_t>(c.tube);
  if (chain_of_tube_.size() <= t) {
    chain_of_tube_.resize(t + 1, -1);
    ring_length_.resize(t + 1, 0);
  }
  chain_of_tube_[t] = static_cast<std::int32_t>(chains_.size());
  ring_length_[t] = c.closed ? static_cast<std::int32_t>(c.tags.size()) : 0;
  chains_.push_back(std::move(c));
}

void Topology::add_bond(const Elements& el, std::uint64_t a, std::uint64_t b, BondType type) {
  check_bond(el, a, b, type);
  record_bond(a, b, type);
}

void Topology::add_chain(const Elements& el, Chain chain) {
  check_chain(el, chain);
  record_chain(std::move(chain));
}

void Topology::add_bonded_chain(const Elements& el, Chain chain, BondType type) {
  check_chain(el, chain);
  // The chain's tags are distinct (each holds its own index), so its own bonds cannot repeat one
  // another; each is checked against the bonds recorded before.
  const std::vector<std::uint64_t>& t = chain.tags;
  const std::size_t n = t.size();
  const std::size_t nb = chain.closed ? n : n - 1;
  for (std::size_t k = 0; k < nb; ++k) check_bond(el, t[k], t[(k + 1) % n], type);
  for (std::size_t k = 0; k < nb; ++k) record_bond(t[k], t[(k + 1) % n], type);
  record_chain(std::move(chain));
}

const Chain* Topology::chain(std::int32_t tube) const {
  if (tube < 0 || static_cast<std::size_t>(tube) >= chain_of_tube_.size()) return nullptr;
  const std::int32_t c = chain_of_tube_[tube];
  return c < 0 ? nullptr : &chains_[c];
}

bool Topology::bonded(std::uint64_t a, std::uint64_t b) const {
  return bonded_.count(key(a, b)) != 0;
}

}  // namespace mdem
