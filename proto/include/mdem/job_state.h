#pragma once
// Job states, one enum end to end (mdem.v1.JobState): the daemon's events and database, `mdem
// run`, the client's results database and reports all name a state through these.
#include <optional>
#include <string>
#include <string_view>

#include "mdem/v1/job.pb.h"

namespace mdem {

using v1::JobState;

// "QUEUED", "RUNNING", "SUCCEEDED", "FAILED", "CANCELLED", "INTERRUPTED", "TIMEOUT";
// JOB_STATE_UNSPECIFIED reads as "QUEUED" (a daemon that has not said yet).
std::string job_state_name(JobState s);
// The state named (exactly as job_state_name writes it), or nullopt.
std::optional<JobState> parse_job_state(std::string_view name);
// Whether a database may hold the state: every state but INTERRUPTED (derived when shown) and
// the unspecified one.
bool is_stored(JobState s);
// Whether the job has ended (SUCCEEDED, FAILED, CANCELLED, TIMEOUT): nothing more will happen
// to it unless asked (a TIMEOUT job is queued again by `mdem resume`, from its checkpoint).
bool is_final(JobState s);
// The same for a state's name; false for a name that is no state.
bool is_final(std::string_view name);
// "QUEUED, RUNNING, SUCCEEDED, FAILED, CANCELLED, INTERRUPTED, TIMEOUT", for messages.
std::string job_state_names();

}  // namespace mdem
