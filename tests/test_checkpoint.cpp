// Checkpoints: a twist job saved at a step, its process gone, and a job built anew from the same
// spec and loaded from the bytes continues bit-identically to the run that was never stopped;
// bytes that cannot be that job's state are refused with a message that says why.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "mdem/core/units.h"
#include "mdem/io/state_io.h"
#include "mdem/job/twist_job.h"

namespace mdem {
namespace {

// A small rope with noise (thermal velocities), dashpots and local damping, under a ramp, a hold
// and an unloading: every integrator path and protocol phase runs in a few hundred steps.
TwistJobSpec small_spec(TwistBoundary boundary = TwistBoundary::ConstantMoment) {
  TwistJobSpec s;
  s.rope.layers = 2;
  s.rope.segments = 10;
  s.loading.torque_max = units::nNnm(2.0);
  s.loading.rate = units::nNnm(1.0);
  s.loading.hold = 1.5;
  s.loading.boundary = boundary;
  s.loading.unload = true;
  s.loading.unload_hold = 1.0;
  s.temperature_k = 300;
  s.seed = 3;
  s.vdw_damping_ratio = 0.03;
  return s;
}

IntegratorSettings settings(int threads) {
  IntegratorSettings st;
  st.local_damping = 0.1;
  st.threads = threads;
  return st;
}

// Frames every 0.1 ps and snapshots every 0.5 ps: the steps of both do not depend on where a run
// stopped.
const JobCadence kCadence{0.1, 0.5};

// What a run reported.
struct Record {
  std::vector<SeriesFrame> frames;
  std::vector<Snapshot> snapshots;
  JobObserver observer() {
    JobObserver o;
    o.frame = [this](const SeriesFrame& f) { frames.push_back(f); };
    o.snapshot = [this](const Snapshot& s) { snapshots.push_back(s); };
    return o;
  }
};

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

bool same_frame(const SeriesFrame& a, const SeriesFrame& b) {
  return a.step == b.step && std::memcmp(&a.time_ps, &b.time_ps, sizeof(double)) == 0 &&
         same_bits(a.values, b.values);
}

void expect_same_ledger(const EnergyLedger& a, const EnergyLedger& b) {
  EXPECT_EQ(
      std::memcmp(a.potential.stored.data(), b.potential.stored.data(), sizeof(a.potential.stored)),
      0);
  EXPECT_EQ(a.kinetic_translational, b.kinetic_translational);
  EXPECT_EQ(a.kinetic_rotational, b.kinetic_rotational);
  EXPECT_EQ(a.external_work, b.external_work);
  EXPECT_EQ(a.dissipated, b.dissipated);
  EXPECT_EQ(a.initial_total, b.initial_total);
}

// Runs `spec` to the end uninterrupted; then runs it again, saves at the first chunk end at or
// past `stop_at` and cancels, builds a new job, loads the bytes and runs that to the end. The
// resumed run must report exactly the uninterrupted run's frames and snapshots after the saved
// step and end in the same state, bit for bit.
void expect_bit_identical_resume(const TwistJobSpec& spec, int threads, long stop_at) {
  TwistJob full(spec, settings(threads));
  Record whole;
  const JobRunResult rf = run_job(full, kCadence, whole.observer());
  const Summary full_summary = full.summary();
  ASSERT_FALSE(rf.cancelled);
  ASSERT_GT(rf.steps, stop_at + 10);

  std::string bytes;
  long saved_at = -1;
  {
    TwistJob first(spec, settings(threads));
    Record before;
    JobObserver obs = before.observer();
    obs.checkpoint = [&](long step) {
      if (bytes.empty() && step >= stop_at) {
        bytes = save_checkpoint(first);
        saved_at = step;
      }
    };
    obs.cancelled = [&] { return !bytes.empty(); };
    const JobRunResult r1 = run_job(first, kCadence, obs);
    ASSERT_TRUE(r1.cancelled);
    ASSERT_EQ(r1.steps, saved_at);
    // Up to the stop it reported what the whole run did.
    ASSERT_LE(before.frames.size(), whole.frames.size());
    for (std::size_t k = 0; k < before.frames.size(); ++k)
      EXPECT_TRUE(same_frame(before.frames[k], whole.frames[k])) << "frame " << k;
  }  // the first job is gone, as after a killed process

  TwistJob resumed(spec, settings(threads));
  load_checkpoint(resumed, bytes);
  EXPECT_EQ(resumed.system().steps(), saved_at);
  // Loading restores everything saving writes.
  EXPECT_EQ(save_checkpoint(resumed), bytes);
  Record after;
  const JobRunResult r2 = run_job(resumed, kCadence, after.observer());
  EXPECT_FALSE(r2.cancelled);
  EXPECT_EQ(r2.steps, rf.steps);

  std::vector<const SeriesFrame*> expected;
  for (const SeriesFrame& f : whole.frames)
    if (f.step > saved_at) expected.push_back(&f);
  ASSERT_EQ(after.frames.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k)
    EXPECT_TRUE(same_frame(after.frames[k], *expected[k])) << "frame at step " << expected[k]->step;
  std::vector<const Snapshot*> snaps;
  for (const Snapshot& s : whole.snapshots)
    if (s.step > saved_at) snaps.push_back(&s);
  ASSERT_EQ(after.snapshots.size(), snaps.size());
  for (std::size_t k = 0; k < snaps.size(); ++k) {
    EXPECT_EQ(after.snapshots[k].step, snaps[k]->step);
    EXPECT_TRUE(same_bits(after.snapshots[k].x, snaps[k]->x));
  }

  const Elements& a = full.system().elements();
  const Elements& b = resumed.system().elements();
  EXPECT_TRUE(same_bits(a.x, b.x));
  EXPECT_TRUE(same_bits(a.q, b.q));
  EXPECT_TRUE(same_bits(a.v, b.v));
  EXPECT_TRUE(same_bits(a.w, b.w));
  EXPECT_TRUE(same_bits(a.f, b.f));
  EXPECT_TRUE(same_bits(a.t, b.t));
  expect_same_ledger(full.system().energy(), resumed.system().energy());
  EXPECT_EQ(full.system().time(), resumed.system().time());
  EXPECT_EQ(full.summary(), full_summary);  // summary() itself is repeatable
  EXPECT_EQ(resumed.summary(), full_summary);
}

// At ~0.024 ps a step: the ramp ends at step 84, the hold at 147, the unloading at 231. The stops
// are neither frame steps (every 4th) nor steps at which the shift angle is sampled (every 10th).
TEST(Checkpoint, ResumedTwistRunIsBitIdenticalOnTwoThreads) {
  for (long stop : {61L, 123L, 183L, 253L}) {
    SCOPED_TRACE("stop at step " + std::to_string(stop));
    expect_bit_identical_resume(small_spec(), 2, stop);
  }
}

TEST(Checkpoint, ResumedTwistRunIsBitIdenticalOnOneThread) {
  expect_bit_identical_resume(small_spec(), 1, 123);
}

// Twist relaxation acts on phase changes (grips held at the hold's start, released after it): a
// run resumed in the hold must not see the hold start again, nor one resumed after the release.
TEST(Checkpoint, ResumedTwistRelaxationRunIsBitIdentical) {
  for (long stop : {110L, 163L}) {
    SCOPED_TRACE("stop at step " + std::to_string(stop));
    expect_bit_identical_resume(small_spec(TwistBoundary::TwistRelaxation), 2, stop);
  }
}

// The clamped hold (positions and spins) under the per-element load: held rotational DOFs at the
// hold's start, all DOFs freed at the release; resumed in the hold and after the release.
TEST(Checkpoint, ResumedClampedTwistRelaxationRunIsBitIdentical) {
  TwistJobSpec s = small_spec(TwistBoundary::TwistRelaxation);
  s.loading.grip_load = GripLoad::PerElement;
  s.loading.grip_hold = GripHold::PositionsAndSpins;
  for (long stop : {110L, 163L}) {
    SCOPED_TRACE("stop at step " + std::to_string(stop));
    expect_bit_identical_resume(s, 2, stop);
  }
}

// Above kParallelMinItems elements the integrator, sink and neighbour-list loops run threaded;
// the energy ledger then repeats only because the integrator adds the threads' sums in a fixed
// order (OpenMP's reduction(+) does not).
TEST(Checkpoint, ResumedRunIsBitIdenticalWhenTheLoopsAreThreaded) {
  TwistJobSpec s = small_spec();
  s.rope.layers = 3;
  s.rope.segments = 108;  // 19 tubes: 2052 elements
  s.loading.torque_max = units::nNnm(0.5);
  s.loading.hold = 0.5;
  s.loading.unload = false;
  expect_bit_identical_resume(s, 2, 23);
}

// Running n steps in chunks is running n steps: run_job's chunking cannot change a result.
TEST(Checkpoint, ChunkedRunEqualsOneRun) {
  TwistJob a(small_spec(), settings(2)), b(small_spec(), settings(2));
  a.system().run(250);
  for (long n : {1L, 9L, 90L, 100L, 50L}) b.system().run(n);
  EXPECT_TRUE(same_bits(a.system().elements().x, b.system().elements().x));
  EXPECT_TRUE(same_bits(a.system().elements().w, b.system().elements().w));
  expect_same_ledger(a.system().energy(), b.system().energy());
}

// A checkpoint of `spec` after 37 steps.
std::string checkpoint_after_steps(const TwistJobSpec& spec, int threads, long steps = 37) {
  TwistJob job(spec, settings(threads));
  job.system().run(steps);
  return save_checkpoint(job);
}

// Loads `bytes` into a new job of `spec` and returns the CheckpointError's message.
std::string load_error(const std::string& bytes, const TwistJobSpec& spec, int threads) {
  TwistJob job(spec, settings(threads));
  try {
    load_checkpoint(job, bytes);
  } catch (const CheckpointError& e) {
    return e.what();
  }
  ADD_FAILURE() << "loading did not throw CheckpointError";
  return {};
}

TEST(Checkpoint, TruncatedBytesAreRefused) {
  const std::string bytes = checkpoint_after_steps(small_spec(), 2);
  for (std::size_t len : {std::size_t{0}, std::size_t{5}, std::size_t{30}, std::size_t{200},
                          bytes.size() / 3, bytes.size() / 2, bytes.size() - 1}) {
    const std::string m = load_error(bytes.substr(0, len), small_spec(), 2);
    EXPECT_NE(m.find("truncated"), std::string::npos) << len << ": " << m;
  }
}

TEST(Checkpoint, ForeignOrDamagedBytesAreRefused) {
  const std::string bytes = checkpoint_after_steps(small_spec(), 2);
  std::string bad = bytes;
  bad[0] ^= 1;
  EXPECT_NE(load_error(bad, small_spec(), 2).find("not an mdem checkpoint"), std::string::npos);
  bad = bytes;
  bad[8] ^= 0x40;  // the version
  EXPECT_NE(load_error(bad, small_spec(), 2).find("format version"), std::string::npos);
  const std::string m = load_error(bytes + "x", small_spec(), 2);
  EXPECT_NE(m.find("1 unread bytes"), std::string::npos) << m;
}

TEST(Checkpoint, CheckpointOfAnotherRopeIsRefused) {
  TwistJobSpec other = small_spec();
  other.rope.segments = 12;
  const std::string m = load_error(checkpoint_after_steps(other, 2), small_spec(), 2);
  EXPECT_NE(m.find("checkpoint holds 84 elements, this job builds 70"), std::string::npos) << m;
}

TEST(Checkpoint, CheckpointOfAnotherLoadingIsRefused) {
  TwistJobSpec other = small_spec();
  other.loading.torque_max = units::nNnm(3.0);
  const std::string m = load_error(checkpoint_after_steps(other, 2), small_spec(), 2);
  EXPECT_NE(m.find("twist loading"), std::string::npos) << m;
}

TEST(Checkpoint, CheckpointOfAnotherGripHoldIsRefused) {
  TwistJobSpec clamped = small_spec(TwistBoundary::TwistRelaxation);
  clamped.loading.grip_hold = GripHold::PositionsAndSpins;
  const std::string m =
      load_error(checkpoint_after_steps(small_spec(TwistBoundary::TwistRelaxation), 2), clamped, 2);
  EXPECT_NE(m.find("grip hold"), std::string::npos) << m;
}

TEST(Checkpoint, AnotherThreadCountIsRefused) {
  const std::string m = load_error(checkpoint_after_steps(small_spec(), 2), small_spec(), 1);
  EXPECT_NE(m.find("2 threads, this system runs 1"), std::string::npos) << m;
  EXPECT_NE(m.find("same thread count"), std::string::npos) << m;
}

TEST(StateIo, PrimitivesRoundTrip) {
  StateWriter w;
  write_header(w);
  w.begin("numbers");
  w.put(3.25);
  w.put(-7L);
  w.put(42);
  w.put(true);
  w.put(std::uint32_t{0xDEADBEEF});
  w.put_string("rope");
  w.begin("arrays");
  const std::vector<Vec3> xs = {Vec3(1, 2, 3), Vec3(-0.0, 1e-300, 4)};
  const std::vector<Quat> qs = {Quat(0.5, 0.5, -0.5, 0.5)};
  const std::vector<std::array<DofMode, 6>> dofs = {{DofMode::Free, DofMode::Fixed,
                                                     DofMode::Prescribed, DofMode::Free,
                                                     DofMode::Free, DofMode::Fixed}};
  const std::vector<double> none;
  w.put(xs);
  w.put(qs);
  w.put(dofs);
  w.put(none);

  StateReader r(w.bytes());
  read_header(r);
  r.begin("numbers");
  EXPECT_EQ(r.get<double>("d"), 3.25);
  EXPECT_EQ(r.get<long>("l"), -7L);
  EXPECT_EQ(r.get<int>("i"), 42);
  EXPECT_TRUE(r.get_bool("b"));
  EXPECT_EQ(r.get<std::uint32_t>("u"), 0xDEADBEEFu);
  EXPECT_EQ(r.get_string("s"), "rope");
  r.begin("arrays");
  std::vector<Vec3> xs2;
  std::vector<Quat> qs2;
  std::vector<std::array<DofMode, 6>> dofs2;
  std::vector<double> none2 = {1.0};
  r.get(xs2, "xs", 2);
  r.get(qs2, "qs");
  r.get(dofs2, "dofs", 1);
  r.get(none2, "none", 0);
  EXPECT_TRUE(same_bits(xs, xs2));
  EXPECT_TRUE(same_bits(qs, qs2));
  EXPECT_EQ(dofs, dofs2);
  EXPECT_TRUE(none2.empty());
  r.expect_end();
}

// Reads one vector from `bytes` and returns the CheckpointError's message.
std::string vector_error(const std::string& bytes, std::size_t expected) {
  StateReader r(bytes);
  std::vector<Vec3> v;
  try {
    r.begin("data");
    r.get(v, "positions", expected);
  } catch (const CheckpointError& e) {
    return e.what();
  }
  ADD_FAILURE() << "reading did not throw CheckpointError";
  return {};
}

TEST(StateIo, CorruptLengthsThrowWithoutAllocating) {
  StateWriter w;
  w.begin("data");
  w.put(std::numeric_limits<std::uint64_t>::max());  // a length prefix of 2^64 - 1 entries
  w.put(1.0);
  const std::string m = vector_error(w.bytes(), std::numeric_limits<std::size_t>::max());
  EXPECT_NE(m.find("section 'data', field 'positions': claims 18446744073709551615 entries"),
            std::string::npos)
      << m;

  StateWriter w2;
  w2.begin("data");
  w2.put(std::vector<Vec3>(3, Vec3::Zero()));
  EXPECT_NE(vector_error(w2.bytes(), 4).find("holds 3 entries, this job has 4"), std::string::npos);

  StateWriter w3;
  w3.begin("other");
  EXPECT_NE(vector_error(w3.bytes(), 0).find("expected section 'data' at byte 0, found 'other'"),
            std::string::npos);

  // A huge string length: refused before any allocation.
  StateWriter w4;
  w4.put(std::uint64_t{1} << 62);
  StateReader r4(w4.bytes());
  EXPECT_THROW(r4.get_string("name"), CheckpointError);
  // Garbage where a section marker belongs.
  StateReader r5(std::string(64, '\x7f'));
  try {
    r5.begin("data");
    ADD_FAILURE() << "no throw";
  } catch (const CheckpointError& e) {
    EXPECT_NE(std::string(e.what()).find("no section marker"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mdem
