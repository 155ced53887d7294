#include "mdem/job/job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

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

// A chunk of a large system's steps between two polls of cancellation (run_job): about this
// long, and at most this many steps.
constexpr double kChunkSeconds = 0.1;
constexpr double kTimedChunkSteps = 64;

long steps_for(double every_ps, double dt) {
  return every_ps > 0 ? std::max(1L, std::lround(every_ps / dt)) : 0;
}

}  // namespace

std::string Job::phase() const {
  const Stage* st = current_stage();
  return st ? st->phase() : std::string("done");
}

Stage& Job::add_stage(std::unique_ptr<Stage> stage) {
  stages_.push_back(std::move(stage));
  if (stages_.size() == 1) stages_.front()->install();
  return *stages_.back();
}

void Job::add_state(std::shared_ptr<Stateful> part) { parts_.push_back(std::move(part)); }

long Job::overall_step() const {
  const Stage* st = current_stage();
  return finished_steps_ + (st ? st->steps_done() : 0);
}

void Job::begin_stage() {
  Stage* st = current_stage();
  if (!st || begun_) return;
  st->install();
  st->begin();
  begun_ = true;
}

void JobWork::add(const JobWork& o) {
  steps += o.steps;
  element_steps += o.element_steps;
  timers.pair_s += o.timers.pair_s;
  timers.neighbor_s += o.timers.neighbor_s;
  timers.integrate_s += o.timers.integrate_s;
  timers.updaters_s += o.timers.updaters_s;
}

void JobWork::add(const System& sys) {
  add(JobWork{sys.steps(),
              static_cast<double>(sys.elements().size()) * static_cast<double>(sys.steps()),
              sys.timers()});
}

JobWork Job::work() {
  JobWork w = left_;
  w.add(system());
  return w;
}

void Job::finish_stage() {
  Stage* st = current_stage();
  if (!st) return;
  finished_steps_ += st->steps_done();
  // The stage's system, as it ends: kept in left_ if the job goes on with another one (the old
  // one may be gone once stage_finished has run, so its figures are taken now).
  const System* before = &st->system();
  JobWork ending;
  ending.add(*before);
  stage_finished(index_);
  ++index_;
  begun_ = false;
  Stage* next = current_stage();
  if (next) next->install();
  if (&(next ? next->system() : system()) != before) left_.add(ending);
}

void Job::save_state(StateWriter& w) const {
  w.begin("job");
  w.put(static_cast<std::uint64_t>(stages_.size()));
  w.put(static_cast<std::uint64_t>(index_));
  w.put(begun_);
  w.put(finished_steps_);
  for (std::size_t k = 0; k < index_; ++k) {
    w.begin("result of " + stages_[k]->name());
    stages_[k]->save_result(w);
  }
  if (const Stage* st = current_stage()) {
    w.begin("stage " + st->name());
    st->save_state(w);
  }
  w.begin("job parts");
  for (const auto& p : parts_) p->save_state(w);
}

void Job::load_state(StateReader& r) {
  if (index_ != 0 || begun_)
    throw CheckpointError("a checkpoint loads only into a job built anew, not one that has run");
  r.begin("job");
  if (r.get<std::uint64_t>("stage count") != stages_.size())
    r.fail("stage count", "the checkpoint's job has other stages than this job's");
  const auto index = r.get<std::uint64_t>("stage index");
  if (index > stages_.size()) r.fail("stage index", "names a stage this job does not have");
  const bool begun = r.get_bool("stage begun");
  const long finished = r.get<long>("finished steps");
  for (std::size_t k = 0; k < index; ++k) {
    r.begin("result of " + stages_[k]->name());
    stages_[k]->load_result(r);
    stage_finished(k);
  }
  index_ = static_cast<std::size_t>(index);
  finished_steps_ = finished;
  if (Stage* st = current_stage()) {
    r.begin("stage " + st->name());
    st->install();  // its updaters are in place when the system's load initializes it
    st->load_state(r);
  }
  begun_ = begun;
  r.begin("job parts");
  for (const auto& p : parts_) p->load_state(r);
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

namespace {

// The step of the time series: the reporting stage's system's step, 0 before one runs.
long series_step(Job& job) {
  const Stage* st = job.current_stage();
  return st && st->reports() ? job.system().steps() : (st ? 0 : job.system().steps());
}

// Total planned steps from the current stage on (0 for stages whose length is unknown yet).
long planned_from(const Job& job) {
  long total = job.finished_steps();
  for (std::size_t k = job.stage_index(); k < job.stages().size(); ++k)
    total += job.stages()[k]->planned_steps();
  return total;
}

}  // namespace

JobRunResult run_job(Job& job, const JobCadence& cadence, const JobObserver& obs) {
  JobRunResult r;
  const int stage_count = static_cast<int>(job.stages().size());
  while (Stage* st = job.current_stage()) {
    // Between stages (the first stage starts as it always did: initialized, step 0 reported).
    // A stage whose system the job has just rebuilt (the tensile job after its pre-relaxation)
    // begins first: a cancel then takes effect at its step 0, where the system can be
    // checkpointed; an uninitialized one cannot (Ctrl-C there failed the job instead).
    if (obs.cancelled && job.stage_index() > 0 && !job.stage_begun() &&
        st->system().initialized() && obs.cancelled()) {
      r.cancelled = true;
      r.steps = series_step(job);
      return r;
    }
    const bool fresh = !job.stage_begun();
    job.begin_stage();
    System& sys = st->system();
    const bool reports = st->reports();
    const double dt = sys.dt();
    const long frame_every = reports ? steps_for(cadence.frame_every_ps, dt) : 0;
    const long snap_every = reports ? steps_for(cadence.snapshot_every_ps, dt) : 0;
    const long start = sys.steps() - st->steps_done();
    const long progress_every = std::max(1L, st->planned_steps() / 200);
    // Cancellation is polled between chunks: at most 50 000 element-steps per chunk, so a cancel
    // takes effect within ~0.2 s (a twisted rope costs 3.5 µs per element-step on two threads,
    // 6 on one). Chunks do not change the results: System::run(a + b) equals run(a) then run(b),
    // and the guard counts absolute steps. Above 25 000 elements that budget is one step, but
    // System::run fuses each step's second pass over the elements with the next step's first
    // except at its last step (one-step runs cost the dense film 6 % of its step): there a chunk
    // is as many steps as the previous one ran in kChunkSeconds, up to kTimedChunkSteps.
    const long n = static_cast<long>(sys.elements().size());
    const long budget_chunk = std::max(1L, 50000 / std::max(1L, n));
    long max_chunk = budget_chunk;

    auto report = [&](long step, long before, bool end) {
      if (obs.frame && frame_every && (step % frame_every == 0 || end))
        obs.frame({step, sys.time(), job.observe()});
      if (obs.snapshot && snap_every && (step % snap_every == 0 || end)) {
        Snapshot snap = capture_snapshot(sys.elements(), step, sys.time());
        job.decorate(snap);
        obs.snapshot(snap);
      }
      // Progress when the stage's step crosses a multiple of progress_every (a stage working in
      // units may step over one), at its start and at its end.
      const long k = step - start, k0 = before - start;
      if (obs.progress && (k / progress_every > k0 / progress_every || k == 0 || end)) {
        JobProgress p;
        p.step = job.overall_step();
        p.total_steps = std::max(p.step, planned_from(job));
        p.time_ps = sys.time();
        p.phase = st->phase();
        p.stage = st->name();
        p.stage_index = static_cast<int>(job.stage_index());
        p.stage_count = stage_count;
        p.stage_step = st->steps_done();
        p.stage_total_steps = st->planned_steps();
        obs.progress(p);
      }
    };

    long step = sys.steps();
    if (fresh && st->steps_done() == 0 && (step == 0 || !reports))
      report(step, step - 1, st->finished());
    while (!st->finished()) {
      if (obs.cancelled && obs.cancelled()) {
        r.cancelled = true;
        r.steps = series_step(job);
        return r;
      }
      // Run to the next step at which anything is due, or a chunk's length.
      long next = std::min(step + max_chunk,
                           start + ((step - start) / progress_every + 1) * progress_every);
      if (frame_every) next = std::min(next, (step / frame_every + 1) * frame_every);
      if (snap_every) next = std::min(next, (step / snap_every + 1) * snap_every);
      const auto began = std::chrono::steady_clock::now();
      st->advance(next - step);
      const double took =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
      const long before = step;
      step = sys.steps();
      if (step > before && took > 0) {
        const double fit = kChunkSeconds * static_cast<double>(step - before) / took;
        max_chunk = std::max(budget_chunk, static_cast<long>(std::min(kTimedChunkSteps, fit)));
      }
      report(step, before, st->finished());
      if (obs.checkpoint) obs.checkpoint(series_step(job));
    }
    job.finish_stage();
  }
  r.steps = job.system().steps();
  return r;
}

void prepare_job(Job& job) {
  while (Stage* st = job.current_stage()) {
    if (st->reports()) return;
    job.begin_stage();
    while (!st->finished()) st->advance(std::numeric_limits<long>::max());
    job.finish_stage();
  }
}

}  // namespace mdem
