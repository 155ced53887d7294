// The force sink: per-thread buffers summed in thread order, zeroed as they are read, so the next
// evaluation starts from zero without a separate pass (and with one after an evaluation that was
// not reduced).
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "mdem/force/force_model.h"

using namespace mdem;

namespace {

// Writes thread k's contribution to element i: distinct small integers, so sums are exact.
void write(ForceSink& sink, std::size_t n, double base) {
  for (int k = 0; k < sink.threads(); ++k)
    for (std::size_t i = 0; i < n; ++i) {
      const double v = base + 10.0 * k + static_cast<double>(i);
      sink.force(k)[i] += Vec3(v, -v, 2 * v);
      sink.torque(k)[i] += Vec3(-v, 3 * v, v);
      sink.damping_force(k)[i] += Vec3(v, 0, -v);
      sink.damping_torque(k)[i] += Vec3(0, v, 0);
      sink.energy(k).add(EnergyTerm::Vdw, v);
    }
}

// The sum over threads 0..nt-1 of write()'s value for element i.
double expected(int nt, std::size_t i, double base) {
  double s = 0;
  for (int k = 0; k < nt; ++k) s += base + 10.0 * k + static_cast<double>(i);
  return s;
}

void expect_sums(ForceSink& sink, std::size_t n, double base) {
  const int nt = sink.threads();
  std::vector<Vec3> f(n), t(n), fd(n), td(n);
  const EnergyTally e = sink.reduce(f, t, fd, td);
  double e_sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double v = expected(nt, i, base);
    e_sum += v;
    EXPECT_EQ(f[i], Vec3(v, -v, 2 * v)) << i;
    EXPECT_EQ(t[i], Vec3(-v, 3 * v, v)) << i;
    EXPECT_EQ(fd[i], Vec3(v, 0, -v)) << i;
    EXPECT_EQ(td[i], Vec3(0, v, 0)) << i;
  }
  EXPECT_EQ(e.stored[static_cast<int>(EnergyTerm::Vdw)], e_sum);
  // Every buffer entry was zeroed as it was read.
  for (int k = 0; k < nt; ++k)
    for (std::size_t i = 0; i < n; ++i) {
      EXPECT_EQ(sink.force(k)[i], Vec3::Zero());
      EXPECT_EQ(sink.torque(k)[i], Vec3::Zero());
      EXPECT_EQ(sink.damping_force(k)[i], Vec3::Zero());
      EXPECT_EQ(sink.damping_torque(k)[i], Vec3::Zero());
    }
}

}  // namespace

TEST(ForceSink, ReduceSumsTheThreadsAndLeavesTheBuffersZero) {
  const std::size_t n = 3000;  // above the parallel threshold: the threaded reduction runs
  for (int nt : {1, 2, 3}) {
    ForceSink sink;
    sink.resize(n, nt, true);
    sink.clear();
    write(sink, n, 1.0);
    expect_sums(sink, n, 1.0);
    // The next evaluation sees only its own contributions, and fresh energies.
    sink.clear();
    write(sink, n, 7.0);
    expect_sums(sink, n, 7.0);
  }
}

TEST(ForceSink, ClearAfterAnEvaluationThatWasNotReducedZeroesTheBuffers) {
  // A model that stopped midway (an exception) left its partial forces: the next clear() must
  // remove them, although the reduce() before had left the buffers zero.
  const std::size_t n = 100;
  ForceSink sink;
  sink.resize(n, 2, true);
  sink.clear();
  write(sink, n, 1.0);
  expect_sums(sink, n, 1.0);
  sink.clear();
  write(sink, n, 5.0);  // never reduced
  sink.clear();
  write(sink, n, 3.0);
  expect_sums(sink, n, 3.0);
}

TEST(ForceSink, SecondReduceWithoutAnEvaluationGivesZero) {
  const std::size_t n = 10;
  ForceSink sink;
  sink.resize(n, 2, false);
  sink.clear();
  sink.force(1)[4] = Vec3(1, 2, 3);
  std::vector<Vec3> f(n), t(n), fd, td;
  sink.reduce(f, t, fd, td);
  EXPECT_EQ(f[4], Vec3(1, 2, 3));
  sink.reduce(f, t, fd, td);
  EXPECT_EQ(f[4], Vec3::Zero());
}

// Damping force buffers without damping torque buffers (no dissipative model writes torques):
// reduce() and take() give zero damping torques, the other sums as with them, and asking for the
// absent buffers names the cause instead of handing out memory.
TEST(ForceSink, WithoutDampingTorqueBuffersTheDampingTorquesAreZero) {
  const std::size_t n = 3000;
  for (int nt : {1, 2}) {
    ForceSink with, without;
    with.resize(n, nt, true, true);
    without.resize(n, nt, true, false);
    EXPECT_TRUE(without.has_damping());
    EXPECT_FALSE(without.has_damping_torque());
    EXPECT_LT(without.memory_bytes(), with.memory_bytes());
    EXPECT_THROW(without.damping_torque(0), std::logic_error);
    without.clear();
    for (int k = 0; k < nt; ++k)
      for (std::size_t i = 0; i < n; ++i) {
        without.force(k)[i] += Vec3(1.0 + k, 2.0, 3.0);
        without.damping_force(k)[i] += Vec3(0.5, -1.0, 2.0 * k);
      }
    std::vector<Vec3> f(n), t(n), fd(n), td(n, Vec3(9, 9, 9));
    without.reduce(f, t, fd, td);
    const double nk = nt;
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_EQ(f[i], Vec3(nk + (nt == 2 ? 1.0 : 0.0), 2.0 * nk, 3.0 * nk)) << i;
      ASSERT_EQ(fd[i], Vec3(0.5 * nk, -nk, nt == 2 ? 2.0 : 0.0)) << i;
      ASSERT_EQ(td[i], Vec3::Zero()) << i;
    }
    // take(), element by element, as the integrator's pass does.
    without.clear();
    without.damping_force(nt - 1)[7] += Vec3(1, 2, 3);
    Vec3 fi, ti, fdi, tdi(9, 9, 9);
    without.take(7, fi, ti, &fdi, &tdi);
    EXPECT_EQ(fdi, Vec3(1, 2, 3));
    EXPECT_EQ(tdi, Vec3::Zero());
  }
}
