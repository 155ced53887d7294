// A study's table from the results database.
#include "study_table.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include "mdem/spec_rules.h"

namespace mdem::cli {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string num(double v, int digits = 6) {
  if (!std::isfinite(v)) return "-";
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

double number_at(const json& doc, const char* section, const char* key) {
  if (!doc.is_object() || !doc.contains(section)) return kNaN;
  const json& s = doc[section];
  return s.is_object() && s.contains(key) && s[key].is_number() ? s[key].get<double>() : kNaN;
}

StudyRun study_run(const StudyRunRecord& rec, const JobRecord& job,
                   const std::vector<SummaryField>& results) {
  StudyRun r;
  r.job_id = job.id;
  const json point = parse_or_text(rec.point_json);
  if (point.is_array())
    for (const json& v : point) r.point.push_back(v.is_number() ? v.get<double>() : kNaN);
  r.succeeded = job.state == "SUCCEEDED";
  const json doc = parse_or_text(job.summary_json);
  r.wall_s = number_at(doc, "performance", "wall_s");
  const double steps = number_at(doc, "performance", "steps");
  const double elements = number_at(doc, "summary", "elements");
  // With multiple time stepping the slow forces are resolved only every respa_k steps: a run's
  // accuracy goes with its outer steps (respa_k = 1 and 2 at one dt take the same steps, and
  // the first is the more accurate).
  const double respa_k = number_at(parse_or_text(job.spec_json), "run", "respa_k");
  r.element_steps = steps * (std::isfinite(elements) ? elements : 1.0) /
                    (std::isfinite(respa_k) && respa_k >= 1 ? respa_k : 1.0);
  r.balance_error = number_at(doc, "accuracy", "energy_balance_error");
  for (const SummaryField& f : results)
    if (const double v = number_at(doc, "summary", f.key.c_str()); std::isfinite(v))
      r.results[f.key] = v;
  if (!std::isfinite(r.element_steps)) r.succeeded = false;
  return r;
}

std::string reference_text(const StudyTable& t) {
  const StudyErrors& e = t.errors;
  if (t.runs.empty() || e.results.empty()) return "no run succeeded: no reference";
  const std::string finest = "the most accurate run, " +
                             point_text(t.fields, t.runs[e.finest].point) + " (" +
                             t.runs[e.finest].job_id + ")";
  bool any_extrapolated = false;
  for (const ResultError& r : e.results) any_extrapolated |= r.extrapolated;
  if (!any_extrapolated) return finest + (e.note.empty() ? "" : "; " + e.note);
  std::string values;
  for (std::size_t i : e.richardson_runs)
    values += (values.empty() ? "" : ", ") + spec::number_text(t.runs[i].point[0]);
  return "Richardson's extrapolation from " + short_name(t.fields[0].path) + " = " + values +
         " (ratio " + num(e.ratio, 4) + ") where the differences shrink; otherwise " + finest;
}

}  // namespace

std::vector<VariedField> varied_fields(const std::string& text) {
  std::vector<VariedField> out;
  const json j = parse_or_text(text);
  if (!j.is_array()) return out;
  for (const json& f : j) {
    VariedField v;
    v.path = f.value("field", "");
    v.integer = f.value("integer", false);
    for (const json& x : f.value("values", json::array()))
      if (x.is_number()) v.values.push_back(x.get<double>());
    out.push_back(std::move(v));
  }
  return out;
}

std::string vary_json(const std::vector<VariedField>& fields) {
  json j = json::array();
  for (const VariedField& f : fields)
    j.push_back({{"field", f.path}, {"integer", f.integer}, {"values", f.values}});
  return j.dump();
}

StudyTable study_table(const ResultsStore& jobs, const StudyStore& studies,
                       const StudyRecord& study, ReferenceMode mode) {
  StudyTable t;
  t.study = study;
  t.fields = varied_fields(study.vary_json);
  t.records = studies.runs(study.id);
  if (const SummaryLayout* layout = summary_layout(study.kind))
    t.results = summary_results(*layout);
  for (const StudyRunRecord& rec : t.records) {
    const std::optional<JobRecord> job = jobs.find(rec.job_id);
    if (!job)
      throw StoreError("the study " + study.id + " lists job " + rec.job_id + ", which " +
                       jobs.path() + " does not hold");
    t.runs.push_back(study_run(rec, *job, t.results));
    t.states.push_back(job->state);
  }
  // Richardson's h: the one varied setting's value per run.
  std::vector<double> varied;
  if (t.fields.size() == 1)
    for (const StudyRun& r : t.runs) varied.push_back(r.point.empty() ? kNaN : r.point[0]);
  bool any = false;
  for (const StudyRun& r : t.runs) any |= r.succeeded;
  if (any) t.errors = study_errors(t.runs, varied, t.results, mode);
  t.reference = reference_text(t);
  return t;
}

void store_errors(StudyStore& studies, const StudyTable& t) {
  std::vector<StudyErrorRow> rows;
  for (const ResultError& e : t.errors.results)
    for (std::size_t i = 0; i < t.runs.size(); ++i) {
      StudyErrorRow row;
      row.seq = t.records[i].seq;
      row.result = e.field.key;
      row.unit = e.field.unit;
      const auto it = t.runs[i].results.find(e.field.key);
      row.value = t.runs[i].succeeded && it != t.runs[i].results.end() ? it->second : kNaN;
      row.reference = e.reference;
      row.error = e.error[i];
      row.relative_error = e.relative[i];
      row.order = e.order;
      row.extrapolated = e.extrapolated;
      row.wall_s = t.runs[i].wall_s;
      row.balance_error = t.runs[i].balance_error;
      rows.push_back(row);
    }
  studies.set_errors(t.study.id, t.reference, rows);
}

void print_study_table(std::ostream& out, const StudyTable& t) {
  std::vector<std::string> head;
  for (const VariedField& f : t.fields) head.push_back(short_name(f.path));
  for (const char* h : {"JOB", "STATE", "WALL[s]", "BALANCE"}) head.push_back(h);
  for (const SummaryField& f : t.results) {
    std::string name = f.key;
    head.push_back(name);
    head.push_back("error");
  }
  std::vector<std::vector<std::string>> rows = {head};
  for (std::size_t i = 0; i < t.runs.size(); ++i) {
    const StudyRun& r = t.runs[i];
    std::vector<std::string> row;
    for (std::size_t k = 0; k < t.fields.size(); ++k)
      row.push_back(k < r.point.size() ? spec::number_text(r.point[k]) : "-");
    row.push_back(r.job_id);
    row.push_back(t.states[i]);
    row.push_back(num(r.wall_s, 4));
    row.push_back(num(r.balance_error, 3));
    for (std::size_t k = 0; k < t.results.size(); ++k) {
      const auto it = r.results.find(t.results[k].key);
      // Printed in the field's unit: value × scale (a fraction in %), as the run's summary.
      const double scale = t.results[k].scale;
      row.push_back(r.succeeded && it != r.results.end() ? num(it->second * scale) : "-");
      if (k >= t.errors.results.size()) {
        row.push_back("-");
        continue;
      }
      const ResultError& e = t.errors.results[k];
      // Relative where the reference is not zero, else the difference in the result's unit.
      const bool rel = std::isfinite(e.relative[i]);
      row.push_back(rel ? num(100 * e.relative[i], 3) + "%"
                        : num(e.error[i] * scale, 3) +
                              (e.field.unit.empty() ? "" : " " + e.field.unit));
    }
    rows.push_back(std::move(row));
  }
  out << "study " << t.study.id << " (" << t.study.kind << ", " << t.runs.size() << " runs)\n";
  print_table(out, rows);
  out << "reference: " << t.reference << "\n";
  for (const ResultError& e : t.errors.results) {
    out << "  " << e.field.label << ": " << num(e.reference * e.field.scale, 8)
        << (e.field.unit.empty() ? "" : " " + e.field.unit)
        << (e.extrapolated ? " (extrapolated), observed order " + num(e.order, 3)
                           : " (the most accurate run)");
    if (!e.extrapolated && std::isfinite(e.order))
      out << "; the differences do not shrink (observed order " << num(e.order, 3) << ")";
    out << "\n";
  }
}

json study_table_json(const StudyTable& t) {
  json j;
  j["study_id"] = t.study.id;
  j["kind"] = t.study.kind;
  j["vary"] = parse_or_text(t.study.vary_json);
  j["reference"] = t.reference;
  json res = json::array();
  for (const ResultError& e : t.errors.results) {
    json r = {{"key", e.field.key}, {"unit", e.field.unit}, {"label", e.field.label}};
    r["reference"] = std::isfinite(e.reference) ? json(e.reference) : json();
    r["extrapolated"] = e.extrapolated;
    r["observed_order"] = std::isfinite(e.order) ? json(e.order) : json();
    res.push_back(r);
  }
  j["results"] = res;
  json runs = json::array();
  for (std::size_t i = 0; i < t.runs.size(); ++i) {
    const StudyRun& r = t.runs[i];
    json run = {{"job_id", r.job_id}, {"point", r.point}, {"state", t.states[i]}};
    run["wall_s"] = std::isfinite(r.wall_s) ? json(r.wall_s) : json();
    run["energy_balance_error"] = std::isfinite(r.balance_error) ? json(r.balance_error) : json();
    json vals = json::object();
    for (const ResultError& e : t.errors.results) {
      const auto it = r.results.find(e.field.key);
      json v;
      v["value"] = r.succeeded && it != r.results.end() ? json(it->second) : json();
      v["error"] = std::isfinite(e.error[i]) ? json(e.error[i]) : json();
      v["relative_error"] = std::isfinite(e.relative[i]) ? json(e.relative[i]) : json();
      vals[e.field.key] = v;
    }
    run["results"] = vals;
    runs.push_back(run);
  }
  j["runs"] = runs;
  return j;
}

}  // namespace mdem::cli
