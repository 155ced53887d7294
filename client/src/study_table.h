#pragma once
// A study's table: its runs read back from the results database (each job's report), the
// errors of the kind's results (study_errors.h), the rows stored in the study tables, and the
// table in words or JSON. Shared by `mdem study` (after its runs), `mdem study show`, `mdem
// watch --study` and `mdem plot` of a study.
#include <ostream>
#include <string>
#include <vector>

#include "flags.h"
#include "results_store.h"
#include "study_errors.h"
#include "study_store.h"
#include "study_vary.h"

namespace mdem::cli {

struct StudyTable {
  StudyRecord study;
  std::vector<VariedField> fields;  // from vary_json
  std::vector<StudyRunRecord> records;
  std::vector<StudyRun> runs;       // as records; a job not (yet) finished counts as not succeeded
  std::vector<std::string> states;  // each run's job state
  std::vector<SummaryField> results;  // the kind's results
  StudyErrors errors;                 // empty results when no run succeeded
  std::string reference;              // how the references were made, in words
};

// The varied fields of vary_json; vary_json of the fields.
std::vector<VariedField> varied_fields(const std::string& vary_json);
std::string vary_json(const std::vector<VariedField>& fields);

// Reads the study's runs from the jobs table and computes the errors; StoreError for a job the
// database does not hold.
StudyTable study_table(const ResultsStore& jobs, const StudyStore& studies,
                       const StudyRecord& study, ReferenceMode mode = ReferenceMode::Auto);
// Stores the table's errors (study_errors) and its reference text.
void store_errors(StudyStore& studies, const StudyTable& t);

// The table in words: one row per run (the varied values, job, state, wall time, energy-balance
// error, each result's value and error), then the reference and observed order of each result.
void print_study_table(std::ostream& out, const StudyTable& t);
json study_table_json(const StudyTable& t);

}  // namespace mdem::cli
