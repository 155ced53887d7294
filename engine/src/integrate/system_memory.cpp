// System::memory_bytes: what a system's data holds, for the daemon's per-job memory peak.
#include "mdem/core/capacity_bytes.h"
#include "mdem/integrate/system.h"

namespace mdem {
namespace {

// The per-element arrays (the domain, groups and topology are small and shared by stages).
std::size_t element_bytes(const Elements& el) {
  return capacity_bytes(el.tag) + capacity_bytes(el.x) + capacity_bytes(el.q) +
         capacity_bytes(el.v) + capacity_bytes(el.w) + capacity_bytes(el.mass) +
         capacity_bytes(el.inv_mass) + capacity_bytes(el.inertia) + capacity_bytes(el.radius) +
         capacity_bytes(el.kind) + capacity_bytes(el.tube) + capacity_bytes(el.index) +
         capacity_bytes(el.dof) + capacity_bytes(el.v_prescribed) +
         capacity_bytes(el.w_prescribed) + capacity_bytes(el.f_ext) + capacity_bytes(el.t_ext) +
         capacity_bytes(el.f) + capacity_bytes(el.t);
}

}  // namespace

std::size_t System::memory_bytes() const {
  std::size_t b = element_bytes(el_) + sink_.memory_bytes() + capacity_bytes(fd_) +
                  capacity_bytes(td_) + capacity_bytes(f_prev_) + capacity_bytes(t_prev_) +
                  capacity_bytes(fext_prev_) + capacity_bytes(text_prev_) +
                  capacity_bytes(partial_sums_);
  for (const PairTable::Entry& e : pairs_.entries())
    if (e.list) b += e.list->memory_bytes();
  for (const ForceModelPtr& m : models_) b += m->memory_bytes();
  return b;
}

}  // namespace mdem
