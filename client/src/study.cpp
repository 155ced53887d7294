// `mdem study KIND --vary FIELD=v1,v2,...`: one job spec run over the cartesian product of the
// varied values, here (one run after another, results in the local database) or on mdemd
// (--server: jobs sharing a study id), and the table of each result's error against the
// study's reference with each run's wall time. `mdem study show ID` prints a stored study again.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "jobs.h"
#include "mdem/cli.h"
#include "mdem/spec.h"
#include "plot.h"
#include "remote.h"
#include "remote_commands.h"
#include "study_commands.h"
#include "study_plot.h"
#include "study_remote.h"
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
        "  --server HOST:PORT   queue the runs on mdemd instead (with --token-file, --tls,\n"
        "                       --ca-file as for `mdem submit`), each job tagged with the study\n"
        "                       id and its values: `mdem watch --study ID` follows its jobs into\n"
        "                       the database and then prints the table; `mdem cancel --study ID`\n"
        "                       cancels them; `mdem ls --study ID --server ...` lists them. Any\n"
        "                       client of the same user can, with a fresh database too\n"
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
  // --server: the connection flags given (empty: the runs are made here).
  FlagValues connection;
};

// The connection flags given (--server, --token-file, --ca-file, --tls).
FlagValues connection_flags(const FlagValues& given) {
  FlagValues out;
  for (const char* f : {"--server", "--token-file", "--ca-file", "--tls"})
    if (given.count(f)) out[f] = given.at(f);
  return out;
}

// The connection flags given as arguments again.
std::vector<std::string> connection_args(const FlagValues& given) {
  std::vector<std::string> out;
  for (const char* f : {"--server", "--token-file", "--ca-file"})
    if (given.count(f)) out.insert(out.end(), {f, given.at(f)});
  if (given.count("--tls")) out.push_back("--tls");
  return out;
}

StudyPlan parse_plan(const SpecKind& kind, std::vector<std::string> args) {
  StudyPlan plan;
  plan.kind = &kind;
  const std::vector<std::string> vary = take_vary(args);
  FlagSpec fs = spec_flag_spec(kind);
  fs.with_value.push_back("--db");
  fs.with_value.push_back("--reference");
  fs.switches.push_back("--json");
  add_connection_flags(fs);
  const FlagValues given = parse_flags(args, fs);
  if (!given.count("--server"))
    for (const char* f : {"--token-file", "--ca-file", "--tls"})
      if (given.count(f)) throw UsageError(std::string(f) + ": only with --server HOST:PORT");
  if (given.count("--server")) plan.connection = connection_flags(given);
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

// A new study of the plan, recorded (server: the daemon that runs its jobs, "" for here).
StudyRecord record_study(StudyStore& studies, const StudyPlan& plan, const std::string& server) {
  StudyRecord study;
  study.id = StudyStore::new_study_id();
  study.kind = plan.kind->name;
  study.spec_json = spec::to_json(plan.base, false);
  study.vary_json = vary_json(plan.fields);
  study.server = server;
  studies.create_study(study);
  return study;
}

int run_local(const StudyPlan& plan, std::ostream& out, std::ostream& err) {
  ResultsStore jobs(plan.db);
  StudyStore studies(plan.db);
  const StudyRecord study = record_study(studies, plan, "");
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

// The study's table from the database at db, its errors computed again and stored.
StudyTable open_study(const std::string& id, const std::string& db, ReferenceMode mode) {
  std::error_code ec;
  if (!std::filesystem::exists(db, ec))
    throw StoreError("no study '" + id + "' in " + db + " (the database does not exist)");
  ResultsStore jobs(db);
  StudyStore studies(db);
  const std::optional<StudyRecord> s = studies.find(id);
  if (!s) throw StoreError("no study '" + id + "' in " + db);
  StudyTable t = study_table(jobs, studies, *s, mode);
  store_errors(studies, t);
  return t;
}

// Each run queued on the daemon with its study tag (study id, run, varied values), recorded
// here as a job of the study; `mdem watch --study` follows them and computes the errors. The
// request id of a run is the study's id and the run's index: a retry queues nothing twice.
int run_remote(const StudyPlan& plan, std::ostream& out, std::ostream& err) {
  ResultsStore jobs(plan.db);
  StudyStore studies(plan.db);
  JobClient client(resolve_connection(plan.connection, process_env()));
  const StudyRecord study = record_study(studies, plan, client.settings().server);
  int queued = 0;
  for (std::size_t i = 0; i < plan.points.size(); ++i) {
    v1::SubmitJobRequest request;
    request.set_request_id(study.id + "-run-" + std::to_string(i));
    *request.mutable_spec() = varied_spec(plan.base, plan.fields, plan.points[i]);
    *request.mutable_study() =
        study_run_tag(study.id, static_cast<int>(i), plan.fields, plan.points[i]);
    v1::SubmitJobResponse response;
    try {
      response = client.submit(request);
    } catch (const RemoteError& e) {
      err << "mdem study " << plan.kind->name << ": " << e.what() << "\n"
          << "study " << study.id << ": " << queued << " of " << plan.points.size()
          << " runs queued before the daemon refused one\n";
      return e.exit_code;
    }
    const v1::JobInfo& info = response.job();
    jobs.upsert_remote_job(record_of(info, client.settings(), job_state_name(info.state())));
    studies.add_run(study.id, {static_cast<int>(i), info.job_id(), json(plan.points[i]).dump()});
    ++queued;
    err << "  run " << i + 1 << "/" << plan.points.size() << " ("
        << point_text(plan.fields, plan.points[i]) << "): queued " << info.job_id() << "\n";
  }
  if (plan.json) {
    write_json(out, json{{"study_id", study.id}, {"server", study.server}, {"runs", queued}});
    out << "\n";
  } else {
    out << study.id << "\n";
    err << "study " << study.id << ": " << queued << " jobs queued on " << study.server
        << "; follow them with `mdem watch --study " << study.id
        << "` (which then prints the errors)\n";
  }
  return kOk;
}

int show(const std::vector<std::string>& args, std::ostream& out) {
  const FlagSpec fs{{"--db", "--reference"}, {"--json"}};
  auto [id, given] = parse_id_and_flags(args, fs);
  const ReferenceMode mode = reference_mode(given);
  const std::string db = given.count("--db") ? given["--db"] : ResultsStore::default_path();
  return finish(out, open_study(id, db, mode), given.count("--json") > 0);
}

// The study's runs and the flags to hand to each job's command: --db and the connection flags.
struct StudyCall {
  std::string id, db;
  bool json = false;
  std::vector<std::string> pass;
  FlagValues connection;  // the connection flags given
};

StudyCall study_call(const std::vector<std::string>& args, bool watching) {
  FlagSpec fs{{"--study", "--db"}, {"--json"}};
  if (watching) fs.with_value.push_back("--reconnect-timeout");
  add_connection_flags(fs);
  const FlagValues given = parse_flags(args, fs);
  StudyCall c;
  c.id = given.at("--study");
  c.db = given.count("--db") ? given.at("--db") : ResultsStore::default_path();
  c.json = given.count("--json") > 0;
  c.connection = connection_flags(given);
  c.pass = connection_args(given);
  c.pass.insert(c.pass.end(), {"--db", c.db});
  if (given.count("--reconnect-timeout"))
    c.pass.insert(c.pass.end(), {"--reconnect-timeout", given.at("--reconnect-timeout")});
  return c;
}

// Whether the study is in the local database (a prefix of its id will do).
bool study_here(const StudyCall& c) {
  std::error_code ec;
  if (!std::filesystem::exists(c.db, ec)) return false;
  ResultsStore jobs(c.db);
  return StudyStore(c.db).find(c.id).has_value();
}

// A study not in the local database but on the daemon that --server (or $MDEM_SERVER) names:
// recorded here from the daemon's jobs (another client submitted it), so that it can be
// followed and its table computed as if it had been submitted from here.
void take_study_from_daemon(const StudyCall& c) {
  if (study_here(c) || !server_named(c.connection, process_env())) return;
  JobClient client(resolve_connection(c.connection, process_env()));
  ResultsStore jobs(c.db);
  StudyStore studies(c.db);
  take_daemon_study(client, jobs, studies, c.id);
}

// The study's jobs: from the local database, else from the daemon named (the study id in full).
std::vector<std::string> study_job_ids(const StudyCall& c) {
  std::vector<std::string> ids;
  if (study_here(c) || !server_named(c.connection, process_env())) {
    for (const StudyRunRecord& r : open_study(c.id, c.db, ReferenceMode::Auto).records)
      ids.push_back(r.job_id);
    return ids;
  }
  JobClient client(resolve_connection(c.connection, process_env()));
  for (const v1::JobInfo& j : daemon_study_jobs(client, c.id)) ids.push_back(j.job_id());
  if (ids.empty())
    throw StoreError("no study '" + c.id + "' in " + c.db + " nor among your jobs on mdemd at " +
                     client.settings().server);
  return ids;
}

// guarded_run, and a daemon's refusal or a lost connection as `mdem submit` reports it: its
// message and exit code (2 for a refused argument, 3 for no connection).
int guarded_remote(const std::string& command, const std::function<int()>& body,
                   std::ostream& err) {
  return guarded_run(
      command,
      [&] {
        try {
          return body();
        } catch (const RemoteError& e) {
          err << command << ": " << e.what() << "\n";
          return e.exit_code;
        }
      },
      err);
}

}  // namespace

int plot_study(const std::string& id, const std::string& db, const std::string& out_path,
               std::ostream& out) {
  if (!out_path.empty()) plot_terminal(out_path);  // a bad extension before any work
  const StudyTable t = open_study(id, db, ReferenceMode::Auto);
  const std::string path = out_path.empty() ? t.study.id + ".png" : out_path;
  const StudyPlotInfo info = render_study_plot(t, path);
  out << "wrote " << path << " (" << info.curves << " result(s) against wall time, "
      << t.runs.size() << " runs)\n";
  return kOk;
}

bool names_study(const std::vector<std::string>& args) {
  for (const std::string& a : args)
    if (a == "--study" || a.rfind("--study=", 0) == 0) return true;
  return false;
}

int watch_study(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  return guarded_remote(
      "mdem watch",
      [&] {
        const StudyCall c = study_call(args, true);
        take_study_from_daemon(c);
        const StudyTable before = open_study(c.id, c.db, ReferenceMode::Auto);
        for (const StudyRunRecord& r : before.records) {
          std::vector<std::string> a = {r.job_id};
          a.insert(a.end(), c.pass.begin(), c.pass.end());
          a.push_back("--json");  // the job's report is read back from the database
          std::ostringstream report;
          err << "study " << before.study.id << ": watching " << r.job_id << "\n";
          const int code = watch(a, report, err);
          if (code != kOk && code != kJobFailed) return code;  // no daemon, Ctrl-C
        }
        return finish(out, open_study(before.study.id, c.db, ReferenceMode::Auto), c.json);
      },
      err);
}

int cancel_study(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  return guarded_remote(
      "mdem cancel",
      [&] {
        const StudyCall c = study_call(args, false);
        int worst = kOk;
        for (const std::string& job_id : study_job_ids(c)) {
          std::vector<std::string> a = {job_id};
          a.insert(a.end(), c.pass.begin(), c.pass.end());
          if (const int code = cancel(a, out, err); code != kOk) worst = code;
        }
        return worst;
      },
      err);
}

int ls_daemon_study(const std::string& id, const FlagValues& given, bool as_json, std::ostream& out,
                    std::ostream& err) {
  return guarded_remote(
      "mdem ls",
      [&] {
        JobClient client(resolve_connection(connection_flags(given), process_env()));
        return print_daemon_study(client, id, as_json, out, err);
      },
      err);
}

int ls_study(const std::string& id, const std::string& db, bool as_json, std::ostream& out) {
  const StudyTable t = open_study(id, db, ReferenceMode::Auto);
  if (as_json) {
    json all = json::array();
    for (std::size_t i = 0; i < t.runs.size(); ++i)
      all.push_back({{"job_id", t.runs[i].job_id},
                     {"point", t.runs[i].point},
                     {"state", t.states[i]},
                     {"wall_s", t.runs[i].wall_s}});
    out << all.dump(2) << "\n";
    return kOk;
  }
  std::vector<std::vector<std::string>> rows = {{"ID", "VALUES", "STATE", "WALL[s]"}};
  for (std::size_t i = 0; i < t.runs.size(); ++i)
    rows.push_back({t.runs[i].job_id, point_text(t.fields, t.runs[i].point), t.states[i],
                    std::isfinite(t.runs[i].wall_s) ? spec::number_text(t.runs[i].wall_s) : "-"});
  out << "study " << t.study.id << " (" << t.study.kind << ")\n";
  print_table(out, rows);
  return kOk;
}

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
      command,
      [&] {
        if (plan.connection.empty()) return run_local(plan, out, err);
        try {
          return run_remote(plan, out, err);
        } catch (const RemoteError& e) {  // no connection before the first run was queued
          err << command << ": " << e.what() << "\n";
          return e.exit_code;
        }
      },
      err);
}

}  // namespace mdem::cli
