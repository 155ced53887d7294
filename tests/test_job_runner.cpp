// The shared job runner (jobs/): what `mdem run` and mdemd do before a run must not change the
// run. A compression job packs its particle in a first stage on a system of its own, set up at
// the grains' shrunk start size; checking the job's time step before anything is stored must
// leave that system alone, so the job packs as an unchecked one does and reaches equilibrium.
#include <gtest/gtest.h>

#include <cstring>

#include "mdem/job/compression_job.h"
#include "mdem/job_runner.h"
#include "mdem/spec.h"

namespace {

using namespace mdem;

// The default compression job (`mdem run compression`: an Au sphere of R = 10 nm), one thread.
v1::JobSpec default_compression() {
  v1::JobSpec s;
  s.mutable_compression();
  s.mutable_run()->set_threads(1);
  s.mutable_outputs()->set_snapshot_every_ps(0);
  return spec::finalize(s);
}

bool same_bits(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec3)) == 0);
}

TEST(JobRunner, CheckingTheTimeStepLeavesAPackingStageAlone) {
  const v1::JobSpec spec = default_compression();

  JobRunner plain(spec);
  const JobOutcome a = plain.run({}, {});
  ASSERT_EQ(a.state, v1::SUCCEEDED) << a.reason;

  JobRunner checked(spec);
  check_time_step(checked.job());  // what `mdem run` and the daemon do before storing the job
  const JobOutcome b = checked.run({}, {});
  ASSERT_EQ(b.state, v1::SUCCEEDED) << b.reason;

  const auto& pa = dynamic_cast<CompressionJob&>(plain.job()).packing();
  const auto& pb = dynamic_cast<CompressionJob&>(checked.job()).packing();
  // The packing reached the equilibrium its spec asks for, and is the unchecked job's bit for bit.
  EXPECT_LT(pb.unbalanced_ratio, PackingSpec{}.tolerance);
  EXPECT_EQ(pb.steps, pa.steps);
  EXPECT_TRUE(same_bits(pb.grains.x, pa.grains.x));
  EXPECT_EQ(pb.touching, pa.touching);
  EXPECT_EQ(b.steps, a.steps);
}

}  // namespace
