// `mdem study KIND --vary FIELD=v1,v2,...`: one job spec run over the cartesian product of the
// varied values, here (one run after another, results in the local database) or on mdemd
// (--server: jobs sharing a study id), and the table of each result's error against the
// study's reference with each run's wall time. `mdem study show ID` prints a stored study again.
#include <filesystem>
#include <sstream>

#include "jobs.h"
#include "mdem/cli.h"
#include "mdem/spec.h"
#include "study_table.h"

namespace mdem::cli {
namespace {

void print_help(std::ostream& os) {
  os << "Usage: mdem study <kind> --vary FIELD=v1,v2,... [--vary ...] [flags of mdem run <kind>]\n"
        "       mdem study show ID [--db PATH] [--json] [--reference auto|finest]\n"
        "\n"
        "Runs one job spec (the flags and --spec FILE of `mdem run <kind>`) once for every\n"
        "combination of the varied values (at most "
     << kMaxStudyRuns
     << " runs), one after another in this\n"
        "process, results in the local database (each run is an ordinary job: `mdem show`,\n"
        "`mdem plot`), then prints each run's wall time, energy-balance error and the error of\n"
        "each of the kind's results (twist: twist angle, end shift, rope radius, Q;\n"
        "compression: peak force, loading stiffness, residual height loss, bonds broken)\n"
        "against the study's reference, stored with the study (docs/results.md).\n"
        "\n"
        "The reference: with one varied setting whose three most accurate runs (most element-\n"
        "steps: smallest step, slowest loading) are at a constant ratio (e.g. safety\n"
        "0.6,0.3,0.15), Richardson's extrapolation from them, with the observed order of\n"
        "convergence; otherwise (and for counts) the most accurate run's value.\n"
        "\n"
        "Study flags:\n"
        "  --vary FIELD=LIST    a numeric field of the spec and its values, comma-separated;\n"
        "                       repeatable (the runs are the cartesian product). FIELD is a\n"
        "                       dotted path (run.safety, twist.torque_rate_nn_nm_per_ps), its\n"
        "                       last part (safety) or the flag that sets it (rate, speed).\n"
        "                       Every value is checked against the field's range first.\n"
        "  --reference MODE     auto (Richardson where it applies; default) or finest\n"
        "  --db PATH            results database (default $MDEM_DB, else\n"
        "                       ~/.local/share/mdem/results.db)\n"
        "  --json               print the study's table as one JSON object\n"
        "\n"
        "`mdem plot ID` draws a study's errors against wall time (log-log); `mdem ls --study ID`\n"
        "lists its jobs.\n"
        "\n"
        "Exit codes: 0 every run succeeded, 1 a run failed or was cancelled (the study stops at\n"
        "a cancelled run), 2 usage error.\n";
}

ReferenceMode reference_mode(const FlagValues& given) {
  const auto it = given.find("--reference");
  if (it == given.end() || it->second == "auto") return ReferenceMode::Auto;
  if (it->second == "finest") return ReferenceMode::Finest;
  throw UsageError("--reference: '" + it->second + "' is not allowed (allowed: auto, finest)");
}

// The --vary arguments taken out of args (the flag may repeat; parse_flags allows no repeat).
std::vector<std::string> take_vary(std::vector<std::string>& args) {
  std::vector<std::string> out, rest;
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--vary") {
      if (i + 1 >= args.size() || args[i + 1].rfind("--", 0) == 0)
        throw UsageError("--vary: missing value (allowed: FIELD=v1,v2,...)");
      out.push_back(args[++i]);
    } else if (args[i].rfind("--vary=", 0) == 0) {
      out.push_back(args[i].substr(7));
    } else {
      rest.push_back(args[i]);
    }
  }
  args = std::move(rest);
  return out;
}

struct StudyPlan {
  const SpecKind* kind = nullptr;
  v1::JobSpec base;
  std::vector<VariedField> fields;
  std::vector<std::vector<double>> points;
  std::string db;
  bool json = false;
  ReferenceMode mode = ReferenceMode::Auto;
};

StudyPlan parse_plan(const SpecKind& kind, std::vector<std::string> args) {
  StudyPlan plan;
  plan.kind = &kind;
  const std::vector<std::string> vary = take_vary(args);
  FlagSpec fs = spec_flag_spec(kind);
  fs.with_value.push_back("--db");
  fs.with_value.push_back("--reference");
  fs.switches.push_back("--json");
  const FlagValues given = parse_flags(args, fs);
  plan.mode = reference_mode(given);
  plan.base = spec_from_flags(kind, given);
  for (const std::string& v : vary) plan.fields.push_back(parse_vary(kind, v));
  plan.points = study_points(plan.fields);
  check_study(plan.base, plan.fields);
  plan.db = given.count("--db") ? given.at("--db") : ResultsStore::default_path();
  plan.json = given.count("--json") > 0;
  return plan;
}

int finish(std::ostream& out, const StudyTable& t, bool as_json) {
  if (as_json) {
    write_json(out, study_table_json(t));
    out << "\n";
  } else {
    print_study_table(out, t);
  }
  for (const std::string& s : t.states)
    if (s != "SUCCEEDED") return kJobFailed;
  return kOk;
}

int run_local(const StudyPlan& plan, std::ostream& out, std::ostream& err) {
  ResultsStore jobs(plan.db);
  StudyStore studies(plan.db);
  StudyRecord study;
  study.id = StudyStore::new_study_id();
  study.kind = plan.kind->name;
  study.spec_json = spec::to_json(plan.base, false);
  study.vary_json = vary_json(plan.fields);
  studies.create_study(study);
  err << "study " << study.id << ": " << plan.points.size() << " " << plan.kind->name
      << " runs in this process\n";
  for (std::size_t i = 0; i < plan.points.size(); ++i) {
    const std::vector<double>& point = plan.points[i];
    SpecRunOptions o;
    o.spec = varied_spec(plan.base, plan.fields, point);
    o.db = plan.db;
    o.json = true;  // the run's report is read back from the database
    std::ostringstream report, run_err;
    std::string id;
    const std::string what = point_text(plan.fields, point);
    err << "  run " << i + 1 << "/" << plan.points.size() << " (" << what << ") ..." << std::flush;
    try {
      run_spec_job(*plan.kind, o, report, run_err, &id);
    } catch (const std::exception& e) {
      err << " not run: " << e.what() << "\n";
      if (!jobs.find(id)) continue;  // nothing recorded: not part of the study
    }
    studies.add_run(study.id, {static_cast<int>(i), id, json(point).dump()});
    const std::optional<JobRecord> rec = jobs.find(id);
    const json doc = parse_or_text(rec ? rec->summary_json : "");
    const double wall = doc.contains("performance") ? doc["performance"].value("wall_s", 0.0) : 0;
    err << " " << id << " " << (rec ? rec->state : "?") << " in " << wall << " s"
        << (rec && !rec->reason.empty() ? ": " + rec->reason : "") << "\n";
    if (rec && rec->state == "CANCELLED") {
      err << "study " << study.id << ": stopped at a cancelled run\n";
      break;
    }
  }
  const StudyTable t = study_table(jobs, studies, *studies.find(study.id), plan.mode);
  store_errors(studies, t);
  return finish(out, t, plan.json);
}

int show(const std::vector<std::string>& args, std::ostream& out) {
  const FlagSpec fs{{"--db", "--reference"}, {"--json"}};
  auto [id, given] = parse_id_and_flags(args, fs);
  const ReferenceMode mode = reference_mode(given);
  const std::string db = given.count("--db") ? given["--db"] : ResultsStore::default_path();
  std::error_code ec;
  if (!std::filesystem::exists(db, ec))
    throw UsageError("no study '" + id + "' in " + db + " (the database does not exist)");
  ResultsStore jobs(db);
  StudyStore studies(db);
  const std::optional<StudyRecord> s = studies.find(id);
  if (!s) throw UsageError("no study '" + id + "' in " + db);
  StudyTable t = study_table(jobs, studies, *s, mode);
  store_errors(studies, t);
  return finish(out, t, given.count("--json") > 0);
}

}  // namespace

int study(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (args.empty() || args.front() == "--help" || args.front() == "-h") {
    print_help(args.empty() ? err : out);
    return args.empty() ? kUsage : kOk;
  }
  if (wants_help(args)) {
    print_help(out);
    return kOk;
  }
  const std::string kind = args.front();
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  const std::string command = "mdem study " + kind;
  if (kind == "show")
    return guarded_run(
        "mdem study show", [&] { return show(rest, out); }, err);
  const SpecKind* k = find_spec_kind(kind);
  if (!k) {
    err << "mdem study: unknown job kind '" << kind << "' (allowed: " << spec_kind_names() << ")\n";
    return kUsage;
  }
  StudyPlan plan;
  try {
    plan = parse_plan(*k, rest);
  } catch (const spec::SpecError& e) {
    err << command << ": invalid job spec:\n"
        << describe_spec_error(e) << "Run 'mdem study --help' for the flags.\n";
    return kUsage;
  } catch (const UsageError& e) {
    err << command << ": " << e.what() << "\nRun 'mdem study --help' for the flags.\n";
    return kUsage;
  }
  return guarded_run(
      command, [&] { return run_local(plan, out, err); }, err);
}

}  // namespace mdem::cli
