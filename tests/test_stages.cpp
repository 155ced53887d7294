// Staged jobs (job/stage.h): a job is a scene and an ordered list of stages run by run_job with
// progress, cancellation and checkpoints in every stage. Checked here: the compression job's
// packing stage packs exactly what pack_grains packs, reports progress, cancels promptly and
// resumes from a checkpoint taken inside it to the bit-identical end; a two-stage job (a damped
// relaxation that stops on a force balance, then an undamped hold) switches damping and stop
// conditions per stage and resumes inside its second stage; the bundle run is an ordinary job.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/io/state_io.h"
#include "mdem/job/bundle_job.h"
#include "mdem/job/compression_job.h"
#include "mdem/job/stage.h"
#include "mdem/scene/bundle_scene.h"
#include "mdem/scene/film_builder.h"
#include "mdem/scene/grain_packing.h"

namespace mdem {
namespace {

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

bool same_frames(const std::vector<SeriesFrame>& a, const std::vector<SeriesFrame>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (a[k].step != b[k].step || std::memcmp(&a[k].time_ps, &b[k].time_ps, sizeof(double)) != 0 ||
        !same_bits(a[k].values, b[k].values))
      return false;
  return true;
}

// Runs `job` until the first checkpoint call (a step boundary in any stage) at which `when(step)`
// holds, saves it there and cancels; returns the bytes (empty if it never held).
template <class When>
std::string save_when(Job& job, const JobCadence& cadence, When when) {
  std::string bytes;
  JobObserver obs;
  obs.checkpoint = [&](long step) {
    if (bytes.empty() && when(step)) bytes = save_checkpoint(job);
  };
  obs.cancelled = [&] { return !bytes.empty(); };
  EXPECT_TRUE(run_job(job, cadence, obs).cancelled);
  return bytes;
}

// ---- compression: the packing stage ----

// A small gold sphere (R = 6 nm, grains of 1–2 nm: a few dozen grains, a few thousand packing
// steps), crushed briefly.
CompressionJobSpec small_particle(std::uint64_t seed = 3) {
  CompressionJobSpec s;
  s.particle.r_outer = 6.0;
  s.particle.grain_r_min = 1.0;
  s.particle.grain_r_max = 2.0;
  s.particle.target_porosity = 0.4;
  s.particle.material = gold();
  s.particle.seed = seed;
  s.bond.behaviour = BondBehaviour::Elastic;
  s.loading.speed = 0.05;
  s.loading.peak_displacement = 0.5;
  s.viscous_ratio = 0.5;
  return s;
}

IntegratorSettings two_threads(double local_damping = 0.7) {
  IntegratorSettings st;
  st.local_damping = local_damping;
  st.threads = 2;
  return st;
}

// The old direct call: pack_grains on the thread count the job packs with.
PackedParticle packed_directly(const CompressionJobSpec& spec) {
  PackingSpec p = spec.particle;
  p.threads = 2;
  return pack_grains(p);
}

void expect_same_packing(const PackedParticle& a, const PackedParticle& b) {
  EXPECT_TRUE(same_bits(a.grains.x, b.grains.x));
  EXPECT_TRUE(same_bits(a.grains.radius, b.grains.radius));
  EXPECT_EQ(a.touching, b.touching);
  EXPECT_EQ(a.steps, b.steps);
  EXPECT_EQ(a.rattlers, b.rattlers);
  EXPECT_EQ(a.porosity, b.porosity);
  EXPECT_EQ(a.unbalanced_ratio, b.unbalanced_ratio);
  EXPECT_EQ(a.wall_shift, b.wall_shift);
}

struct Record {
  std::vector<SeriesFrame> frames;
  std::vector<JobProgress> progress;
  JobObserver observer() {
    JobObserver o;
    o.frame = [this](const SeriesFrame& f) { frames.push_back(f); };
    o.progress = [this](const JobProgress& p) { progress.push_back(p); };
    return o;
  }
};

TEST(Stages, PackingStageGivesTheDirectCallsParticleAndReportsProgress) {
  const CompressionJobSpec spec = small_particle();
  const PackedParticle direct = packed_directly(spec);
  ASSERT_GT(direct.grains.size(), 10u);
  ASSERT_GT(direct.steps, 3000);  // growth and relaxation both ran

  CompressionJob job(spec, two_threads());
  ASSERT_EQ(job.stages().size(), 2u);
  EXPECT_EQ(job.stages()[0]->name(), "packing");
  EXPECT_FALSE(job.built());
  Record rec;
  const JobRunResult r = run_job(job, {1.0, 0.0}, rec.observer());
  ASSERT_FALSE(r.cancelled);
  // Run in chunks under the run loop, the packing is the direct call's, bit for bit.
  expect_same_packing(job.packing(), direct);
  EXPECT_EQ(job.bonds().bonds().size(), direct.touching.size());

  // Progress: the packing first (its own phase and stage), then the compression; the overall
  // step never goes back, and the packing's last report is its step count.
  ASSERT_FALSE(rec.progress.empty());
  EXPECT_EQ(rec.progress.front().stage, "packing");
  EXPECT_EQ(rec.progress.front().phase, "packing");
  EXPECT_EQ(rec.progress.back().stage, "compression");
  long packing_reports = 0, last_packing_step = -1, prev = -1;
  for (const JobProgress& p : rec.progress) {
    EXPECT_GE(p.step, prev);
    EXPECT_LE(p.step, p.total_steps);
    EXPECT_EQ(p.stage_count, 2);
    prev = p.step;
    if (p.stage == "packing") {
      EXPECT_EQ(p.stage_index, 0);
      ++packing_reports;
      last_packing_step = p.stage_step;
    } else {
      EXPECT_EQ(p.stage_index, 1);
      EXPECT_EQ(p.step, direct.steps + p.stage_step);  // overall = packing + this stage
    }
  }
  EXPECT_GE(packing_reports, 3);
  std::printf("[ packing  ] %zu grains, %ld packing steps, %ld progress reports while packing\n",
              direct.grains.size(), direct.steps, packing_reports);
  EXPECT_EQ(last_packing_step, direct.steps);
  // Frames only from the compression's system, from its step 0.
  ASSERT_FALSE(rec.frames.empty());
  EXPECT_EQ(rec.frames.front().step, 0);
  EXPECT_EQ(r.steps, job.system().steps());
}

TEST(Stages, CancelDuringPackingReturnsPromptly) {
  CompressionJob job(small_particle(), two_threads());
  JobObserver obs;
  bool seen = false;
  obs.progress = [&](const JobProgress& p) { seen = seen || (p.stage == "packing" && p.step > 0); };
  obs.cancelled = [&] { return seen; };
  const auto t0 = std::chrono::steady_clock::now();
  const JobRunResult r = run_job(job, {1.0, 0.0}, obs);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_TRUE(r.cancelled);
  EXPECT_EQ(job.stage_index(), 0u);  // still packing
  EXPECT_FALSE(job.built());
  EXPECT_EQ(r.steps, 0);  // no step of the time series yet
  EXPECT_LT(wall, 2.0);
}

// Runs `spec` uninterrupted; then again, saving at the first checkpoint call where the packing
// has done at least `packing_steps` and cancelling; a job built anew loads the bytes and runs to
// the end: the same frames, particle and final state, bit for bit.
void expect_packing_resume(const CompressionJobSpec& spec, long packing_steps) {
  const JobCadence cadence{0.5, 0.0};
  CompressionJob full(spec, two_threads());
  Record whole;
  const JobRunResult rf = run_job(full, cadence, whole.observer());
  const Summary full_summary = full.summary();

  std::string bytes;
  {
    CompressionJob first(spec, two_threads());
    bytes = save_when(first, cadence, [&](long step) {
      EXPECT_EQ(step, 0);  // packing: no step of the time series yet
      return first.stage_index() == 0 && first.stages()[0]->steps_done() >= packing_steps;
    });
    ASSERT_FALSE(first.built());
  }
  ASSERT_FALSE(bytes.empty());
  CompressionJob resumed(spec, two_threads());
  load_checkpoint(resumed, bytes);
  EXPECT_EQ(resumed.stage_index(), 0u);
  EXPECT_GE(resumed.stages()[0]->steps_done(), packing_steps);
  EXPECT_EQ(save_checkpoint(resumed), bytes);  // loading restores everything saving writes
  Record after;
  EXPECT_EQ(run_job(resumed, cadence, after.observer()).steps, rf.steps);
  expect_same_packing(resumed.packing(), full.packing());
  EXPECT_TRUE(same_frames(after.frames, whole.frames));
  EXPECT_TRUE(same_bits(resumed.system().elements().x, full.system().elements().x));
  EXPECT_EQ(resumed.summary(), full_summary);
}

TEST(Stages, CheckpointWhileGrainsGrowResumesBitIdentically) {
  expect_packing_resume(small_particle(), 1000);
}

TEST(Stages, CheckpointWhilePackingRelaxesResumesBitIdentically) {
  expect_packing_resume(small_particle(), 3500);
}

TEST(Stages, CheckpointAfterPackingCarriesTheParticle) {
  // Saved in the compression stage, the checkpoint holds the packed particle: a job built anew
  // does not pack again, and ends where the uninterrupted run ends.
  const CompressionJobSpec spec = small_particle();
  CompressionJob full(spec, two_threads());
  run_job(full, {1.0, 0.0}, {});
  std::string bytes;
  {
    CompressionJob first(spec, two_threads());
    bytes = save_when(first, {1.0, 0.0}, [](long step) { return step >= 20; });
  }
  CompressionJob resumed(spec, two_threads());
  load_checkpoint(resumed, bytes);
  EXPECT_TRUE(resumed.built());
  EXPECT_EQ(resumed.stage_index(), 1u);
  expect_same_packing(resumed.packing(), full.packing());
  run_job(resumed, {1.0, 0.0}, {});
  EXPECT_TRUE(same_bits(resumed.system().elements().x, full.system().elements().x));
  EXPECT_EQ(resumed.summary(), full.summary());

  // The particle of another seed is another job: its checkpoint is refused, naming the packing.
  CompressionJob other(small_particle(4), two_threads());
  try {
    load_checkpoint(other, bytes);
    ADD_FAILURE() << "a checkpoint of another packing loaded";
  } catch (const CheckpointError& e) {
    EXPECT_NE(std::string(e.what()).find("packing"), std::string::npos) << e.what();
  }
}

// ---- a two-stage job: damped relaxation to a force balance, then an undamped hold ----

class RelaxThenHold final : public Job {
 public:
  RelaxThenHold(double tolerance, long max_relax, long hold)
      : sys_(make_bundle_system(bundle(), two_threads(0.0))) {
    SystemStage::Settings relax;
    relax.local_damping = 0.3;
    relax.stop = StopCondition::when(std::make_shared<ForceBalance>(tolerance), 20, max_relax);
    add_stage(std::make_unique<SystemStage>("relax", *this, std::move(relax)));
    SystemStage::Settings keep;
    keep.local_damping = 0.0;
    keep.stop = StopCondition::after_steps(hold);
    add_stage(std::make_unique<SystemStage>("hold", *this, std::move(keep)));
  }
  static BundleSpec bundle() {
    BundleSpec b;
    b.tubes = 1;
    b.segments = 8;
    b.speed = 0.02;
    b.spin = 0.02;
    b.bundle_spin = 0;
    return b;
  }
  std::string_view kind() const override { return "relax-then-hold"; }
  System& system() override { return sys_; }
  double duration() const override { return 0; }
  std::vector<std::string> columns() const override {
    return energy_columns({EnergyTerm::BondTension});
  }
  std::vector<double> observe() override { return energy_values(sys_, {EnergyTerm::BondTension}); }
  Summary summary() override { return {}; }

 private:
  System sys_;
};

TEST(Stages, EachStageHasItsDampingAndStopCondition) {
  const double tol = 0.05;  // eV/nm
  RelaxThenHold job(tol, 20000, 400);
  std::vector<std::string> stages;
  double dissipated_at_hold = -1;
  long relax_steps = -1;
  JobObserver obs;
  obs.progress = [&](const JobProgress& p) {
    if (stages.empty() || stages.back() != p.stage) stages.push_back(p.stage);
    if (p.stage == "hold" && dissipated_at_hold < 0) {
      dissipated_at_hold = job.system().energy().dissipated;
      relax_steps = p.step - p.stage_step;
    }
  };
  const JobRunResult r = run_job(job, {1.0, 0.0}, obs);
  EXPECT_FALSE(r.cancelled);
  EXPECT_EQ(stages, (std::vector<std::string>{"relax", "hold"}));
  // The relaxation stopped on its criterion, at a check step, well before its maximum: the
  // largest net force, computed here from the elements, was below the tolerance there.
  ASSERT_GT(relax_steps, 0);
  EXPECT_LT(relax_steps, 20000);
  EXPECT_EQ(relax_steps % 20, 0);
  EXPECT_EQ(r.steps, relax_steps + 400);
  // The hold is undamped: nothing more is dissipated (energy conservation, no damping at all).
  EXPECT_GT(dissipated_at_hold, 0);
  EXPECT_EQ(job.system().energy().dissipated, dissipated_at_hold);
  EXPECT_EQ(job.system().settings().local_damping, 0.0);
  for (const Vec3& fd : job.system().damping_forces()) EXPECT_EQ(fd.norm(), 0.0);

  // The criterion itself: run the relaxation alone and look at the force where it stopped.
  RelaxThenHold alone(tol, 20000, 400);
  JobObserver stop_at_hold;
  stop_at_hold.cancelled = [&] { return alone.stage_index() == 1; };
  run_job(alone, {1.0, 0.0}, stop_at_hold);
  ASSERT_EQ(alone.stage_index(), 1u);
  const Elements& el = alone.system().elements();
  double worst = 0;
  for (std::size_t i = 0; i < el.size(); ++i)
    worst = std::max(worst, (el.f[i] + el.f_ext[i]).norm());
  EXPECT_LT(worst, tol);
  EXPECT_EQ(alone.system().steps(), relax_steps);
}

// A job that hands on to a new, larger system after its first stage (as the tensile job does
// after its pre-relaxation): its work counts both systems' steps and element-steps.
class RebuildAfterFirst final : public Job {
 public:
  RebuildAfterFirst(long first, long second) {
    sys_ = std::make_unique<System>(make_bundle_system(bundle(8), two_threads(0.0)));
    SystemStage::Settings a;
    a.stop = StopCondition::after_steps(first);
    add_stage(std::make_unique<SystemStage>("small", *this, std::move(a)));
    SystemStage::Settings b;
    b.stop = StopCondition::after_steps(second);
    add_stage(std::make_unique<SystemStage>("large", *this, std::move(b)));
  }
  static BundleSpec bundle(int segments) {
    BundleSpec b = RelaxThenHold::bundle();
    b.segments = segments;
    return b;
  }
  std::string_view kind() const override { return "rebuild-after-first"; }
  System& system() override { return *sys_; }
  double duration() const override { return 0; }
  std::vector<std::string> columns() const override { return {}; }
  std::vector<double> observe() override { return {}; }
  Summary summary() override { return {}; }

 protected:
  void stage_finished(std::size_t k) override {
    if (k == 0) sys_ = std::make_unique<System>(make_bundle_system(bundle(12), two_threads(0.0)));
  }

 private:
  std::unique_ptr<System> sys_;
};

TEST(Stages, WorkCountsEverySystemTheJobRan) {
  RebuildAfterFirst job(30, 50);
  run_job(job, {1.0, 0.0}, {});
  // The second system ran its 50 steps from step 0 (a new system), the first its 30.
  EXPECT_EQ(job.system().steps(), 50);
  EXPECT_EQ(job.system().elements().size(), 12u);
  const JobWork w = job.work();
  EXPECT_EQ(w.steps, 30 + 50);
  EXPECT_EQ(w.element_steps, 8.0 * 30 + 12.0 * 50);
  // The timers hold both systems' time: more than the current one's alone.
  EXPECT_GT(w.timers.total(), job.system().timers().total());
  // A job that keeps its system counts it once.
  RelaxThenHold same(0.05, 20000, 400);
  run_job(same, {1.0, 0.0}, {});
  EXPECT_EQ(same.work().steps, same.system().steps());
  EXPECT_EQ(same.work().element_steps,
            static_cast<double>(same.system().elements().size()) * same.system().steps());
}

TEST(Stages, ResumeInsideTheSecondStageIsBitIdentical) {
  RelaxThenHold full(0.05, 20000, 400);
  const JobRunResult rf = run_job(full, {1.0, 0.0}, {});
  std::string bytes;
  long saved_at = -1;
  {
    RelaxThenHold first(0.05, 20000, 400);
    bytes = save_when(first, {1.0, 0.0}, [&](long step) {
      saved_at = step;
      return first.stage_index() == 1 && first.stage_begun() &&
             first.stages()[1]->steps_done() >= 150;
    });
  }
  RelaxThenHold resumed(0.05, 20000, 400);
  load_checkpoint(resumed, bytes);
  EXPECT_EQ(resumed.stage_index(), 1u);
  EXPECT_EQ(resumed.system().steps(), saved_at);
  EXPECT_EQ(resumed.system().settings().local_damping, 0.0);  // the hold's, not the relax's
  EXPECT_EQ(save_checkpoint(resumed), bytes);
  EXPECT_EQ(run_job(resumed, {1.0, 0.0}, {}).steps, rf.steps);
  EXPECT_TRUE(same_bits(resumed.system().elements().x, full.system().elements().x));
  EXPECT_TRUE(same_bits(resumed.system().elements().w, full.system().elements().w));
  EXPECT_EQ(resumed.system().energy().total(), full.system().energy().total());
}

TEST(Stages, StopConditionsAreCheckedAtConstruction) {
  RelaxThenHold job(0.05, 10, 10);
  auto expect_refused = [&](StopCondition c, const std::string& what) {
    SystemStage::Settings s;
    s.stop = std::move(c);
    try {
      SystemStage st("bad", job, std::move(s));
      ADD_FAILURE() << "accepted: " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  expect_refused(StopCondition{}, "exactly one");
  expect_refused(StopCondition{1.0, 5, nullptr, 100, 0}, "exactly one");
  expect_refused(StopCondition::after(-1.0), "duration");
  expect_refused(StopCondition::after(std::nan("")), "duration");
  expect_refused(StopCondition::when(std::make_shared<ForceBalance>(1.0), 0, 10), "check_every");
  // A criterion may end a duration early, not a step count; it needs a check interval.
  expect_refused(StopCondition{0, 5, std::make_shared<ForceBalance>(1.0), 10, 10}, "exactly one");
  expect_refused(StopCondition::after_unless(1.0, std::make_shared<ForceBalance>(1.0), 0),
                 "check_every");
  SystemStage::Settings ok;
  ok.stop = StopCondition::after_unless(1.0, std::make_shared<ForceBalance>(1.0), 10);
  EXPECT_NO_THROW(SystemStage("early", job, std::move(ok)));
  EXPECT_THROW(ForceBalance(0.0), std::invalid_argument);
}

// A seven-tube bundle bound by vdW, then the same bundle with the vdW contact switched off by its
// second stage: the tubes no longer interact.
class Unbind final : public Job {
 public:
  Unbind() : sys_(make_bundle_system(bundle(), two_threads(0.0))) {
    vdw_ = sys_.find<AnisotropicVdw>();
    SystemStage::Settings bound;
    bound.stop = StopCondition::after_steps(100);
    add_stage(std::make_unique<SystemStage>("bound", *this, std::move(bound)));
    SystemStage::Settings unbound;
    unbound.inactive_models = {vdw_};
    unbound.stop = StopCondition::after_steps(200);
    add_stage(std::make_unique<SystemStage>("unbound", *this, std::move(unbound)));
  }
  static BundleSpec bundle() {
    BundleSpec b;
    b.tubes = 7;
    b.segments = 4;
    return b;
  }
  std::string_view kind() const override { return "unbind"; }
  System& system() override { return sys_; }
  double duration() const override { return 0; }
  std::vector<std::string> columns() const override { return energy_columns({EnergyTerm::Vdw}); }
  std::vector<double> observe() override { return energy_values(sys_, {EnergyTerm::Vdw}); }
  Summary summary() override { return {}; }
  const AnisotropicVdw* vdw() const { return vdw_; }

 private:
  System sys_;
  const AnisotropicVdw* vdw_ = nullptr;
};

TEST(Stages, AStageCanSwitchAForceModelOff) {
  Unbind job;
  const auto vdw = static_cast<int>(EnergyTerm::Vdw);
  double bound_vdw = 0;
  bool active_when_bound = false;
  JobObserver obs;
  obs.progress = [&](const JobProgress& p) {
    if (p.stage == "bound" && p.stage_step == 100) {  // the bound stage's end
      bound_vdw = job.system().energy().potential.stored[vdw];
      active_when_bound = job.system().model_active(job.vdw());
    }
  };
  EXPECT_EQ(run_job(job, {1.0, 0.0}, obs).steps, 300);
  EXPECT_LT(bound_vdw, -1.0);  // eV: seven tubes side by side are bound
  EXPECT_TRUE(active_when_bound);
  EXPECT_FALSE(job.system().model_active(job.vdw()));
  EXPECT_EQ(job.system().energy().potential.stored[vdw], 0.0);
  // Switching the contact off is booked as work (the binding energy given back), so the
  // balance still closes to Verlet's few per cent and nothing was dissipated.
  EXPECT_NEAR(job.system().energy().external_work, -bound_vdw, 0.1 * -bound_vdw);
  EXPECT_LT(job.system().energy_balance_error(), 0.05);
  EXPECT_EQ(job.system().energy().dissipated, 0.0);
}

// ---- the bundle run as an ordinary job ----

TEST(Stages, BundleJobConservesEnergyAndResumes) {
  BundleJobSpec spec;
  spec.bundle.tubes = 1;
  spec.bundle.segments = 10;
  spec.steps = 600;
  IntegratorSettings st;
  st.threads = 2;
  BundleJob full(spec, st);
  Record rec;
  const JobRunResult r = run_job(full, {0.05, 0.0}, rec.observer());
  EXPECT_EQ(r.steps, 600);
  EXPECT_EQ(full.duration(), 600 * full.system().dt());
  // No damping, no loads: W_ext = 0 = ΔE up to Verlet's bounded few-per-cent fluctuation at the
  // default step.
  EXPECT_LT(full.system().energy_balance_error(), 0.05);
  EXPECT_EQ(full.system().energy().dissipated, 0.0);
  EXPECT_EQ(rec.frames.front().step, 0);
  EXPECT_EQ(rec.frames.back().step, 600);
  EXPECT_EQ(rec.progress.back().phase, "bundle");

  std::string bytes;
  {
    BundleJob first(spec, st);
    bytes = save_when(first, {0.05, 0.0}, [](long step) { return step >= 250; });
  }
  BundleJob resumed(spec, st);
  load_checkpoint(resumed, bytes);
  EXPECT_EQ(run_job(resumed, {0.05, 0.0}, {}).steps, 600);
  EXPECT_TRUE(same_bits(resumed.system().elements().x, full.system().elements().x));
  EXPECT_EQ(resumed.summary(), full.summary());

  BundleJobSpec bad = spec;
  bad.steps = 0;
  EXPECT_THROW(BundleJob(bad, st), std::invalid_argument);
}

// ---- chunks of a large system's steps ----

// 30 000 CNT segments in free flight (no force model, so a step is only the integrator's pass):
// above 25 000 elements the job runner's 50 000 element-step budget between two polls of
// cancellation is one step.
class FreeFlight final : public Job {
 public:
  explicit FreeFlight(long steps) : sys_(film(), settings()) {
    SystemStage::Settings s;
    s.stop = StopCondition::after_steps(steps);
    add_stage(std::make_unique<SystemStage>("flight", *this, std::move(s)));
  }
  static Elements film() {
    FilmSpec f;
    f.side = 300;
    f.thickness = 10;
    f.tubes = 300;
    f.segments_per_tube = 100;
    f.seed = 7;
    Elements el;
    add_random_film(el, f);
    for (std::size_t i = 0; i < el.size(); ++i) {
      const double k = static_cast<double>(i % 97) - 48;
      el.v[i] = Vec3(0.001 * k, -0.002 * k, 0.0005 * k);
      el.w[i] = Vec3(0.003 * k, 0.001 * k, -0.002 * k);
    }
    return el;
  }
  static IntegratorSettings settings() {
    IntegratorSettings s = two_threads(0.0);
    s.dt = 0.002;
    return s;
  }
  std::string_view kind() const override { return "free-flight"; }
  System& system() override { return sys_; }
  double duration() const override { return 0; }
  std::vector<std::string> columns() const override { return energy_columns({}); }
  std::vector<double> observe() override { return energy_values(sys_, {}); }
  Summary summary() override { return {}; }

 private:
  System sys_;
};

TEST(Stages, ALargeSystemRunsChunksOfSeveralStepsWithTheSameResults) {
  // One-step chunks would run every step of a large film as a run's last, whose passes over the
  // elements are not fused (6 % of the dense film's step): the runner takes as many steps per
  // chunk as ran in ~0.1 s, up to 64, and up to the next progress report (every 0.5 % of the
  // stage: 10 steps here). A step here costs ~0.3 ms, so chunks of several steps (at a step of
  // 0.05 s, 150 times slower, they would be one step again). The results are those of one
  // System::run of all the steps, bit for bit, and a cancel still stops at a chunk's end.
  const long steps = 2000;
  FreeFlight job(steps);
  ASSERT_GT(job.system().elements().size(), 25000u);
  std::vector<long> polls;
  JobObserver obs;
  obs.checkpoint = [&](long step) { polls.push_back(step); };
  EXPECT_EQ(run_job(job, {0.0, 0.0}, obs).steps, steps);
  ASSERT_FALSE(polls.empty());
  EXPECT_EQ(polls.back(), steps);
  long longest = 0;
  for (std::size_t k = 1; k < polls.size(); ++k)
    longest = std::max(longest, polls[k] - polls[k - 1]);
  EXPECT_EQ(longest, 10) << polls.size() << " chunks";

  System alone(FreeFlight::film(), FreeFlight::settings());
  alone.initialize();
  alone.run(steps);
  EXPECT_TRUE(same_bits(job.system().elements().x, alone.elements().x));
  EXPECT_TRUE(same_bits(job.system().elements().q, alone.elements().q));

  FreeFlight cancelled(steps);
  long at = -1;
  JobObserver stop;
  stop.checkpoint = [&](long step) { at = step; };
  stop.cancelled = [&] { return at >= 100; };
  const JobRunResult r = run_job(cancelled, {0.0, 0.0}, stop);
  EXPECT_TRUE(r.cancelled);
  EXPECT_EQ(r.steps, at);
  EXPECT_LE(at, 110);
}

}  // namespace
}  // namespace mdem
