#include "study_remote.h"

#include <algorithm>
#include <limits>

#include "flags.h"
#include "mdem/cli.h"
#include "mdem/job_state.h"
#include "mdem/spec.h"
#include "remote_commands.h"
#include "study_table.h"

namespace mdem::cli {
namespace {

// The most jobs one ListJobs returns; a study has at most kMaxStudyRuns.
constexpr int kListLimit = 1000;

// The run's varied values in the order of `fields` (NaN for one the tag lacks).
std::vector<double> point_of(const v1::StudyRun& tag, const std::vector<VariedField>& fields) {
  std::vector<double> point(fields.size(), std::numeric_limits<double>::quiet_NaN());
  for (const v1::StudyValue& v : tag.values())
    for (std::size_t i = 0; i < fields.size(); ++i)
      if (fields[i].path == v.field()) point[i] = v.value();
  return point;
}

// The varied fields of the study's jobs: the fields of its first run, each with its values in
// the order the runs took them.
std::vector<VariedField> fields_of(const std::vector<v1::JobInfo>& jobs) {
  std::vector<VariedField> fields;
  for (const v1::StudyValue& v : jobs.front().study().values())
    fields.push_back({v.field(), integer_field(v.field()), {}});
  for (const v1::JobInfo& j : jobs)
    for (const v1::StudyValue& v : j.study().values())
      for (VariedField& f : fields)
        if (f.path == v.field() &&
            std::find(f.values.begin(), f.values.end(), v.value()) == f.values.end())
          f.values.push_back(v.value());
  return fields;
}

}  // namespace

v1::StudyRun study_run_tag(const std::string& study_id, int run,
                           const std::vector<VariedField>& fields,
                           const std::vector<double>& point) {
  v1::StudyRun tag;
  tag.set_study_id(study_id);
  tag.set_run(run);
  for (std::size_t i = 0; i < fields.size() && i < point.size(); ++i) {
    v1::StudyValue* v = tag.add_values();
    v->set_field(fields[i].path);
    v->set_value(point[i]);
  }
  return tag;
}

std::vector<v1::JobInfo> daemon_study_jobs(JobClient& client, const std::string& study_id) {
  const v1::ListJobsResponse r = client.list(false, kListLimit, study_id);
  std::vector<v1::JobInfo> jobs(r.jobs().begin(), r.jobs().end());
  std::sort(jobs.begin(), jobs.end(), [](const v1::JobInfo& a, const v1::JobInfo& b) {
    return a.study().run() < b.study().run();
  });
  return jobs;
}

StudyRecord take_daemon_study(JobClient& client, ResultsStore& jobs, StudyStore& studies,
                              const std::string& study_id) {
  if (std::optional<StudyRecord> here = studies.find(study_id)) return *here;
  const std::vector<v1::JobInfo> remote = daemon_study_jobs(client, study_id);
  if (remote.empty())
    throw StoreError("no study '" + study_id + "' in " + jobs.path() + " nor among your jobs on " +
                     "mdemd at " + client.settings().server + " (`mdem ls --server " +
                     client.settings().server + "` lists them)");
  StudyRecord s;
  s.id = study_id;
  s.kind = remote.front().kind();
  s.spec_json = spec::to_json(remote.front().spec(), false);
  const std::vector<VariedField> fields = fields_of(remote);
  s.vary_json = vary_json(fields);
  s.server = client.settings().server;
  for (const v1::JobInfo& j : remote)
    if (j.kind() != s.kind)
      throw StoreError("the study '" + study_id + "' on mdemd at " + s.server + " mixes kinds (" +
                       s.kind + ", " + j.kind() + "): not a study mdem made");
  for (const v1::JobInfo& j : remote)
    if (!jobs.find(j.job_id())) jobs.upsert_remote_job(record_of(j, client.settings()));
  studies.create_study(s);
  for (const v1::JobInfo& j : remote)
    studies.add_run(s.id, {j.study().run(), j.job_id(), json(point_of(j.study(), fields)).dump()});
  return *studies.find(s.id);
}

int print_daemon_study(JobClient& client, const std::string& study_id, bool as_json,
                       std::ostream& out, std::ostream& err) {
  const std::vector<v1::JobInfo> remote = daemon_study_jobs(client, study_id);
  const std::vector<VariedField> fields =
      remote.empty() ? std::vector<VariedField>{} : fields_of(remote);
  if (as_json) {
    json all = json::array();
    for (const v1::JobInfo& j : remote)
      all.push_back({{"job_id", j.job_id()},
                     {"run", j.study().run()},
                     {"point", point_of(j.study(), fields)},
                     {"state", job_state_name(j.state())},
                     {"step", j.step()},
                     {"total_steps", j.total_steps()}});
    out << all.dump(2) << "\n";
    return kOk;
  }
  if (remote.empty()) {
    err << "no study '" << study_id << "' among your jobs on mdemd at " << client.settings().server
        << "\n";
    return kOk;
  }
  std::vector<std::vector<std::string>> rows = {{"RUN", "VALUES", "ID", "STATE", "DONE"}};
  for (const v1::JobInfo& j : remote)
    rows.push_back({std::to_string(j.study().run()),
                    point_text(fields, point_of(j.study(), fields)), j.job_id(),
                    job_state_name(j.state()),
                    std::to_string(j.step()) + "/" + std::to_string(j.total_steps())});
  out << "study " << study_id << " (" << remote.front().kind() << ") on mdemd at "
      << client.settings().server << "\n";
  print_table(out, rows);
  return kOk;
}

}  // namespace mdem::cli
