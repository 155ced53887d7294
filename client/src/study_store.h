#pragma once
// Studies in the local results database: beside the jobs (results_store.h) the tables studies
// (one row per study: kind, base spec, what is varied, the reference used), study_runs (its
// jobs, one per point) and study_errors (each run's error of each result, with the run's wall
// time and energy-balance error). docs/results.md describes them. The tables are created when
// missing, so a database of an older mdem gains them and loses nothing.
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace mdem::cli {

struct StudyRecord {
  std::string id;         // "s-20261201-233012-3f9a"
  std::string kind;       // "twist"
  std::string spec_json;  // the base spec (finalized)
  std::string vary_json;  // [{"field": "run.safety", "values": [0.6, 0.3, 0.15]}, ...]
  std::string server;     // the mdemd that runs its jobs; "" for a study run here
  std::string created_at;
  std::string reference;  // how the errors were computed (words); "" until computed
};

struct StudyRunRecord {
  int seq = 0;  // the point's index, in the order the runs were made
  std::string job_id;
  std::string point_json;  // the varied values, in vary order: [0.3]
};

// One run's error of one result (NaN stored as NULL and read back as NaN).
struct StudyErrorRow {
  int seq = 0;
  std::string result;  // the summary key: "twist_angle_deg"
  std::string unit;
  double value = 0, reference = 0, error = 0, relative_error = 0, order = 0;
  bool extrapolated = false;
  double wall_s = 0, balance_error = 0;
};

class StudyStore {
 public:
  // Opens the results database at `path` (which ResultsStore has created) and adds the study
  // tables if missing. Throws StoreError.
  explicit StudyStore(const std::string& path);
  ~StudyStore();
  StudyStore(const StudyStore&) = delete;
  StudyStore& operator=(const StudyStore&) = delete;

  static std::string new_study_id();

  void create_study(const StudyRecord& s);
  void add_run(const std::string& study_id, const StudyRunRecord& run);
  // Replaces the study's errors and its reference text, in one transaction.
  void set_errors(const std::string& study_id, const std::string& reference,
                  const std::vector<StudyErrorRow>& rows);

  std::vector<StudyRecord> list() const;
  // The study with this id, or the only one whose id starts with it; nullopt when none;
  // StoreError when the prefix is ambiguous.
  std::optional<StudyRecord> find(const std::string& id_or_prefix) const;
  std::vector<StudyRunRecord> runs(const std::string& study_id) const;
  std::vector<StudyErrorRow> errors(const std::string& study_id) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Whether `id` names a study ("s-...") rather than a job ("j-...").
bool is_study_id(const std::string& id);

}  // namespace mdem::cli
