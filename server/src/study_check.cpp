#include "study_check.h"

#include <cmath>
#include <regex>

namespace mdem::server {
namespace {

// A caller's text quoted in a message: never a huge one.
std::string quoted(const std::string& s) {
  constexpr std::size_t kShown = 80;
  return "'" + (s.size() > kShown
                    ? s.substr(0, kShown) + "...' (" + std::to_string(s.size()) + " characters)"
                    : s + "'");
}

}  // namespace

std::string study_id_problem(const std::string& id, const std::string& field) {
  static const std::regex re("s-[A-Za-z0-9._-]{1,62}");
  if (id.size() <= kMaxStudyIdLength && std::regex_match(id, re)) return "";
  return field + ": " + quoted(id) + " is not a study id (allowed: 3.." +
         std::to_string(kMaxStudyIdLength) +
         " characters of [A-Za-z0-9._-] starting with 's-', as `mdem study` prints)";
}

std::string study_run_problem(const v1::StudyRun& study) {
  if (study.study_id().empty()) {
    if (study.run() != 0 || study.values_size() > 0)
      return "study: a run index or varied values without study.study_id (allowed: a complete "
             "study, or no study at all)";
    return "";
  }
  if (std::string p = study_id_problem(study.study_id(), "study.study_id"); !p.empty()) return p;
  if (study.run() < 0 || study.run() > kMaxStudyRun)
    return "study.run: " + std::to_string(study.run()) + " is out of range (allowed: 0.." +
           std::to_string(kMaxStudyRun) + ")";
  if (study.values_size() < 1 || study.values_size() > kMaxStudyValues)
    return "study.values: " + std::to_string(study.values_size()) + " varied fields (allowed: 1.." +
           std::to_string(kMaxStudyValues) + ")";
  static const std::regex field_re("[a-z0-9_.]+");
  for (int i = 0; i < study.values_size(); ++i) {
    const v1::StudyValue& v = study.values(i);
    const std::string where = "study.values[" + std::to_string(i) + "]";
    if (v.field().empty() || v.field().size() > kMaxStudyFieldLength ||
        !std::regex_match(v.field(), field_re))
      return where + ".field: " + quoted(v.field()) + " is not a spec field's path (allowed: 1.." +
             std::to_string(kMaxStudyFieldLength) + " characters of [a-z0-9_.], e.g. run.safety)";
    if (!std::isfinite(v.value()))
      return where + ".value: " + std::to_string(v.value()) + " for " + v.field() +
             " is not finite (allowed: a finite number)";
  }
  return "";
}

}  // namespace mdem::server
