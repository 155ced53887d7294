#pragma once
// The `mdem` command-line interface: subcommand dispatch and the commands themselves, in a
// library so tests can call a command in-process with their own streams.
#include <ostream>
#include <string>
#include <vector>

namespace mdem::cli {

// Process exit codes, distinct so scripts can tell a bad command line from a failed job.
enum ExitCode {
  kOk = 0,
  kJobFailed = 1,  // the command ran but the job (or the evaluation) failed
  kUsage = 2,      // bad command line: unknown subcommand or flag, malformed or out-of-range value
};

// Entry point of the `mdem` binary: dispatches `probe`, `run`, `help`, `--help`, `--version`.
// An unknown subcommand prints the usage to stderr and returns kUsage.
int main(int argc, char** argv);

// `mdem probe [flags]`: evaluates one contact model (anisotropic vdW, its PFC variant, or the
// intra-tube parallel bond) for two elements and writes one JSON object to `out`. `args` are the
// arguments after the subcommand. Errors go to `err`; returns an ExitCode.
int probe(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// `mdem run <kind> [flags]`: runs a job in-process (client/src/run.cpp).
int run(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// Commands on the local results database (client/src/results_commands.cpp); `--db PATH` picks
// the database. `mdem ls`: the jobs, newest first. `mdem show ID`: one job with its spec and
// summary. `mdem export ID --format xyz|vtk|csv`: files for OVITO, ParaView or a spreadsheet.
// `mdem plot ID`: the time series drawn to .png/.svg by gnuplot.
int ls(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int show(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int export_job(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);
int plot(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace mdem::cli
