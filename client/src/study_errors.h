#pragma once
// The errors of a study's results: each result of the kind (SummaryField::result) compared with
// a reference - Richardson's extrapolation from the three most accurate runs when one setting
// is varied at a constant refinement ratio and the differences shrink (the observed order from
// those three runs), else the most accurate run itself (the run with the most element-steps:
// the smallest step, the slowest loading; with multiple time stepping, outer steps). Pure
// numbers: no database, no jobs.
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "mdem/job_kinds.h"

namespace mdem::cli {

// Richardson's extrapolation of f(h) = f* + C h^p from f at h (coarse), h/r and h/r² (fine).
struct Richardson {
  double order;  // p = ln((f_c - f_m) / (f_m - f_f)) / ln r
  double limit;  // f* = f_f + (f_f - f_m) / (r^p - 1)
};
// nullopt when the two differences do not have the same sign or one is zero (no asymptotic
// range to extrapolate from), or r <= 1, or a value is not finite.
std::optional<Richardson> richardson(double f_coarse, double f_mid, double f_fine, double r);

// One run of a study as the analysis sees it.
struct StudyRun {
  std::string job_id;
  std::vector<double> point;  // the varied values
  bool succeeded = false;
  double wall_s = 0;
  double element_steps =
      0;  // elements x steps / respa_k: the resolution that orders runs by accuracy
  double balance_error = 0;               // the run's energy-balance error (NaN: none)
  std::map<std::string, double> results;  // result key -> value
};

enum class ReferenceMode { Auto, Finest };

struct ResultError {
  SummaryField field;
  double reference = 0;          // NaN: no successful run has this result
  bool extrapolated = false;     // the reference is Richardson's, not the finest run's value
  double order = 0;              // the observed order (NaN when not measured)
  std::vector<double> error;     // per run: |f - reference| in the result's unit (NaN: none)
  std::vector<double> relative;  // per run: error / |reference| (NaN when reference is 0)
};

struct StudyErrors {
  std::size_t finest = 0;                    // index of the most accurate successful run
  std::vector<std::size_t> richardson_runs;  // coarse, mid, fine (empty: not used)
  double ratio = 0;                          // their refinement ratio (0: none)
  std::string note;                          // why Richardson was not used, when it was not
  std::vector<ResultError> results;
};

// `varied`: the one varied setting's value per run, when exactly one is varied (empty
// otherwise; Richardson then is not used). `results`: the kind's result fields.
// std::invalid_argument when no run succeeded.
StudyErrors study_errors(const std::vector<StudyRun>& runs, const std::vector<double>& varied,
                         const std::vector<SummaryField>& results,
                         ReferenceMode mode = ReferenceMode::Auto);

}  // namespace mdem::cli
