// System::memory_bytes, the daemon's per-job memory figure (issue 16, "peak memory in ls/show"):
// against a hand count of the arrays a system must hold for N elements (the element arrays, the
// integrator's per-element work arrays, one force/torque buffer per thread, a bond per bond and a
// 4-byte index per listed neighbour pair), it is at least that (capacities are at least sizes)
// and within a factor 2.5 of it (vector growth, the neighbour search's scratch), and it grows with
// the element count.
#include <gtest/gtest.h>

#include <cstdio>

#include "mdem/force/bond/parallel_bond.h"
#include "mdem/job/job.h"
#include "mdem/neighbor/neighbor_list.h"
#include "mdem/spec.h"
#include "mdem/spec_job.h"

namespace {

using mdem::System;

// Bytes per element the arrays of Elements hold, counted by hand from elements.h: tag 8; x, v, w,
// inertia, v_prescribed, w_prescribed, f_ext, t_ext, f, t: 10 Vec3 of 24; q 32; mass, inv_mass,
// radius 3 x 8; kind 1; tube, index 2 x 4; dof 6.
constexpr std::size_t kElementBytes = 8 + 10 * 24 + 32 + 3 * 8 + 1 + 2 * 4 + 6;
// The integrator's own per-element arrays: damping force and torque, the previous step's forces,
// torques, external forces and torques (6 Vec3), and the force sink's force and torque per thread.
constexpr std::size_t kSystemBytes = 6 * 24;
constexpr std::size_t kSinkBytesPerThread = 2 * 24;

mdem::v1::JobSpec twist(int layers) {
  mdem::v1::JobSpec s;
  s.set_seed(7);
  auto* t = s.mutable_twist();
  t->set_layers(layers);
  t->set_length_nm(13.56);
  t->set_torque_nn_nm(2);
  t->set_hold_ps(1);
  return s;
}

struct Counted {
  std::size_t n = 0, measured = 0, hand = 0;
};

Counted count(int layers) {
  std::unique_ptr<mdem::Job> job = mdem::make_spec_job(mdem::spec::finalize(twist(layers)), 1);
  System& sys = job->system();
  sys.initialize();
  sys.run(50);
  Counted c;
  c.n = sys.elements().size();
  std::size_t bonds = 0, pairs = 0;
  if (const auto* pb = sys.find<mdem::ParallelBond>()) bonds = pb->bonds().size();
  for (const auto& e : sys.pair_table().entries()) pairs += e.list->pair_count();
  c.hand = c.n * (kElementBytes + kSystemBytes + kSinkBytesPerThread * sys.threads()) +
           bonds * sizeof(mdem::Bond) + pairs * sizeof(std::uint32_t);
  c.measured = sys.memory_bytes();
  return c;
}

TEST(MemoryBytes, WithinAFactorOfAHandCountAndGrowingWithTheElements) {
  const Counted small = count(2), large = count(4);
  ASSERT_GT(large.n, small.n);
  for (const Counted& c : {small, large}) {
    std::printf("%zu elements: %zu bytes measured, %zu counted by hand (ratio %.2f)\n", c.n,
                c.measured, c.hand, static_cast<double>(c.measured) / c.hand);
    EXPECT_GE(c.measured, c.hand) << c.n << " elements";
    EXPECT_LE(static_cast<double>(c.measured), 2.5 * static_cast<double>(c.hand))
        << c.n << " elements";
  }
  EXPECT_GT(large.measured, small.measured);
  // Per element, the two agree to the factor too: the figure scales with N, not a constant.
  const double per_small = static_cast<double>(small.measured) / small.n,
               per_large = static_cast<double>(large.measured) / large.n;
  EXPECT_LT(std::max(per_small, per_large) / std::min(per_small, per_large), 2.5);
}

}  // namespace
