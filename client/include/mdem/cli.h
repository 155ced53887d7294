#pragma once
// The `mdem` command-line interface: subcommand dispatch and the commands themselves, in a
// library so tests can call a command in-process with their own streams.
#include <ostream>
#include <string>
#include <vector>

namespace mdem::cli {

// Process exit codes, distinct so scripts can tell a bad command line from a failed job and from
// a daemon that cannot be reached.
enum ExitCode {
  kOk = 0,
  kJobFailed = 1,      // the command ran but the job (or the evaluation) failed; for a daemon's
                       // job also: the token refused, no permission, no such job, a per-user limit
  kUsage = 2,          // bad command line: unknown subcommand or flag, malformed or out-of-range
                       // value, a bad config file; a spec the daemon refused (INVALID_ARGUMENT)
  kConnection = 3,     // could not reach or talk to the daemon (down, unreachable, no answer in
                       // time, the connection lost for good while watching)
  kInterrupted = 130,  // `mdem watch` stopped by Ctrl-C (the job goes on on the daemon)
};

// Entry point of the `mdem` binary: dispatches the commands, `help`, `--help`, `--version`.
// An unknown subcommand prints the usage to stderr and returns kUsage.
int main(int argc, char** argv);

// `mdem probe [flags]`: evaluates one contact model (anisotropic vdW, its PFC variant, or the
// intra-tube parallel bond) for two elements and writes one JSON object to `out`. `args` are the
// arguments after the subcommand. Errors go to `err`; returns an ExitCode.
int probe(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// `mdem run <kind> [flags]`: runs a job in-process (client/src/run.cpp).
int run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// `mdem study <kind> --vary FIELD=v1,v2,...`: one spec run over several values of its settings,
// with the errors of the kind's results against the study's reference (client/src/study.cpp).
int study(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// Commands on the mdemd daemon (client/src/remote_commands.cpp), which keep what they learn in
// the local results database: `mdem submit <kind>` queues a job, `mdem watch ID` follows it into
// the database, `mdem cancel ID` stops it. `--server HOST:PORT` (or $MDEM_SERVER, or the config
// file) names the daemon.
int submit(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int watch(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int cancel(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
// `mdem resume ID [--time-limit T]`: queues a daemon's TIMEOUT job again from its checkpoint.
int resume_remote(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// Commands on the local results database (client/src/results_commands.cpp); `--db PATH` picks
// the database. `mdem ls`: the jobs, newest first. `mdem show ID`: one job with its spec and
// summary. `mdem export ID --format xyz|vtk|csv`: files for OVITO, ParaView or a spreadsheet.
// `mdem plot ID`: the time series drawn to .png/.svg by gnuplot.
// With --server (or $MDEM_SERVER), `ls` and `show` ask the daemon instead.
int ls(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int show(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int export_job(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int plot(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace mdem::cli
