// The stability suite (issue 15 item 5, docs/stability.md): stiff and extreme cases run through
// the path a user takes - `mdem run` in-process, the shared job runner (jobs/) with the job
// classes the CLI builds, and for a few the daemon - each either finishing with finite, physical
// results or stopping with a message that names the step, the element, the cause and what to
// change; never a crash, a hang or a non-finite number in the results database. Cases that need
// a setting no job spec has (a bond-stiffness scale, a temperature or torque above the spec's
// range, a time step above the safe limit) run through JobRunner with a test registry of job
// kinds whose build makes the same TwistJob and then changes that one thing. Every case prints
// one "[stability]" line with its figures and wall time: the table of docs/stability.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../client/src/results_store.h"
#include "cnt_scene.h"
#include "mdem/core/cnt.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/contact/linear_contact.h"
#include "mdem/force/contact/np_cnt_contact.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/job/twist_job.h"
#include "mdem/job_runner.h"
#include "mdem/protocol/tensile_protocol.h"
#include "mdem/scene/grain.h"
#include "mdem/scene/nanoparticle.h"
#include "mdem/scene/tube_builder.h"
#include "mdem/spec.h"
#include "server_support.h"
#include "support.h"

namespace {

using namespace mdem;
using mdem::testing::contains;
using mdem::testing::TempDir;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;
using mdem::testing::since;
using mdem::testing::operator+;

// One line of the suite's table (docs/stability.md): the case, what happened, the wall time.
void note(const std::string& name, const std::string& what, double wall_s) {
  std::string w = what;
  std::replace(w.begin(), w.end(), '\n', ' ');
  std::printf("[stability] %s | %s | %.3f s\n", name.c_str(), w.c_str(), wall_s);
  std::fflush(stdout);
}

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

// ---- what every case must satisfy ------------------------------------------------------------

// A stop message names the step, the element and the cause, and says what to change.
void expect_useful_stop(const std::string& msg) {
  EXPECT_TRUE(contains(msg, "step")) << msg;
  EXPECT_TRUE(contains(msg, "segment") || contains(msg, "element") || contains(msg, "grain") ||
              contains(msg, "nanoparticle"))
      << msg;
  EXPECT_TRUE(contains(msg, "lower dt") || contains(msg, "check") || contains(msg, "reduce") ||
              contains(msg, "use "))
      << msg;
}

// A case that may either stop or finish: a stop's message must be useful (expect_useful_stop);
// a finished run is noted with its figures (computed only then: a failed job has no summary).
void note_outcome(const std::string& name, bool failed, const std::string& reason,
                  const std::function<std::string()>& figures, double wall_s) {
  if (failed) {
    expect_useful_stop(reason);
    note(name, "FAILED: " + reason, wall_s);
  } else {
    note(name, "SUCCEEDED: " + figures(), wall_s);
  }
}

// Every number the results database holds for every job in it is finite (frames, snapshots);
// a SUCCEEDED job's summary has no null (a non-finite number prints as null in JSON). Returns
// {frames, snapshots} of the last job.
std::pair<std::size_t, std::size_t> expect_finite_db(const std::string& db) {
  cli::ResultsStore store(db);
  std::size_t nf = 0, ns = 0;
  for (const cli::JobRecord& job : store.list()) {
    nf = 0;
    for (const SeriesFrame& f : store.frames(job.id)) {
      EXPECT_TRUE(std::isfinite(f.time_ps));
      for (double v : f.values) EXPECT_TRUE(std::isfinite(v)) << job.id << " step " << f.step;
      ++nf;
    }
    ns = store.snapshot_count(job.id);
    for (std::size_t k = 0; k < ns; ++k) {
      const auto s = store.snapshot(job.id, k);
      EXPECT_TRUE(s);
      if (!s) break;
      for (std::size_t i = 0; i < s->size(); ++i)
        EXPECT_TRUE(s->x[i].allFinite() && s->q[i].coeffs().allFinite()) << job.id;
      for (const Vec3& v : s->v) EXPECT_TRUE(v.allFinite()) << job.id;
    }
    if (job.state == "SUCCEEDED" && !job.summary_json.empty()) {
      const json r = json::parse(job.summary_json);
      for (const auto& [k, v] : r["summary"].items()) EXPECT_FALSE(v.is_null()) << k;
    }
  }
  return {nf, ns};
}

// ---- `mdem run` in-process ------------------------------------------------------------------

struct CliRun {
  mdem::testing::CliResult r;
  json doc;  // the --json report (empty when none was printed)
  double wall_s = 0;
};

CliRun mdem_run(const std::string& kind, const std::vector<std::string>& args,
                const std::string& db) {
  std::vector<std::string> a = args;
  for (const char* s : {"--json", "--no-log"}) a.emplace_back(s);
  a.insert(a.end(), {"--db", db});
  const auto t0 = Clock::now();
  CliRun c{mdem::testing::run_job(kind, a), {}, 0};
  c.wall_s = since(t0);
  if (!c.r.out.empty()) c.doc = json::parse(c.r.out, nullptr, false);
  return c;
}

// A rope of 7 tubes x 10 segments (70 elements) on one thread.
const std::vector<std::string> kSmallRope = {"--layers", "2",         "--length",
                                             "13.56",    "--threads", "1"};

// Torque 10x the thesis's 64 nN·nm is outside the spec's range: refused before any work,
// naming the field, its flag and the range.
TEST(Stability, CliTorqueTenTimesTheThesisIsRefusedWithTheRange) {
  TempDir d("stab-torque");
  const CliRun c =
      mdem_run("twist", kSmallRope + std::vector<std::string>{"--torque", "640"}, d.file("r.db"));
  EXPECT_EQ(c.r.code, 2) << c.r.err;
  EXPECT_TRUE(contains(c.r.err, "torque")) << c.r.err;
  EXPECT_TRUE(contains(c.r.err, "500")) << c.r.err;
  note("twist, torque 640 nN·nm (10x thesis), mdem run", "refused: " + c.r.err.substr(0, 160),
       c.wall_s);
}

// The largest torque the spec allows (500 nN·nm, 7.8x the thesis) raised 100x faster than the
// thesis's 1 nN·nm/ps on a 7-tube rope: the run either finishes with finite figures or stops
// with a useful message, and the database stays finite.
TEST(Stability, CliTorqueAtTheSpecLimitRampedFast) {
  TempDir d("stab-torque-max");
  const std::string db = d.file("r.db");
  const CliRun c =
      mdem_run("twist",
               kSmallRope + std::vector<std::string>{"--torque", "500", "--rate", "100", "--hold",
                                                     "5", "--snapshot-every", "1"},
               db);
  ASSERT_TRUE(c.r.code == 0 || c.r.code == 1) << c.r.err;
  const auto [nf, ns] = expect_finite_db(db);
  note_outcome(
      "twist, torque 500 nN·nm at 100 nN·nm/ps, mdem run", c.r.code == 1, c.doc.value("reason", ""),
      [&, nf = nf, ns = ns] {
        const json& s = c.doc["summary"];
        return "twist angle " + fmt(s["twist_angle_deg"]) + " deg, end shift " +
               fmt(s["shift_angle_deg"]) + " deg, balance error " +
               fmt(c.doc["accuracy"]["energy_balance_error"]) + ", frames " + std::to_string(nf) +
               ", snapshots " + std::to_string(ns);
      },
      c.wall_s);
}

// 10^4 K is above the spec's temperature range (2000 K): refused naming it.
TEST(Stability, CliTemperatureOfTenThousandKelvinIsRefusedWithTheRange) {
  TempDir d("stab-temp");
  const CliRun c = mdem_run(
      "twist", kSmallRope + std::vector<std::string>{"--temperature", "10000"}, d.file("r.db"));
  EXPECT_EQ(c.r.code, 2) << c.r.err;
  EXPECT_TRUE(contains(c.r.err, "temperature")) << c.r.err;
  EXPECT_TRUE(contains(c.r.err, "2000")) << c.r.err;
  note("twist, 10^4 K, mdem run", "refused: " + c.r.err.substr(0, 160), c.wall_s);
}

// dt at 0.95x the critical step (safety 1 lets it through) runs; at 1.05x it is refused before
// any work with the limit and what to use instead.
TEST(Stability, CliTimeStepAroundTheCriticalStep) {
  TempDir d("stab-dt");
  const std::string db = d.file("r.db");
  const auto base = kSmallRope + std::vector<std::string>{"--torque", "20", "--rate",        "10",
                                                          "--hold",   "5",  "--temperature", "300"};
  const CliRun probe = mdem_run("twist", mdem::testing::with(base, {"--hold", "0"}), db);
  ASSERT_EQ(probe.r.code, 0) << probe.r.err;
  const double dtc = probe.doc["accuracy"]["critical_dt_ps"];
  const CliRun at95 = mdem_run(
      "twist", base + std::vector<std::string>{"--safety", "1", "--dt", fmt(0.95 * dtc)}, db);
  ASSERT_EQ(at95.r.code, 0) << at95.r.err;
  EXPECT_NEAR(at95.doc["accuracy"]["dt_over_critical"].get<double>(), 0.95, 1e-4);
  const double err = at95.doc["accuracy"]["energy_balance_error"];
  EXPECT_LT(err, 0.1);
  note("twist, dt = 0.95 x critical (" + fmt(dtc) + " ps), safety 1, mdem run",
       "SUCCEEDED: balance error " + fmt(err) + ", twist angle " +
           fmt(at95.doc["summary"]["twist_angle_deg"]) + " deg",
       at95.wall_s);
  const CliRun at105 = mdem_run(
      "twist", base + std::vector<std::string>{"--safety", "1", "--dt", fmt(1.05 * dtc)}, db);
  EXPECT_EQ(at105.r.code, 2) << at105.r.err;
  EXPECT_TRUE(contains(at105.r.err, "above the safe limit")) << at105.r.err;
  note("twist, dt = 1.05 x critical, safety 1, mdem run", "refused: " + at105.r.err.substr(0, 200),
       at105.wall_s);
  expect_finite_db(db);
}

// Platens 10x and 100x faster than the thesis's 0.01 nm/ps crush the default Au particle.
TEST(Stability, CliPlatenSpeedTenAndHundredTimesTheThesis) {
  for (const char* speed : {"0.1", "1"}) {
    TempDir d("stab-platen");
    const std::string db = d.file("r.db");
    const CliRun c =
        mdem_run("compression", {"--speed", speed, "--threads", "1", "--snapshot-every", "5"}, db);
    ASSERT_TRUE(c.r.code == 0 || c.r.code == 1) << c.r.err;
    const auto [nf, ns] = expect_finite_db(db);
    const std::string name = std::string("compression, platen speed ") + speed + " nm/ps";
    note_outcome(
        name, c.r.code == 1, c.doc.value("reason", ""),
        [&, nf = nf, ns = ns] {
          const json& s = c.doc["summary"];
          return "peak force " + fmt(s["peak_force_nN"]) + " nN, bonds broken " +
                 fmt(s["bonds_broken"]) + ", balance error " +
                 fmt(c.doc["accuracy"]["energy_balance_error"]) + ", frames " + std::to_string(nf) +
                 ", snapshots " + std::to_string(ns);
        },
        c.wall_s);
  }
}

// Crushed to 95 % of its diameter (4.75x the thesis's 20 %): the platens nearly meet.
TEST(Stability, CliCompressionToNinetyFivePercentOfTheDiameter) {
  TempDir d("stab-crush");
  const std::string db = d.file("r.db");
  const CliRun c =
      mdem_run("compression",
               {"--peak", "19", "--speed", "0.1", "--threads", "1", "--snapshot-every", "5"}, db);
  ASSERT_TRUE(c.r.code == 0 || c.r.code == 1) << c.r.err;
  expect_finite_db(db);
  note_outcome(
      "compression to h = 19 nm of 20 nm", c.r.code == 1, c.doc.value("reason", ""),
      [&] {
        return "peak force " + fmt(c.doc["summary"]["peak_force_nN"]) + " nN, balance error " +
               fmt(c.doc["accuracy"]["energy_balance_error"]);
      },
      c.wall_s);
}

// ---- the job runner with the CLI's job classes, past the spec's ranges ------------------------

// The finalized spec of a small twist job (7 tubes x 10 segments, one thread).
v1::JobSpec small_twist_spec(double torque_nn_nm, double rate, double hold_ps) {
  v1::JobSpec s;
  s.mutable_run()->set_threads(1);
  s.mutable_outputs()->set_snapshot_every_ps(0);
  auto* t = s.mutable_twist();
  t->set_layers(2);
  t->set_length_nm(13.56);
  t->set_torque_nn_nm(torque_nn_nm);
  t->set_torque_rate_nn_nm_per_ps(rate);
  t->set_hold_ps(hold_ps);
  return spec::finalize(s);
}

// A registry with one kind, twist, whose job is the CLI's TwistJob with `edit` applied to its
// settings before it is built and `after` to the job after.
JobKindRegistry twist_registry(std::function<void(IntegratorSettings&)> edit,
                               std::function<void(TwistJob&)> after = {}) {
  JobKind k = twist_job_kind();
  const auto build = k.build;
  k.build = [edit, after, build](const v1::JobSpec& spec, IntegratorSettings s) {
    if (edit) edit(s);
    auto job = build(spec, s);
    if (after) after(dynamic_cast<TwistJob&>(*job));
    return job;
  };
  return JobKindRegistry{k};
}

struct RunnerResult {
  JobOutcome outcome;
  ReportJson report;
  double dt = 0, dt_critical = 0, balance = 0;
  bool frames_finite = true;
  long frames = 0;
};

RunnerResult run_runner(const v1::JobSpec& spec, const JobKindRegistry& kinds) {
  JobRunner runner(spec, 0, kinds);
  RunnerResult r;
  JobObserver obs;
  obs.frame = [&](const SeriesFrame& f) {
    ++r.frames;
    for (double v : f.values) r.frames_finite = r.frames_finite && std::isfinite(v);
  };
  check_time_step(runner.job());
  r.outcome = runner.run(obs, {});
  r.report = runner.report("stab", r.outcome);
  const System& sys = runner.job().system();
  r.dt = sys.dt();
  r.dt_critical = sys.critical_dt();
  r.balance = sys.energy_balance_error();
  return r;
}

// Bond stiffness x100 and x10^4 with the automatic step: once the bonds set the step (x100 on;
// at x1 the vdW contact and its dashpots lower it too), it falls as 1/sqrt(stiffness), the run
// finishes with its balance closed, and the rope's twist tends to the rigid-bond limit.
TEST(Stability, StiffBondsTakeAProportionallySmallerAutomaticStep) {
  const v1::JobSpec spec = small_twist_spec(10, 10, 1);
  std::vector<double> dt, twist;
  for (const double scale : {1.0, 100.0, 1e4}) {
    const auto t0 = Clock::now();
    const auto kinds = twist_registry({}, [scale](TwistJob& job) {
      for (Bond& b : job.system().find<ParallelBond>()->bonds()) {
        b.k.kn_area *= scale;
        b.k.ks_area *= scale;
        b.k.kn_inertia *= scale;
        b.k.ks_polar *= scale;
      }
    });
    const RunnerResult r = run_runner(spec, kinds);
    ASSERT_EQ(r.outcome.state, v1::SUCCEEDED) << r.outcome.reason;
    EXPECT_TRUE(r.frames_finite);
    EXPECT_LT(r.balance, 0.01);
    dt.push_back(r.dt);
    twist.push_back(r.report["summary"]["twist_angle_deg"]);
    note("twist, bond stiffness x" + fmt(scale) + ", auto dt (job runner)",
         "SUCCEEDED: dt " + fmt(r.dt * 1000) + " fs (" + fmt(r.dt / dt[0]) + " of x1), " +
             std::to_string(r.outcome.steps) + " steps, balance error " + fmt(r.balance) +
             ", twist angle " + fmt(twist.back()) + " deg",
         since(t0));
  }
  EXPECT_LT(dt[1] / dt[0], 0.1 * 1.4);     // at most the vdW's share above 1/sqrt(100)
  EXPECT_NEAR(dt[2] / dt[1], 0.1, 0.002);  // bond-dominated: exactly 1/sqrt(100)
  EXPECT_LT(std::abs(twist[2] - twist[1]), 0.1 * std::abs(twist[1] - twist[0]));
}

// dt at 0.95x and 1.05x the critical step with the safe-limit check off (check_dt), then 1.5x,
// 2x and 3x: the critical step is a Gershgorin bound below the true limit, so the first ones
// run; the run guard stops the unstable ones with the step, element, cause and what to change.
TEST(Stability, TimeStepBeyondTheCriticalStepWithTheCheckOff) {
  v1::JobSpec spec = small_twist_spec(20, 10, 5);
  spec.mutable_twist()->set_temperature_k(300);
  const double dtc = run_runner(small_twist_spec(20, 10, 0), job_kinds()).dt_critical;
  bool stopped = false;
  for (const double f : {0.95, 1.05, 1.5, 2.0, 3.0}) {
    const auto t0 = Clock::now();
    const auto kinds = twist_registry([=](IntegratorSettings& s) {
      s.dt = f * dtc;
      s.safety = 1;
      s.check_dt = false;
    });
    const RunnerResult r = run_runner(spec, kinds);
    EXPECT_TRUE(r.frames_finite);
    const std::string name = "twist, dt = " + fmt(f) + " x critical, check off (job runner)";
    const bool failed = r.outcome.state == v1::FAILED;
    stopped = stopped || failed;
    if (!failed) {
      EXPECT_LT(r.balance, 0.5);  // not stopped: within the guard's tolerance
    }
    note_outcome(
        name, failed, r.outcome.reason, [&] { return "balance error " + fmt(r.balance); },
        since(t0));
    if (f <= 1.05) {
      EXPECT_EQ(r.outcome.state, v1::SUCCEEDED) << f << ": " << r.outcome.reason;
    }
  }
  EXPECT_TRUE(stopped) << "even 3x the critical step ran: the guard never tripped";
}

// Velocities of 10^4 K (5x the spec's range): the seeded motion carries 3 kT per element
// (equipartition over 6 degrees of freedom) at the start, and the run finishes finite.
TEST(Stability, TenThousandKelvinStartsAtEquipartitionAndStaysFinite) {
  v1::JobSpec spec = small_twist_spec(10, 10, 5);
  spec.mutable_twist()->set_temperature_k(1e4);  // past validation: the spec allows 2000 K
  const auto t0 = Clock::now();
  JobRunner runner(spec, 0, job_kinds());
  const auto cols = runner.job().columns();
  std::vector<double> first;
  bool finite = true;
  JobObserver obs;
  obs.frame = [&](const SeriesFrame& f) {
    if (first.empty()) first = f.values;
    for (double v : f.values) finite = finite && std::isfinite(v);
  };
  const JobOutcome o = runner.run(obs, {});
  EXPECT_TRUE(finite);
  const auto col = [&](const std::string& n) {
    const auto it = std::find(cols.begin(), cols.end(), n);
    EXPECT_NE(it, cols.end()) << n;
    return first.at(static_cast<std::size_t>(it - cols.begin()));
  };
  const double n = static_cast<double>(runner.job().system().elements().size());
  const double kt = units::kBoltzmann * 1e4;
  const double ke0 = col("kinetic_translational_eV") + col("kinetic_rotational_eV");
  EXPECT_NEAR(ke0 / (3 * n * kt), 1.0, 0.2);  // 420 degrees of freedom: 7 % standard deviation
  const std::string name = "twist, velocities of 10^4 K (job runner)";
  EXPECT_NE(o.state, v1::CANCELLED);
  const System& sys = runner.job().system();
  note_outcome(
      name, o.state == v1::FAILED, o.reason,
      [&] {
        return "initial kinetic " + fmt(ke0) + " eV (3NkT = " + fmt(3 * n * kt) +
               "), balance error " + fmt(sys.energy_balance_error()) + ", dt " +
               fmt(sys.dt() * 1000) + " fs";
      },
      since(t0));
}

// Torque 10x the thesis's 64 nN·nm (above the spec's 500) at 10 nN·nm/ps on the 7-tube rope.
TEST(Stability, TorqueTenTimesTheThesisThroughTheJobRunner) {
  const auto t0 = Clock::now();
  v1::JobSpec spec = small_twist_spec(64, 10, 10);
  spec.mutable_twist()->set_torque_nn_nm(640);  // past validation: the spec allows 500
  const RunnerResult r = run_runner(spec, job_kinds());
  EXPECT_TRUE(r.frames_finite);
  const std::string name = "twist, torque 640 nN·nm at 10 nN·nm/ps (job runner)";
  EXPECT_NE(r.outcome.state, v1::CANCELLED);
  note_outcome(
      name, r.outcome.state == v1::FAILED, r.outcome.reason,
      [&] {
        return "twist angle " + fmt(r.report["summary"]["twist_angle_deg"]) + " deg, end shift " +
               fmt(r.report["summary"]["shift_angle_deg"]) + " deg, balance error " +
               fmt(r.balance);
      },
      since(t0));
}

// ---- overlapping scenes, engine level --------------------------------------------------------

// The twist job's models (bonds, vdW, its dashpots) on a hand-made scene, auto dt.
System cnt_system(Elements el, double safety = 0.6) {
  IntegratorSettings s;
  s.threads = 1;
  s.safety = safety;
  return mdem::testing::cnt_scene_system(std::move(el), s);
}

Vec3 momentum(const Elements& el) {
  Vec3 p = Vec3::Zero();
  for (std::size_t i = 0; i < el.size(); ++i) p += el.mass[i] * el.v[i];
  return p;
}
double momentum_scale(const Elements& el) {
  double s = 0;
  for (std::size_t i = 0; i < el.size(); ++i) s += el.mass[i] * el.v[i].norm();
  return s;
}

struct SceneRun {
  std::string outcome;  // "finished ..." or the stop message
  bool failed = false;
  double wall_s = 0;
};

// Runs `steps` steps: finite state, momentum conserved (no external load), energy balance closed
// (the dashpots' dissipation booked), or a useful stop.
SceneRun run_scene(System& sys, long steps, double balance_limit = 0.05) {
  const auto t0 = Clock::now();
  SceneRun r;
  try {
    sys.initialize();
    const double e0 = sys.energy().total();
    sys.run(steps);
    const Elements& el = sys.elements();
    for (std::size_t i = 0; i < el.size(); ++i)
      EXPECT_TRUE(el.x[i].allFinite() && el.v[i].allFinite() && el.w[i].allFinite());
    EXPECT_LT(momentum(el).norm(), 1e-9 * std::max(1.0, momentum_scale(el)));
    EXPECT_LT(sys.energy_balance_error(), balance_limit);
    r.outcome = "finished: stored + kinetic " + fmt(e0) + " -> " + fmt(sys.energy().total()) +
                " eV, dissipated " + fmt(sys.energy().dissipated) + " eV, balance error " +
                fmt(sys.energy_balance_error()) + ", dt " + fmt(sys.dt() * 1000) + " fs, |p| " +
                fmt(momentum(el).norm());
  } catch (const NumericalError& e) {
    r.failed = true;
    r.outcome = std::string("stopped: ") + e.what();
    expect_useful_stop(e.what());
  }
  r.wall_s = since(t0);
  return r;
}

// Two 11-segment tubes crossing through each other at 90°: their middle segments share a centre.
// The finding of docs/stability.md: the critical step missed the vdW's rotational stiffness in
// deep overlap (the δ(θ) curvature term), so at the automatic step the balance error reached 0.21
// (0.46 on the way). With the rotational bound (vdw_rotational_stiffness) the automatic step
// falls from 10.3 to 8.0 fs and the balance error to 0.011-0.026 (0.011 at commit 7896411,
// 0.026 after the step loop's round-off-level change 48553a4: how deep the crossing segments go
// decides it, and that trajectory is sensitive to round-off), 1.4e-3 at half the step.
TEST(Stability, TubesGeneratedCrossingThroughEachOther) {
  for (const double safety : {0.6, 0.3}) {
    Elements el;
    mdem::testing::add_crossing_tubes(el);
    System sys = cnt_system(std::move(el), safety);
    const SceneRun r = run_scene(sys, 2000, safety < 0.5 ? 0.01 : 0.05);
    EXPECT_FALSE(r.failed) << r.outcome;
    note(
        "two tubes crossing through each other (shared centre), safety " + fmt(safety) + ", engine",
        r.outcome, r.wall_s);
  }
}

// 300 % strain (docs/stability.md; the full run is bench_stability's
// BM_TensileThreeHundredPercent): the tensile protocol explains a runaway element whose bond is
// drawn out past its rest length (the model's bonds never break), and only then.
TEST(Stability, TensileStopNamesABondDrawnOutPastItsRestLength) {
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 3, 0);
  auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  el.x[2] += Vec3(0, 3.0, 0);  // the bond 1-2 drawn out sideways by 3 nm (rest length 1.356 nm)
  el.x[0] += Vec3(0, 0.5, 0);  // the bond 0-1 sheared by 0.5 nm: within its rest length
  IntegratorSettings s;
  s.threads = 1;
  System sys(std::move(el), s);
  sys.add(std::move(bonds));
  TensileLoading l;
  l.length = 40;
  l.monotonic = {0.01, 10, 3.0};
  const TensileProtocol protocol(l);
  const std::string why = protocol.explain_runaway(sys, 2);
  EXPECT_TRUE(contains(why, "bond to element 1 is drawn out by")) << why;
  EXPECT_TRUE(contains(why, "bonds never break")) << why;
  EXPECT_TRUE(contains(why, "lower the target strain")) << why;
  EXPECT_EQ(protocol.explain_runaway(sys, 0), "");
  note("element whose bond is drawn out 3 nm sideways, tensile protocol", why, 0);
}

// Two tubes on one axis: every segment of one on a segment of the other, and shifted by half a
// segment (interleaved).
TEST(Stability, CoaxialTubes) {
  for (const double shift : {0.0, 0.5 * cnt::kSegmentLength}) {
    Elements el;
    add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 10, 0);
    add_straight_tube(el, Vec3(shift, 0, 0), Vec3::UnitX(), 10, 1);
    System sys = cnt_system(std::move(el));
    const SceneRun r = run_scene(sys, 2000);
    note("two coaxial tubes, shifted " + fmt(shift) + " nm, engine", r.outcome, r.wall_s);
  }
}

// Tube B starts where tube A ends: their end segments coincide.
TEST(Stability, TubesWithEndToEndCoincidentSegments) {
  Elements el;
  add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 10, 0);
  add_straight_tube(el, Vec3(9 * cnt::kSegmentLength, 0, 0), Vec3::UnitX(), 10, 1);
  System sys = cnt_system(std::move(el));
  const SceneRun r = run_scene(sys, 2000);
  note("two tubes end to end, end segments coincident, engine", r.outcome, r.wall_s);
}

// An NP centred on a tube's segment, and one 0.1 nm off the axis: the finite-overlap NP-CNT law
// pushes the tube out, with no non-finite number.
TEST(Stability, NanoparticleInsideATube) {
  for (const double off : {0.0, 0.1}) {
    Elements el;
    const auto tube = add_straight_tube(el, Vec3::Zero(), Vec3::UnitX(), 10, 0);
    el.add(nanoparticle(el.x[tube[4]] + Vec3(0, off, 0)));
    auto bonds = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
    IntegratorSettings s;
    s.threads = 1;
    System sys(std::move(el), s);
    sys.add(std::move(bonds));
    sys.add(std::make_unique<AnisotropicVdw>());
    sys.add(std::make_unique<NpCntContact>());
    ASSERT_FALSE(sys.initialized());
    const SceneRun r = run_scene(sys, 2000);
    note("NP inside a tube, " + fmt(off) + " nm off its axis, engine", r.outcome, r.wall_s);
  }
}

// 27 Au grains of 1 nm on a cubic lattice 1.5 nm apart (each pair overlapping by half a radius),
// undamped: they fly apart, the stored energy turned into kinetic energy.
TEST(Stability, GrainsOverlappingByHalfTheirRadius) {
  const GrainMaterial au = gold();
  Elements el;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      for (int c = 0; c < 3; ++c) el.add(grain_element(1.5 * Vec3(a, b, c), 1.0, au));
  IntegratorSettings s;
  s.threads = 1;
  System sys(std::move(el), s);
  sys.add(std::make_unique<LinearContact>(au.youngs, 1.0));
  const auto t0 = Clock::now();
  sys.initialize();
  const double stored0 = sys.energy().potential.total_stored();
  EXPECT_GT(stored0, 0);
  SceneRun r = run_scene(sys, 4000);
  ASSERT_FALSE(r.failed) << r.outcome;
  // Apart for good: nothing stored any more, all of it kinetic (undamped, so to the balance).
  EXPECT_EQ(sys.energy().potential.total_stored(), 0.0);
  EXPECT_NEAR(sys.energy().kinetic() / stored0, 1.0, 0.01);
  note("27 grains overlapping by half their radius, engine",
       r.outcome + ", stored " + fmt(stored0) + " eV -> kinetic " + fmt(sys.energy().kinetic()) +
           " eV",
       since(t0));
}

// ---- results far beyond the usual sizes --------------------------------------------------------

// A frame and a snapshot every step (the default job stores a frame per ps and a snapshot per
// 10 ps: here 50x and 500x more): every one stored, all finite, and the database still reads.
TEST(Stability, CliAFrameAndASnapshotEveryStep) {
  TempDir d("stab-many");
  const std::string db = d.file("r.db");
  const CliRun c = mdem_run(
      "twist",
      kSmallRope + std::vector<std::string>{"--torque", "2", "--hold", "20", "--temperature", "300",
                                            "--energy-every", "0.001", "--snapshot-every", "0.001"},
      db);
  ASSERT_EQ(c.r.code, 0) << c.r.err;
  const long steps = c.doc["performance"]["steps"];
  const auto [nf, ns] = expect_finite_db(db);
  EXPECT_EQ(static_cast<long>(nf), steps + 1);
  EXPECT_EQ(static_cast<long>(ns), steps + 1);
  const auto bytes = std::filesystem::file_size(db);
  note("twist, a frame and a snapshot every step, mdem run",
       "SUCCEEDED: " + std::to_string(steps) + " steps, " + std::to_string(nf) + " frames, " +
           std::to_string(ns) + " snapshots, database " + fmt(bytes / 1e6) + " MB",
       c.wall_s);
}

// ---- the daemon ------------------------------------------------------------------------------

using mdem::testing::DaemonProcess;
using mdem::testing::fresh_dir;
using mdem::testing::kAliceToken;

// The CLI's out-of-range cases submitted to mdemd: refused at submit, each field named.
TEST(StabilityDaemon, OutOfRangeTorqueAndTemperatureAreRefusedAtSubmit) {
  DaemonProcess d(fresh_dir("stab-range"));
  v1::JobSpec s = mdem::testing::small_spec(5);
  s.mutable_twist()->set_torque_nn_nm(640);
  s.mutable_twist()->set_temperature_k(1e4);
  const auto t0 = Clock::now();
  const grpc::Status st = mdem::testing::submit(d, kAliceToken, "range", s).status;
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_TRUE(contains(st.error_message(), "twist.torque_nn_nm")) << st.error_message();
  EXPECT_TRUE(contains(st.error_message(), "twist.temperature_k")) << st.error_message();
  note("twist, torque 640 nN·nm and 10^4 K, mdemd", "refused: " + st.error_message(), since(t0));
}

// dt at 1.05x the critical step with safety 1: the daemon builds the rope at submit and refuses
// the step with its limit; 0.95x runs.
TEST(StabilityDaemon, TimeStepAboveTheCriticalStepIsRefusedAtSubmit) {
  DaemonProcess d(fresh_dir("stab-dt"));
  v1::JobSpec s = mdem::testing::small_spec(5);
  const double dtc = run_runner(spec::finalize(s), job_kinds()).dt_critical;
  s.mutable_run()->set_safety(1);
  s.mutable_run()->set_dt_ps(1.05 * dtc);
  auto t0 = Clock::now();
  const grpc::Status st = mdem::testing::submit(d, kAliceToken, "dt105", s).status;
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_TRUE(contains(st.error_message(), "above the safe limit")) << st.error_message();
  note("twist, dt = 1.05 x critical, safety 1, mdemd", "refused: " + st.error_message(), since(t0));
  s.mutable_run()->set_dt_ps(0.95 * dtc);
  t0 = Clock::now();
  const std::string id = mdem::testing::submit_ok(d, kAliceToken, "dt95", s);
  const v1::JobInfo info = mdem::testing::wait_finished(d, id);
  EXPECT_EQ(info.state(), v1::SUCCEEDED) << info.reason();
  note("twist, dt = 0.95 x critical, safety 1, mdemd",
       std::string(v1::JobState_Name(info.state())) + " after " + std::to_string(info.step()) +
           " steps",
       since(t0));
}

// A frame and a snapshot every step streamed by the daemon: every event arrives, in order, finite.
TEST(StabilityDaemon, AFrameAndASnapshotEveryStepAllArrive) {
  DaemonProcess d(fresh_dir("stab-stream"));
  const v1::JobSpec s = mdem::testing::small_spec(20, 0.001, 0.001);
  const auto t0 = Clock::now();
  const std::string id = mdem::testing::submit_ok(d, kAliceToken, "many", s);
  const v1::JobInfo info = mdem::testing::wait_finished(d, id);
  ASSERT_EQ(info.state(), v1::SUCCEEDED) << info.reason();
  grpc::Status st;
  const auto ev = mdem::testing::watch(d, kAliceToken, id, 1, -1, &st, 120);
  ASSERT_TRUE(st.ok()) << st.error_message();
  mdem::testing::expect_contiguous(ev);
  const auto frames = mdem::testing::frames_by_step(ev);
  const auto snaps = mdem::testing::snapshots_by_step(ev);
  for (const auto& [step, v] : frames)
    for (double x : v) ASSERT_TRUE(std::isfinite(x)) << "step " << step;
  EXPECT_EQ(static_cast<long>(frames.size()), info.step() + 1);
  EXPECT_EQ(static_cast<long>(snaps.size()), info.step() + 1);
  std::size_t bytes = 0;
  for (const auto& [step, b] : snaps) bytes += b.size();
  note("twist, a frame and a snapshot every step, mdemd",
       "SUCCEEDED: " + std::to_string(ev.size()) + " events, " + std::to_string(frames.size()) +
           " frames, " + std::to_string(snaps.size()) + " snapshots (" + fmt(bytes / 1e6) + " MB)",
       since(t0));
}

}  // namespace
