#pragma once
// A study on mdemd: each run is submitted with its study id and varied values
// (SubmitJobRequest.study), so the daemon knows the study and any client of the same user can
// list it (ListJobs study_id), take it into its own results database, follow and cancel it.
#include <map>
#include <ostream>
#include <string>
#include <vector>

#include "mdem/v1/service.pb.h"
#include "remote.h"
#include "results_store.h"
#include "study_store.h"
#include "study_vary.h"

namespace mdem::cli {

// The study tag of one run: its study id, index and the point's values by field path.
v1::StudyRun study_run_tag(const std::string& study_id, int run,
                           const std::vector<VariedField>& fields,
                           const std::vector<double>& point);

// The daemon's jobs of the study (the caller's), in run order. RemoteError from the daemon
// (INVALID_ARGUMENT for a malformed id); an empty list when it has none.
std::vector<v1::JobInfo> daemon_study_jobs(JobClient& client, const std::string& study_id);

// The study as the daemon knows it, recorded in the local database (the study, its runs and
// their jobs, each job with the daemon to watch it from), unless already there; returns it.
// StoreError naming the database and the daemon when neither holds the study.
StudyRecord take_daemon_study(JobClient& client, ResultsStore& jobs, StudyStore& studies,
                              const std::string& study_id);

// `mdem ls --study ID --server HOST:PORT`: the study's jobs as the daemon lists them (run,
// varied values, job id, state, elapsed progress); a JSON array with as_json.
int print_daemon_study(JobClient& client, const std::string& study_id, bool as_json,
                       std::ostream& out, std::ostream& err);

}  // namespace mdem::cli
