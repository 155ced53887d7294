#include "mdem/job_state.h"

namespace mdem {

namespace {
constexpr JobState kStates[] = {v1::QUEUED,    v1::RUNNING,     v1::SUCCEEDED, v1::FAILED,
                                v1::CANCELLED, v1::INTERRUPTED, v1::TIMEOUT};
}  // namespace

std::string job_state_name(JobState s) {
  return s == v1::JOB_STATE_UNSPECIFIED ? "QUEUED" : v1::JobState_Name(s);
}

std::optional<JobState> parse_job_state(std::string_view name) {
  for (const JobState s : kStates)
    if (job_state_name(s) == name) return s;
  return std::nullopt;
}

bool is_stored(JobState s) { return s != v1::JOB_STATE_UNSPECIFIED && s != v1::INTERRUPTED; }

bool is_final(JobState s) {
  return s == v1::SUCCEEDED || s == v1::FAILED || s == v1::CANCELLED || s == v1::TIMEOUT;
}

bool is_final(std::string_view name) {
  const std::optional<JobState> s = parse_job_state(name);
  return s && is_final(*s);
}

std::string job_state_names() {
  std::string s;
  for (const JobState st : kStates) s += (s.empty() ? "" : ", ") + job_state_name(st);
  return s;
}

}  // namespace mdem
