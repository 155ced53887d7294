// The registry of the job kinds this build runs (one line per kind), and the declared summary
// read by the report's JSON, the printer and `mdem ls`.
#include "mdem/job_kinds.h"

#include <cmath>
#include <cstdio>
#include <map>

namespace mdem {

const JobKindRegistry& job_kinds() {
  static const JobKindRegistry kinds = {twist_job_kind(), compression_job_kind(),
                                        tensile_job_kind()};
  return kinds;
}

const SummaryLayout* summary_layout(const std::string& kind) {
  const JobKind* k = job_kinds().find(kind);
  return k ? &k->summary : nullptr;
}

ReportJson summary_json(const SummaryLayout& layout, const Summary& s) {
  std::map<std::string, const SummaryValue*> by_key;
  for (const auto& [k, v] : s) by_key.emplace(k, &v);
  ReportJson j = ReportJson::object();
  auto put = [&](const std::string& k, const SummaryValue& v) {
    std::visit([&](const auto& x) { j[k] = x; }, v);
  };
  for (const SummaryField& f : layout)
    if (const auto it = by_key.find(f.key); it != by_key.end()) put(f.key, *it->second);
  for (const auto& [k, v] : s)
    if (!j.contains(k)) put(k, v);
  return j;
}

std::string summary_value_text(const SummaryField& f, const nlohmann::ordered_json& v) {
  std::string text;
  if (v.is_string()) {
    text = v.get<std::string>();
  } else if (v.is_number_integer()) {
    text = std::to_string(v.get<long long>());
  } else if (v.is_number()) {
    // A value below 1e-9 of its unit (1e-9 nm, deg, nN, GPa) is round-off of a zero (a residual
    // of 1.9e-13 nm): printed as 0, not to `digits` digits of noise. The JSON keeps the number.
    double x = v.get<double>();
    if (std::abs(x) < 1e-9) x = 0;
    x *= f.scale;
    char buf[48];
    std::snprintf(buf, sizeof buf, "%.*g", f.digits, x);
    text = buf;
  } else {
    text = v.dump();
  }
  return f.unit.empty() ? text : text + " " + f.unit;
}

std::vector<std::string> summary_lines(const SummaryLayout& layout,
                                       const nlohmann::ordered_json& summary) {
  std::map<int, std::string> lines;
  if (!summary.is_object()) return {};
  for (const SummaryField& f : layout) {
    if (f.line == 0 || !summary.contains(f.key)) continue;
    if (f.none_if_negative && summary[f.key].is_number() && summary[f.key].get<double>() < 0)
      continue;
    std::string& line = lines[f.line];
    line += (line.empty() ? "" : ", ") + f.label + " " + summary_value_text(f, summary[f.key]);
  }
  std::vector<std::string> out;
  for (auto& [n, line] : lines) out.push_back(std::move(line));
  return out;
}

std::vector<std::string> summary_highlights(const SummaryLayout& layout,
                                            const nlohmann::ordered_json& summary) {
  std::vector<std::string> out;
  if (!summary.is_object()) return out;
  for (const SummaryField& f : layout) {
    if (!f.highlight || !summary.contains(f.key)) continue;
    const std::string value = summary_value_text(f, summary[f.key]);
    // A count reads "1638 elements"; a value "peak force 702.8 nN".
    out.push_back(f.type == SummaryField::Type::Count ? value + " " + f.label
                                                      : f.label + " " + value);
  }
  return out;
}

std::vector<SummaryField> summary_results(const SummaryLayout& layout) {
  std::vector<SummaryField> out;
  for (const SummaryField& f : layout)
    if (f.result) out.push_back(f);
  return out;
}

}  // namespace mdem
