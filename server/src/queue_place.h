#pragma once
// Why a queued job waits, as Slurm's squeue says it: its place in the queue and the limit that
// holds it (every worker busy), naming the jobs ahead of it and running (a job of another user
// as "another user's job", unless the caller is an admin).
#include <string>
#include <vector>

#include "job_store.h"
#include "mdem/v1/service.pb.h"
#include "tokens.h"

namespace mdem::server {

// Sets queue_position and waiting_for of `info` when it is QUEUED. `queue`: the queued jobs in
// the order they will start (JobStore::queue); `running`: the running ones; `workers`: how many
// jobs run at once.
void describe_wait(v1::JobInfo& info, const std::vector<JobOwner>& queue,
                   const std::vector<JobOwner>& running, int workers, const Identity& who);

}  // namespace mdem::server
