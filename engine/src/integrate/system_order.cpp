// Memory order of a system's elements (IntegratorSettings::memory_order): reordering them, and
// every element index the system, its models and updaters hold, at neighbour-list rebuilds.
#include <omp.h>

#include <string>

#include "mdem/core/limits.h"
#include "mdem/integrate/system.h"
#include "mdem/neighbor/memory_order.h"

namespace mdem {

void System::check_memory_order() const {
  const MemoryOrder m = settings_.memory_order;
  if (m == MemoryOrder::AsBuilt) return;
  if (m != MemoryOrder::Morton && m != MemoryOrder::Slabs)
    throw ConfigError("memory_order must be as_built (0), morton (1) or slabs (2), got " +
                      std::to_string(static_cast<int>(m)));
  const int every = settings_.memory_order_every;
  if (every < 1 || every > limits::kMaxReorderEvery)
    throw ConfigError("memory_order_every must be in [1, " +
                      std::to_string(limits::kMaxReorderEvery) + "] neighbour-list rebuilds, got " +
                      std::to_string(every));
  if (const std::string why = reorder_blocker(); !why.empty()) throw ConfigError(why);
}

void System::update_pairs() {
  if (settings_.memory_order == MemoryOrder::AsBuilt)
    pairs_.update(el_);
  else
    pairs_.update(el_, [this] { return reorder_along_curve(); });
}

std::string System::reorder_blocker(bool with_updaters) const {
  for (const auto& m : models_)
    if (!m->follows_reorder())
      return "memory_order " + std::string(to_string(settings_.memory_order)) + ": force model '" +
             std::string(m->name()) +
             "' holds element indices and does not follow a reordering; use memory_order "
             "as_built with it";
  for (std::size_t k = 0; with_updaters && k < updaters_.size(); ++k)
    if (!updaters_[k]->follows_reorder())
      return "memory_order " + std::string(to_string(settings_.memory_order)) + ": updater " +
             std::to_string(k + 1) + " of " + std::to_string(updaters_.size()) +
             " (a protocol, observer or plain function) does not follow a reordering of the "
             "elements; use memory_order as_built with it";
  return {};
}

void System::reorder_elements(std::span<const std::uint32_t> new_to_old) {
  if (const std::string why = reorder_blocker(); !why.empty()) throw ConfigError(why);
  apply_order(new_to_old);
}

void System::apply_order(std::span<const std::uint32_t> new_to_old) {
  const std::size_t n = el_.size();
  el_.reorder(new_to_old);  // checks the permutation before it changes anything
  // The system's own per-element arrays (sized at initialize; empty before).
  for (auto* a : {&fd_, &td_, &f_prev_, &t_prev_, &fext_prev_, &text_prev_})
    if (a->size() == n) permute(*a, new_to_old);
  const std::vector<std::uint32_t> old_to_new = invert_permutation(new_to_old);
  for (const auto& m : models_) m->reorder(old_to_new);
  for (const auto& u : updaters_) u->reorder(old_to_new);
  pairs_.invalidate();
  ++reorders_;
}

bool System::reorder_along_curve() {
  if (settings_.memory_order == MemoryOrder::AsBuilt || pairs_.empty()) return false;
  // Every memory_order_every-th build of the first sub-list (its count is in checkpoints, so a
  // resumed run reorders at the same steps).
  if (pairs_.entries().front().list->builds() % settings_.memory_order_every != 0) return false;
  const std::vector<std::uint32_t> order = wanted_order();
  if (order.empty() || is_identity_order(order)) return false;
  reorder_elements(order);
  return true;
}

std::vector<std::uint32_t> System::wanted_order() const {
  switch (settings_.memory_order) {
    case MemoryOrder::Slabs: {  // one per thread of the team (one thread keeps the tag order)
      const int team = initialized_            ? threads_
                       : settings_.threads > 0 ? settings_.threads
                                               : omp_get_max_threads();
      return slab_order(el_, team, *domain_);
    }
    case MemoryOrder::Morton:
      if (!pairs_.empty()) return morton_order(el_, pairs_.max_range(), *domain_);
      return {};
    case MemoryOrder::AsBuilt:
      return {};
  }
  return {};
}

void System::set_memory_order(MemoryOrder m) {
  const MemoryOrder before = settings_.memory_order;
  settings_.memory_order = m;
  try {
    check_memory_order();
  } catch (...) {
    settings_.memory_order = before;
    throw;
  }
  if (before != MemoryOrder::AsBuilt || m == MemoryOrder::AsBuilt) return;
  if (const std::vector<std::uint32_t> order = wanted_order();
      !order.empty() && !is_identity_order(order))
    reorder_elements(order);
}

}  // namespace mdem
