#include "mdem/job.h"

#include <algorithm>
#include <cmath>

namespace mdem {

std::vector<std::string> energy_columns(const std::vector<EnergyTerm>& terms) {
  std::vector<std::string> c;
  for (EnergyTerm t : terms)
    c.push_back(std::string(kEnergyTermNames[static_cast<int>(t)]) + "_eV");
  for (const char* n : {"kinetic_translational_eV", "kinetic_rotational_eV", "external_work_eV",
                        "dissipated_eV", "total_eV", "balance_residual_eV"})
    c.emplace_back(n);
  return c;
}

std::vector<double> energy_values(const System& sys, const std::vector<EnergyTerm>& terms) {
  const EnergyLedger& L = sys.energy();
  std::vector<double> v;
  for (EnergyTerm t : terms) v.push_back(L.potential.stored[static_cast<int>(t)]);
  v.insert(v.end(), {L.kinetic_translational, L.kinetic_rotational, L.external_work, L.dissipated,
                     L.total(), L.balance_residual()});
  return v;
}

namespace {

long steps_for(double every_ps, double dt) {
  return every_ps > 0 ? std::max(1L, std::lround(every_ps / dt)) : 0;
}

}  // namespace

JobRunResult run_job(Job& job, const JobCadence& cadence, const JobObserver& obs) {
  System& sys = job.system();
  sys.initialize();
  const double dt = sys.dt();
  const long total = std::max(1L, static_cast<long>(std::ceil(job.duration() / dt - 1e-9)));
  const long frame_every = steps_for(cadence.frame_every_ps, dt);
  const long snap_every = steps_for(cadence.snapshot_every_ps, dt);
  const long progress_every = std::max(1L, total / 200);

  auto report = [&](long step) {
    if (obs.frame && frame_every && (step % frame_every == 0 || step == total))
      obs.frame({step, sys.time(), job.observe()});
    if (obs.snapshot && snap_every && (step % snap_every == 0 || step == total))
      obs.snapshot(capture_snapshot(sys.elements(), step, sys.time()));
    if (obs.progress && (step % progress_every == 0 || step == total))
      obs.progress({step, total, sys.time(), job.phase()});
  };

  JobRunResult r;
  report(0);
  long step = 0;
  while (step < total) {
    if (obs.cancelled && obs.cancelled()) {
      r.cancelled = true;
      break;
    }
    // Run to the next step at which anything is due.
    long next = std::min(total, (step / progress_every + 1) * progress_every);
    if (frame_every) next = std::min(next, (step / frame_every + 1) * frame_every);
    if (snap_every) next = std::min(next, (step / snap_every + 1) * snap_every);
    sys.run(next - step);
    step = next;
    report(step);
  }
  r.steps = step;
  return r;
}

}  // namespace mdem
