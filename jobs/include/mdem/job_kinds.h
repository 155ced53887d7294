#pragma once
// The jobs layer's registry of job kinds: for each kind how a finalized spec becomes an engine
// job, an upper bound of its elements, and its summary layout: the declared list of the named
// values (with units, labels and print precision) its report carries, which the report's JSON,
// the printer, `mdem ls` and the export read. A new kind is its own <kind>_job_kind.cpp and one
// line in job_kinds() (jobs/src/job_kinds.cpp).
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "mdem/integrate/system.h"
#include "mdem/job/job.h"
#include "mdem/kind_registry.h"
#include "mdem/v1/job.pb.h"

namespace mdem {

// One named value of a kind's summary.
struct SummaryField {
  enum class Type { Real, Count, Label };
  std::string key;  // the engine Summary's name and the JSON key ("twist_angle_deg")
  Type type = Type::Real;
  std::string unit;        // as printed ("deg", "nN·nm"); "" for counts, labels and ratios
  std::string label;       // words for people ("twist angle")
  int line = 0;            // the printer's line it goes on (1, 2, ...); 0: in the JSON only
  int digits = 6;          // significant digits when printed (reals)
  bool highlight = false;  // shown in `mdem ls`
  // One of the kind's results: what a user reads off the job (a twist angle, a peak force), whose
  // error a study (`mdem study`) measures against its reference. Reals and counts only.
  bool result = false;
  // Printed as value × scale (100: a fraction printed in %, unit "%"); the JSON keeps the value.
  double scale = 1.0;
  // A count whose negative value means "none" (a separated tube's number, -1 when no tube
  // separated): not printed then; the JSON keeps it.
  bool none_if_negative = false;
};
using SummaryLayout = std::vector<SummaryField>;

// The picture `mdem plot ID` draws without --columns: `columns` against the column `x` scaled by
// x_scale and labelled x_label (a tensile job: stress in GPa against strain in %). No columns:
// the energy overview against time.
struct DefaultPlot {
  std::vector<std::string> columns;
  std::string x = "time_ps";
  double x_scale = 1.0;
  std::string x_label;  // "" = from the column's name
};

struct JobKind {
  std::string name;  // as in the proto layer's registry ("twist")
  v1::JobSpec::KindCase kind_case;
  // The engine job of a finalized spec with the given integrator settings.
  std::function<std::unique_ptr<Job>(const v1::JobSpec&, const IntegratorSettings&)> build;
  // The kind's local damping alpha (it lives in the kind's own message).
  std::function<double(const v1::JobSpec&)> local_damping;
  // An upper bound of the element count from the spec alone (nothing built).
  std::function<long(const v1::JobSpec&)> element_bound;
  // Whether building the scene is quick (a lattice) rather than a simulation of its own.
  bool builds_quickly = true;
  SummaryLayout summary;
  DefaultPlot plot;
};

using JobKindRegistry = KindRegistry<JobKind>;

// The kinds this build runs: twist, compression, tensile.
const JobKindRegistry& job_kinds();
JobKind twist_job_kind();
JobKind compression_job_kind();
JobKind tensile_job_kind();

// The layout of the kind named `kind` in job_kinds(), or nullptr for a kind that has none (the
// `run bundle` demo, a report from a newer daemon).
const SummaryLayout* summary_layout(const std::string& kind);

// The summary as JSON, values in the layout's order; a value the engine reports but the layout
// does not declare follows, under its own name.
using ReportJson = nlohmann::ordered_json;
ReportJson summary_json(const SummaryLayout& layout, const Summary& s);

// One declared value as text: "12.5 deg", "twisted", "7"; reals to the field's digits.
std::string summary_value_text(const SummaryField& f, const nlohmann::ordered_json& v);
// The summary's values in words, one string per printed line ("morphology twisted, twist angle
// 12.5 deg, ..."): the declared fields present in `summary`, in layout order.
std::vector<std::string> summary_lines(const SummaryLayout& layout,
                                       const nlohmann::ordered_json& summary);
// The highlights of `mdem ls`: "morphology twisted", "1638 elements", "peak force 702.8 nN".
std::vector<std::string> summary_highlights(const SummaryLayout& layout,
                                            const nlohmann::ordered_json& summary);
// The layout's results (SummaryField::result), in layout order.
std::vector<SummaryField> summary_results(const SummaryLayout& layout);

}  // namespace mdem
