#pragma once
// The parallel frame of a force model that acts on grains one at a time (the walls): threads
// across the elements, each with its own force buffer and energy, the energy booked as `term`.
// Private to the engine's sources.
#include <omp.h>

#include "mdem/force/force_model.h"

namespace mdem {

// Calls kernel(i, f, energy) for every grain i; f is the calling thread's force buffer and
// energy its running sum.
template <class Kernel>
void for_each_grain(const Elements& el, ForceSink& sink, EnergyTerm term, Kernel&& kernel) {
  const long n = static_cast<long>(el.size());
#pragma omp parallel num_threads(sink.threads()) if (n >= kParallelMinItems)
  {
    const int tid = omp_get_thread_num();
    Vec3* f = sink.force(tid);
    double energy = 0;
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i)
      if (el.kind[i] == ElementKind::Grain) kernel(i, f, energy);
    sink.energy(tid).add(term, energy);
  }
}

}  // namespace mdem
