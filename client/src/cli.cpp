// Subcommand dispatch of `mdem`.
#include "mdem/cli.h"

#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "mdem/suggest.h"

#ifndef MDEM_VERSION
#define MDEM_VERSION "unknown"
#endif

namespace mdem::cli {
namespace {

const std::vector<std::string> kCommands = {"run",  "submit", "watch", "cancel", "resume", "ls",
                                            "show", "export", "plot",  "probe",  "help"};

void print_usage(std::ostream& os) {
  os << "mdem " MDEM_VERSION
        " - mesoscopic distinct element simulations of carbon-nanotube mechanics\n"
        "\n"
        "Usage: mdem <command> [flags]\n"
        "\n"
        "Commands:\n"
        "  run <kind>     run a job in this process (e.g. `mdem run twist`, `mdem run bundle`)\n"
        "  submit <kind>  queue a job on the mdemd daemon (same flags as run; --watch follows it)\n"
        "  watch ID       follow a daemon's job, storing its results in the local database\n"
        "  cancel ID      cancel a daemon's job (what it produced is kept)\n"
        "  resume ID      queue a daemon's job that hit its --time-limit (TIMEOUT) again, from\n"
        "                 its checkpoint\n"
        "  ls             list the jobs in the local results database (--server: on the daemon)\n"
        "  show ID        show one job: state, spec, summary, frame and snapshot counts\n"
        "                 (--server: the daemon's view)\n"
        "  export ID      write a job's results as extended XYZ (OVITO), VTK (ParaView) or CSV\n"
        "  plot ID        draw a job's time series to a .png or .svg with gnuplot\n"
        "  study <kind>   run one job spec over several values of its settings (--vary) and\n"
        "                 measure each result's error against wall time\n"
        "  probe          evaluate one contact model for two elements and print JSON\n"
        "  help [cmd]     show this help, or the help of one command\n"
        "\n"
        "Flags:\n"
        "  -h, --help     show this help\n"
        "  --version      print the version\n"
        "\n"
        "The daemon: --server HOST:PORT, else $MDEM_SERVER, else `server:` in the config file\n"
        "($MDEM_CONFIG, else $XDG_CONFIG_HOME/mdem/config.yaml, else ~/.config/mdem/config.yaml,\n"
        "with keys server, token_file, tls, ca_file); the token from --token-file FILE, else\n"
        "$MDEM_TOKEN, else `token_file:`. submit, watch and cancel use the config file's server;\n"
        "ls and show ask the daemon only with --server or $MDEM_SERVER. Results of every job,\n"
        "run here or on the daemon, go to one local database (--db PATH, else $MDEM_DB, else\n"
        "~/.local/share/mdem/results.db), so export and plot work alike on both.\n"
        "\n"
        "Exit codes: 0 success; 1 the job failed or was cancelled (also: the daemon refused the\n"
        "token or the permission, no such job, a per-user limit); 2 usage error (bad flag, spec,\n"
        "config or token file); 3 the daemon could not be reached or did not answer (130: a\n"
        "watch stopped by Ctrl-C).\n"
        "\n"
        "Run `mdem <command> --help` for the flags of a command.\n";
}

int dispatch(const std::vector<std::string>& argv_tail, std::ostream& out, std::ostream& err) {
  if (argv_tail.empty()) {
    print_usage(err);
    return kUsage;
  }
  const std::string& cmd = argv_tail.front();
  const std::vector<std::string> rest(argv_tail.begin() + 1, argv_tail.end());
  if (cmd == "probe") return probe(rest, out, err);
  if (cmd == "run") return run(rest, out, err);
  if (cmd == "study") return study(rest, out, err);
  if (cmd == "submit") return submit(rest, out, err);
  if (cmd == "watch") return watch(rest, out, err);
  if (cmd == "cancel") return cancel(rest, out, err);
  if (cmd == "resume") return resume_remote(rest, out, err);
  if (cmd == "ls") return ls(rest, out, err);
  if (cmd == "show") return show(rest, out, err);
  if (cmd == "export") return export_job(rest, out, err);
  if (cmd == "plot") return plot(rest, out, err);
  if (cmd == "--help" || cmd == "-h") {
    print_usage(out);
    return kOk;
  }
  if (cmd == "help") {
    if (rest.empty() || rest.front() == "--help" || rest.front() == "-h" ||
        rest.front() == "help") {
      print_usage(out);
      return kOk;
    }
    if (rest.front() == "probe") return probe({"--help"}, out, err);
    if (rest.front() == "run") return run({"--help"}, out, err);
    if (rest.front() == "study") return study({"--help"}, out, err);
    if (rest.front() == "submit") return submit({"--help"}, out, err);
    if (rest.front() == "watch") return watch({"--help"}, out, err);
    if (rest.front() == "cancel") return cancel({"--help"}, out, err);
    if (rest.front() == "resume") return resume_remote({"--help"}, out, err);
    if (rest.front() == "ls") return ls({"--help"}, out, err);
    if (rest.front() == "show") return show({"--help"}, out, err);
    if (rest.front() == "export") return export_job({"--help"}, out, err);
    if (rest.front() == "plot") return plot({"--help"}, out, err);
    err << "mdem help: unknown command '" << rest.front() << "'"
        << did_you_mean(rest.front(), kCommands) << "\n\n";
    print_usage(err);
    return kUsage;
  }
  if (cmd == "--version" || cmd == "version") {
    out << "mdem " MDEM_VERSION "\n";
    return kOk;
  }
  if (!cmd.empty() && cmd.front() == '-')
    err << "mdem: unknown flag '" << cmd << "'" << did_you_mean(cmd, {"--help", "--version"})
        << "\n\n";
  else
    err << "mdem: unknown command '" << cmd << "'" << did_you_mean(cmd, kCommands) << "\n\n";
  print_usage(err);
  return kUsage;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args;
  for (int i = 1; i < argc; ++i) args.emplace_back(argv[i]);
  try {
    return dispatch(args, std::cout, std::cerr);
  } catch (const std::exception& e) {
    std::cerr << "mdem: error: " << e.what() << "\n";
    return kJobFailed;
  }
}

}  // namespace mdem::cli
