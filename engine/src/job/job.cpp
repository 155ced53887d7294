#include "mdem/job/job.h"

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

void Job::save_state(StateWriter&) const {
  throw CheckpointError("job kind '" + std::string(kind()) + "' cannot checkpoint");
}

void Job::load_state(StateReader&) {
  throw CheckpointError("job kind '" + std::string(kind()) + "' cannot checkpoint");
}

std::string save_checkpoint(const Job& job) {
  StateWriter w;
  write_header(w);
  w.put_string(job.kind());
  job.save_state(w);
  return w.take();
}

void load_checkpoint(Job& job, std::string_view bytes) {
  StateReader r(bytes);
  read_header(r);
  const std::string kind = r.get_string("job kind");
  if (kind != job.kind())
    r.fail("job kind",
           "checkpoint of a '" + kind + "' job, this job is '" + std::string(job.kind()) + "'");
  job.load_state(r);
  r.expect_end();
}

JobRunResult run_job(Job& job, const JobCadence& cadence, const JobObserver& obs) {
  System& sys = job.system();
  // A restored (or advanced) system keeps its state: initializing would reset its energy ledger
  // and guard figures, and the run that started it reported step 0.
  const bool resumed = sys.steps() > 0;
  if (!resumed || !sys.initialized()) sys.initialize();
  const double dt = sys.dt();
  const long total = std::max(1L, static_cast<long>(std::ceil(job.duration() / dt - 1e-9)));
  const long frame_every = steps_for(cadence.frame_every_ps, dt);
  const long snap_every = steps_for(cadence.snapshot_every_ps, dt);
  const long progress_every = std::max(1L, total / 200);
  // Cancellation is polled between chunks: at most 50 000 element-steps per chunk, so a cancel
  // takes effect within ~0.2 s (a twisted rope costs 3.5 µs per element-step on two threads, 6 on
  // one). Chunks do not change the results: System::run(a + b) equals run(a) then run(b), and the
  // guard counts absolute steps.
  const long n = static_cast<long>(sys.elements().size());
  const long max_chunk = std::max(1L, 50000 / std::max(1L, n));

  auto report = [&](long step) {
    if (obs.frame && frame_every && (step % frame_every == 0 || step == total))
      obs.frame({step, sys.time(), job.observe()});
    if (obs.snapshot && snap_every && (step % snap_every == 0 || step == total)) {
      Snapshot snap = capture_snapshot(sys.elements(), step, sys.time());
      job.decorate(snap);
      obs.snapshot(snap);
    }
    if (obs.progress && (step % progress_every == 0 || step == total))
      obs.progress({step, total, sys.time(), job.phase()});
  };

  JobRunResult r;
  long step = sys.steps();
  if (!resumed) report(0);
  while (step < total) {
    if (obs.cancelled && obs.cancelled()) {
      r.cancelled = true;
      break;
    }
    // Run to the next step at which anything is due, or a chunk's length.
    long next = std::min({total, (step / progress_every + 1) * progress_every, step + max_chunk});
    if (frame_every) next = std::min(next, (step / frame_every + 1) * frame_every);
    if (snap_every) next = std::min(next, (step / snap_every + 1) * snap_every);
    sys.run(next - step);
    step = next;
    report(step);
    if (obs.checkpoint) obs.checkpoint(step);
  }
  r.steps = step;
  return r;
}

}  // namespace mdem
