// The commands that read the local results database: `mdem ls`, `mdem show`, `mdem export` and
// `mdem plot`.
#include <algorithm>
#include <filesystem>
#include <memory>

#include "export.h"
#include "flags.h"
#include "mdem/cli.h"
#include "mdem/job_kinds.h"
#include "mdem/job_state.h"
#include "mdem/time_text.h"
#include "plot.h"
#include "remote.h"
#include "remote_commands.h"
#include "results_store.h"
#include "study_commands.h"
#include "study_store.h"

namespace mdem::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* kDbFlagHelp =
    "  --db PATH       the results database (default: $MDEM_DB, else\n"
    "                  $XDG_DATA_HOME/mdem/results.db, else ~/.local/share/mdem/results.db)\n"
    "  -h, --help      show this help\n";
constexpr const char* kIdHelp =
    "ID is a job id as `mdem ls` prints it, or any prefix of one that names a single job.\n";
constexpr const char* kExitHelp =
    "Exit codes: 0 success, 1 no such job or the database/output cannot be read or written,\n"
    "2 usage error.\n";

constexpr const char* kRemoteHelp =
    "With --server HOST:PORT (or $MDEM_SERVER set) the daemon is asked instead of the local\n"
    "database (the config file's server is not enough: `mdem ls` stays local without them);\n"
    "--local (or --db) reads the local database even then. On a daemon:\n";

constexpr const char* kRemoteExitHelp =
    "Exit codes: 0 success, 1 no such job (or not yours, or the token was refused) or the\n"
    "database/output cannot be read or written, 2 usage error (also a bad config or token\n"
    "file), 3 the daemon could not be reached or did not answer.\n";

void print_ls_help(std::ostream& os) {
  os << "Usage: mdem ls [--db PATH] [--json]\n"
        "       mdem ls --server HOST:PORT [--all] [--limit N] [--json] [connection flags]\n"
        "       mdem ls --study ID [--db PATH] [--json]   (a study's jobs: `mdem study --help`)\n"
        "\n"
        "Lists the jobs of the local results database, newest first: id, kind, state, creation\n"
        "time (UTC) and highlights of the spec and summary (name, morphology, element count, why\n"
        "a job failed). Jobs submitted to a daemon are there too, with what `mdem watch` stored.\n"
        "\n"
        "Flags:\n"
        "  --json          print a JSON array of the jobs (spec and final report as JSON)\n"
     << kDbFlagHelp << "  --local         the local database even with $MDEM_SERVER set\n\n"
     << kRemoteHelp
     << "  --all           every user's jobs (an admin's token only) with a USER column\n"
        "  --limit N       at most N jobs, 1..1000 (default: the daemon's, 100)\n"
     << kConnectionHelp << "\n"
     << kRemoteExitHelp;
}

void print_show_help(std::ostream& os) {
  os << "Usage: mdem show ID [--db PATH] [--json]\n"
        "       mdem show ID --server HOST:PORT [--json] [connection flags]\n"
        "\n"
        "Prints one job: kind, state (and why it failed), creation and finish times, the numbers\n"
        "of frames (with the series' columns) and snapshots, and the spec and report JSON.\n"
     << kIdHelp
     << "\n"
        "Flags:\n"
        "  --json          print one JSON object\n"
     << kDbFlagHelp << "  --local         the local database even with $MDEM_SERVER set\n\n"
     << kRemoteHelp
     << "the daemon's view of the job (user, state, progress, spec, report); ID is passed as\n"
        "given.\n"
     << kConnectionHelp << "\n"
     << kRemoteExitHelp;
}

void print_export_help(std::ostream& os) {
  os << "Usage: mdem export ID --format xyz|vtk|csv [--out PATH] [--db PATH]\n"
        "\n"
        "Writes a job's results for other programs (numbers with 17 significant digits):\n"
        "  xyz  extended XYZ for OVITO: one file, one frame per snapshot (Time in ps and Step in\n"
        "       the header). Per element: species (C CNT segment, Si nanoparticle, G grain), pos\n"
        "       (nm), orientation (unit quaternion body -> world in X Y Z W order, OVITO's),\n"
        "       axis (body x in the world frame: a segment's axis, for oriented cylinders),\n"
        "       radius (nm), tube, index and the per-element scalars (e.g. force_nN).\n"
        "  vtk  VTK XML PolyData for ParaView: one <base>_<k>.vtp per snapshot and a <base>.pvd\n"
        "       collection with their times (ps). Points at element centres with the same arrays\n"
        "       (orientation in x y z w order), and one polyline per tube through its segments.\n"
        "  csv  the time series: step,time_ps and the job's columns, one row per frame.\n"
     << kIdHelp
     << "\n"
        "Flags:\n"
        "  --format F      xyz, vtk or csv (required)\n"
        "  --out PATH      the file to write; for vtk the .pvd file (the .vtp files go next to\n"
        "                  it; missing directories are created). Default: <job id>.xyz,\n"
        "                  <job id>.pvd or <job id>.csv in the current directory\n"
     << kDbFlagHelp << "\n"
     << kExitHelp;
}

void print_plot_help(std::ostream& os) {
  os << "Usage: mdem plot ID [--out PATH] [--columns A,B,...] [--x COLUMN] [--db PATH]\n"
        "       mdem plot STUDY-ID [--out PATH] [--db PATH]   (a study's errors against wall\n"
        "                                                     time, log-log: `mdem study --help`)\n"
        "\n"
        "Draws a job's time series with gnuplot: by default the energy components (the columns\n"
        "ending in _eV) against time_ps; a tensile job's stress (GPa) against strain (%).\n"
     << kIdHelp
     << "\n"
        "Flags:\n"
        "  --out PATH      the picture: .png (pngcairo) or .svg (default: <job id>.png in the\n"
        "                  current directory; missing directories are created)\n"
        "  --columns LIST  comma-separated columns to draw (default: every *_eV column)\n"
        "  --x COLUMN      the horizontal axis: time_ps (default), step, or a column (e.g. a\n"
        "                  strain column, for a stress-strain curve)\n"
     << kDbFlagHelp
     << "\n"
        "Needs gnuplot (Debian: apt-get install gnuplot-nox); $MDEM_GNUPLOT names another\n"
        "gnuplot binary.\n"
     << kExitHelp;
}

// The job id matches nothing (exit kJobFailed).
struct NoSuchJob : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Prints the command's help when asked for, else runs its body, mapping errors to exit codes and
// messages prefixed with the command.
template <class Body>
int guarded(const std::string& cmd, const std::vector<std::string>& args, std::ostream& out,
            std::ostream& err, void (*print_help)(std::ostream&), Body&& body) {
  if (wants_help(args)) {
    print_help(out);
    return kOk;
  }
  try {
    return body();
  } catch (const UsageError& e) {
    err << "mdem " << cmd << ": " << e.what() << "\nRun 'mdem " << cmd
        << " --help' for the flags.\n";
    return kUsage;
  } catch (const NoSuchJob& e) {
    err << "mdem " << cmd << ": " << e.what() << "\n";
    return kJobFailed;
  } catch (const RemoteError& e) {
    err << "mdem " << cmd << ": " << e.what() << "\n";
    return e.exit_code;
  } catch (const std::exception& e) {
    err << "mdem " << cmd << ": error: " << e.what() << "\n";
    return kJobFailed;
  }
}

std::string db_path(const std::map<std::string, std::string>& given) {
  const auto it = given.find("--db");
  return it != given.end() ? it->second : ResultsStore::default_path();
}

bool db_exists(const std::string& path) {
  std::error_code ec;
  return fs::exists(path, ec);
}

// Opens the database holding the job: a database that does not exist holds no job (and is not
// created by a command that only reads).
std::unique_ptr<ResultsStore> open_store(const std::string& path, const std::string& id) {
  if (!db_exists(path))
    throw NoSuchJob("no job '" + id + "' in " + path + " (the database does not exist)");
  return std::make_unique<ResultsStore>(path);
}

JobRecord resolve(const ResultsStore& store, const std::string& id) {
  std::optional<JobRecord> job = store.find(id);
  if (!job) throw NoSuchJob("no job '" + id + "' in " + store.path());
  return std::move(*job);
}

// A daemon's job not yet seen ending here: the daemon may know a later state than this record.
bool may_be_outdated(const JobRecord& job) { return !job.server.empty() && !is_final(job.state); }

json job_json(const JobRecord& job) {
  json j{{"job_id", job.id},
         {"kind", job.kind},
         {"state", job.state},
         {"reason", job.reason},
         {"created_at", job.created_at},
         {"finished_at", job.finished_at}};
  if (!job.server.empty()) {
    j["server"] = job.server;
    j["state_may_be_outdated"] = may_be_outdated(job);
  }
  j["spec"] = parse_or_text(job.spec_json);
  // The job's final report (its summary, accuracy, performance), under the key `mdem show
  // --server` uses: no summary.summary.
  j["report"] = parse_or_text(job.summary_json);
  return j;
}

std::string scalar_text(const json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

// The few facts worth a glance in `mdem ls`.
std::string highlights(const JobRecord& job) {
  std::vector<std::string> parts;
  const json spec = parse_or_text(job.spec_json);
  if (spec.is_object() && spec.contains("name")) parts.push_back(scalar_text(spec["name"]));
  json summary = parse_or_text(job.summary_json);
  if (summary.is_object() && summary.contains("summary")) summary = summary["summary"];
  // The kind's declared highlights (jobs/src/<kind>_job_kind.cpp).
  if (const SummaryLayout* layout = summary_layout(job.kind))
    for (std::string& h : summary_highlights(*layout, summary)) parts.push_back(std::move(h));
  if (!job.reason.empty()) parts.push_back(job.reason);
  std::string text;
  for (const std::string& p : parts) text += (text.empty() ? "" : "; ") + p;
  constexpr std::size_t kMax = 72;
  return text.size() > kMax ? text.substr(0, kMax - 3) + "..." : text;
}

// Whether ls/show ask the daemon: --server, or $MDEM_SERVER without --local or --db. The flags only
// the daemon understands are refused locally.
bool ask_daemon(const std::map<std::string, std::string>& given) {
  if (given.count("--local")) {
    for (const char* f : {"--server", "--token-file", "--tls", "--ca-file", "--all", "--limit"})
      if (given.count(f)) throw UsageError(std::string(f) + ": not with --local");
    return false;
  }
  if (given.count("--server")) {
    if (given.count("--db")) throw UsageError("--db: the local database is not read with --server");
    return true;
  }
  // $MDEM_SERVER alone: the daemon, unless --db asks for a local database.
  if (server_named(given, process_env()) && !given.count("--db")) return true;
  for (const char* f : {"--token-file", "--tls", "--ca-file", "--all", "--limit"})
    if (given.count(f))
      throw UsageError(std::string(f) + ": only with --server HOST:PORT (or $MDEM_SERVER)");
  return false;
}

int run_ls(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  FlagSpec spec{{"--db", "--limit", "--study"}, {"--json", "--all", "--local"}};
  add_connection_flags(spec);
  auto given = parse_flags(args, spec);
  // A study: as the daemon that --server names knows it (it keeps the study id with each job),
  // else from the local database (its jobs may run on a daemon: `mdem watch --study`).
  if (given.count("--study")) {
    if (given.count("--server")) {
      if (given.count("--db"))
        throw UsageError("--db: the local database is not read with --server");
      return ls_daemon_study(given["--study"], given, given.count("--json") > 0, out, err);
    }
    return ls_study(given["--study"], db_path(given), given.count("--json") > 0, out);
  }
  if (ask_daemon(given)) return remote_ls(given, out, err);
  const std::string path = db_path(given);
  std::vector<JobRecord> jobs;
  if (db_exists(path)) jobs = ResultsStore(path).list();
  if (given.count("--json")) {
    json all = json::array();
    for (const JobRecord& j : jobs) all.push_back(job_json(j));
    out << all.dump(2) << '\n';
    return kOk;
  }
  if (jobs.empty()) {
    err << "no jobs in " << path << '\n';
    return kOk;
  }
  std::vector<std::vector<std::string>> rows = {{"ID", "KIND", "STATE", "CREATED", "SUMMARY"}};
  bool outdated = false;
  for (const JobRecord& j : jobs) {
    outdated = outdated || may_be_outdated(j);
    rows.push_back(
        {j.id, j.kind, j.state + (may_be_outdated(j) ? "*" : ""), j.created_at, highlights(j)});
  }
  print_table(out, rows);
  if (outdated)
    out << "* a daemon's job as last watched; the daemon may know more (`mdem watch ID` "
           "fetches it, `mdem ls --server HOST:PORT` asks the daemon)\n";
  return kOk;
}

void print_document(std::ostream& os, const char* title, const std::string& text) {
  os << title << ":\n";
  const json j = parse_or_text(text);
  if (j.is_null())
    os << "  (none yet)";
  else
    write_json(os, j);
  os << '\n';
}

void print_job(std::ostream& os, const JobRecord& job, const std::vector<std::string>& columns,
               std::size_t frames, std::size_t snapshots) {
  std::vector<std::vector<std::string>> rows = {
      {"id:", job.id}, {"kind:", job.kind}, {"state:", job.state}};
  if (!job.reason.empty()) rows.push_back({"reason:", job.reason});
  rows.push_back({"created:", job.created_at});
  rows.push_back({"finished:", job.finished_at.empty() ? "-" : job.finished_at});
  // From the report's performance block (a local run's; the daemon's show has its own rows).
  const json report = parse_or_text(job.summary_json);
  if (report.is_object() && report.contains("performance") && report["performance"].is_object()) {
    const json& perf = report["performance"];
    if (perf.contains("wall_s") && perf["wall_s"].is_number())
      rows.push_back({"elapsed:", duration_text(perf["wall_s"].get<double>())});
    if (perf.contains("job_data_bytes") && perf["job_data_bytes"].is_number()) {
      char mb[32];
      std::snprintf(mb, sizeof mb, "%.1f", perf["job_data_bytes"].get<double>() / 1e6);
      rows.push_back({"memory:", std::string("job data ") + mb +
                                     " MB (its peak; the run's last "
                                     "lines give the process's)"});
    }
  }
  std::string cols;
  for (const std::string& c : columns) cols += (cols.empty() ? "" : ", ") + c;
  rows.push_back({"frames:", std::to_string(frames) + (cols.empty() ? "" : " (" + cols + ")")});
  rows.push_back({"snapshots:", std::to_string(snapshots)});
  print_table(os, rows);
  print_document(os, "spec", job.spec_json);
  print_document(os, "report", job.summary_json);
}

int run_show(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  FlagSpec spec{{"--db"}, {"--json", "--local"}};
  add_connection_flags(spec);
  auto [id, given] = parse_id_and_flags(args, spec);
  if (ask_daemon(given)) return remote_show(id, given, out, err);
  const auto store = open_store(db_path(given), id);
  const JobRecord job = resolve(*store, id);
  const std::vector<std::string> columns = store->columns(job.id);
  const std::size_t frames = store->frame_count(job.id), snaps = store->snapshot_count(job.id);
  if (!given.count("--json")) {
    print_job(out, job, columns, frames, snaps);
    return kOk;
  }
  json j = job_json(job);
  j["columns"] = columns;
  j["frames"] = frames;
  j["snapshots"] = snaps;
  write_json(out, j);
  out << '\n';
  return kOk;
}

const char* export_extension(const std::string& format) {
  if (format == "xyz") return ".xyz";
  if (format == "vtk") return ".pvd";
  if (format == "csv") return ".csv";
  throw UsageError("--format: unknown format '" + format + "' (allowed: xyz, vtk, csv)");
}

int run_export(const std::vector<std::string>& args, std::ostream& out) {
  const FlagSpec spec{{"--format", "--out", "--db"}, {}};
  auto [id, given] = parse_id_and_flags(args, spec);
  if (!given.count("--format")) throw UsageError("--format: missing (allowed: xyz, vtk, csv)");
  const std::string format = given["--format"];
  const char* ext = export_extension(format);
  if (format == "vtk" && given.count("--out") && fs::path(given["--out"]).extension() != ".pvd")
    throw UsageError("--out: '" + given["--out"] + "' must end in .pvd for --format vtk");
  const auto store = open_store(db_path(given), id);
  const JobRecord job = resolve(*store, id);
  const std::string path = given.count("--out") ? given["--out"] : job.id + ext;
  std::vector<std::string> files;
  if (format == "xyz") files = export_xyz(*store, job, path);
  if (format == "vtk") files = export_vtk(*store, job, path);
  if (format == "csv") files = export_csv(*store, job, path);
  out << "wrote " << files.front();
  if (files.size() > 1) out << " and " << files.size() - 1 << " .vtp file(s) next to it";
  out << '\n';
  return kOk;
}

int run_plot(const std::vector<std::string>& args, std::ostream& out) {
  const FlagSpec spec{{"--out", "--columns", "--x", "--db"}, {}};
  auto [id, given] = parse_id_and_flags(args, spec);
  if (is_study_id(id)) {
    for (const char* f : {"--columns", "--x"})
      if (given.count(f))
        throw UsageError(std::string(f) + ": not for a study (its plot is fixed)");
    return plot_study(id, db_path(given), given.count("--out") ? given["--out"] : "", out);
  }
  if (given.count("--out")) plot_terminal(given["--out"]);  // a bad extension before any work
  const auto store = open_store(db_path(given), id);
  const JobRecord job = resolve(*store, id);
  PlotRequest request;
  request.title = job.id + " (" + job.kind + ")";
  request.columns = store->columns(job.id);
  // The kind's own picture (a tensile job's stress-strain curve), else the energy overview.
  const JobKind* kind = job_kinds().find(job.kind);
  if (!given.count("--columns") && kind && !kind->plot.columns.empty()) {
    std::string wanted;
    for (const std::string& c : kind->plot.columns) wanted += (wanted.empty() ? "" : ",") + c;
    request.selected = select_columns(request.columns, wanted);
    request.x = kind->plot.x;
    request.x_scale = kind->plot.x_scale;
    request.x_label = kind->plot.x_label;
  } else {
    request.selected =
        select_columns(request.columns, given.count("--columns") ? given["--columns"] : "");
    request.energy_overview = !given.count("--columns");
  }
  if (given.count("--x")) {
    request.x = given["--x"];
    request.x_scale = 1.0;
    request.x_label.clear();
  }
  check_x_column(request.columns, request.x);
  request.out_path = given.count("--out") ? given["--out"] : job.id + ".png";
  const std::vector<SeriesFrame> frames = store->frames(job.id);
  render_plot(request, frames);
  out << "wrote " << request.out_path << " (" << request.selected.size() << " column(s), "
      << frames.size() << " frames)\n";
  return kOk;
}

}  // namespace

int ls(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  return guarded("ls", args, out, err, print_ls_help, [&] { return run_ls(args, out, err); });
}

int show(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  return guarded("show", args, out, err, print_show_help, [&] { return run_show(args, out, err); });
}

int export_job(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  return guarded("export", args, out, err, print_export_help,
                 [&] { return run_export(args, out); });
}

int plot(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  return guarded("plot", args, out, err, print_plot_help, [&] { return run_plot(args, out); });
}

}  // namespace mdem::cli
