#include "mdem/neighbor/pair_table.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

namespace mdem {

const char* kind_name(ElementKind k) {
  switch (k) {
    case ElementKind::CntSegment:
      return "CntSegment";
    case ElementKind::Nanoparticle:
      return "Nanoparticle";
    case ElementKind::Grain:
      return "Grain";
    case ElementKind::Wall:
      return "Wall";
  }
  return "unknown";
}

std::string KindPairs::describe() const {
  if (is_all()) return "all kinds";
  std::string s;
  for (int a = 0; a < kElementKinds; ++a)
    for (int b = a; b < kElementKinds; ++b) {
      const auto ka = static_cast<ElementKind>(a), kb = static_cast<ElementKind>(b);
      if (!has(ka, kb)) continue;
      if (!s.empty()) s += ", ";
      s += std::string(kind_name(ka)) + "-" + kind_name(kb);
    }
  return s.empty() ? "no kinds" : s;
}

void PairTable::setup(const std::vector<ForceModelPtr>& models, double skin, const Domain& domain) {
  entries_.clear();
  index_.clear();
  auto find_owner = [&](std::string_view name) -> Entry* {
    for (auto& e : entries_)
      if (e.owner->name() == name) return &e;
    return nullptr;
  };
  // Whether m belongs to another pair model of the system (its owner lists the pairs).
  auto has_owner = [&](const ForceModel* m) {
    const std::string_view name = m->pair_owner();
    return !name.empty() && std::any_of(models.begin(), models.end(), [&](const auto& o) {
      return o.get() != m && o->cutoff() > 0 && o->pair_owner().empty() && o->name() == name;
    });
  };
  // Owners first (a model may be added before the contact it belongs to), then the members.
  for (int pass = 0; pass < 2; ++pass) {
    for (const auto& mp : models) {
      const ForceModel* m = mp.get();
      if (!(m->cutoff() > 0)) continue;
      const bool joins = has_owner(m);
      if ((pass == 0) == joins) continue;
      if (joins) {
        Entry* owner = find_owner(m->pair_owner());
        if (m->cutoff() > owner->cutoff) {
          std::ostringstream msg;
          msg << m->name() << " belongs to the pairs of " << owner->owner->name()
              << " but reaches further (cutoff " << m->cutoff() << " nm > " << owner->cutoff
              << " nm): its cutoff must be at most its contact's";
          throw std::invalid_argument(msg.str());
        }
        owner->members.push_back(m);
        continue;
      }
      Entry e;
      e.kinds = m->kinds();
      e.cutoff = m->cutoff();
      e.owner = m;
      e.members = {m};
      try {
        e.list = std::make_unique<NeighborList>(e.cutoff, skin, domain);
      } catch (const std::invalid_argument& err) {
        throw std::invalid_argument(std::string(m->name()) + ": " + err.what());
      }
      e.list->set_kinds(e.kinds);
      e.list->set_owner(m);
      e.list->set_exclusion(
          [m](const Elements& el, std::size_t i, std::size_t j) { return m->excludes(el, i, j); });
      entries_.push_back(std::move(e));
    }
  }
  for (const auto& e : entries_)
    for (const ForceModel* m : e.members) index_.emplace_back(m, e.list.get());
}

const NeighborList* PairTable::list_of(const ForceModel* m) const {
  for (const auto& [model, list] : index_)
    if (model == m) return list;
  return nullptr;
}

std::vector<const PairTable::Entry*> PairTable::lookup(ElementKind a, ElementKind b) const {
  std::vector<const Entry*> out;
  for (const auto& e : entries_)
    if (e.kinds.has(a, b)) out.push_back(&e);
  return out;
}

void PairTable::update(const Elements& el, const std::function<bool()>& before_rebuild) {
  if (entries_.empty()) return;
  if (entries_.size() == 1 && !before_rebuild) {  // the common case: one test, no flags
    if (entries_.front().list->needs_rebuild(el)) entries_.front().list->build(el);
    return;
  }
  std::vector<char> stale(entries_.size());
  bool any = false;
  for (std::size_t k = 0; k < entries_.size(); ++k)
    any |= (stale[k] = entries_[k].list->needs_rebuild(el));
  if (any && before_rebuild && before_rebuild()) std::fill(stale.begin(), stale.end(), 1);
  for (std::size_t k = 0; k < entries_.size(); ++k)
    if (stale[k]) entries_[k].list->build(el);
}

void PairTable::invalidate() {
  for (auto& e : entries_) e.list->invalidate();
}

double PairTable::max_range() const {
  double r = 0;
  for (const auto& e : entries_) r = std::max(r, e.list->cutoff() + e.list->skin());
  return r;
}

std::string PairTable::describe() const {
  std::ostringstream s;
  for (const auto& e : entries_) {
    if (s.tellp() > 0) s << "; ";
    s << e.kinds.describe() << ": ";
    for (std::size_t k = 0; k < e.members.size(); ++k)
      s << (k ? " + " : "") << e.members[k]->name();
    s << ", cutoff " << e.cutoff << " nm";
  }
  return s.str();
}

}  // namespace mdem
