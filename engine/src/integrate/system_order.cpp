// Memory order of a system's elements (IntegratorSettings::memory_order): reordering them, and
// every element index the system, its models and updaters hold, at neighbour-list rebuilds.
#include <string>

#include "mdem/core/limits.h"
#include "mdem/integrate/system.h"
#include "mdem/neighbor/memory_order.h"

namespace mdem {

void System::check_memory_order() const {
  const MemoryOrder m = settings_.memory_order;
  if (m == MemoryOrder::AsBuilt) return;
  if (m != MemoryOrder::Morton)
    throw ConfigError("memory_order must be as_built (0) or morton (1), got " +
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

std::string System::reorder_blocker() const {
  for (const auto& m : models_)
    if (!m->follows_reorder())
      return "memory_order " + std::string(to_string(settings_.memory_order)) + ": force model '" +
             std::string(m->name()) +
             "' holds element indices and does not follow a reordering; use memory_order "
             "as_built with it";
  for (std::size_t k = 0; k < updaters_.size(); ++k)
    if (!updaters_[k]->follows_reorder())
      return "memory_order " + std::string(to_string(settings_.memory_order)) + ": updater " +
             std::to_string(k + 1) + " of " + std::to_string(updaters_.size()) +
             " (a protocol, observer or plain function) does not follow a reordering of the "
             "elements; use memory_order as_built with it";
  return {};
}

void System::reorder_elements(std::span<const std::uint32_t> new_to_old) {
  if (const std::string why = reorder_blocker(); !why.empty()) throw ConfigError(why);
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
  if (settings_.memory_order != MemoryOrder::Morton || pairs_.empty()) return false;
  // Every memory_order_every-th build of the first sub-list (its count is in checkpoints, so a
  // resumed run reorders at the same steps).
  if (pairs_.entries().front().list->builds() % settings_.memory_order_every != 0) return false;
  const std::vector<std::uint32_t> order = morton_order(el_, pairs_.max_range(), *domain_);
  if (is_identity_order(order)) return false;
  reorder_elements(order);
  return true;
}

}  // namespace mdem
