#pragma once
// The study a submitted job says it belongs to (SubmitJobRequest.study) and the study id a
// ListJobs asks for, checked before anything is stored: an id of the client's form, a run index,
// the varied fields' names and finite values. Each check returns "" when the input is allowed,
// else one line naming the field, what is wrong and what is allowed.
#include <string>

#include "mdem/v1/service.pb.h"

namespace mdem::server {

inline constexpr std::size_t kMaxStudyIdLength = 64;
inline constexpr int kMaxStudyRun = 9999;
inline constexpr int kMaxStudyValues = 16;
inline constexpr std::size_t kMaxStudyFieldLength = 128;

// `field` names the request field in the message ("study.study_id", "study_id").
std::string study_id_problem(const std::string& id, const std::string& field);
// A submit's study: unset (no study id, no run, no values) or a complete one.
std::string study_run_problem(const v1::StudyRun& study);

}  // namespace mdem::server
