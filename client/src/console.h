#pragma once
// What a job shows on the terminal, shared by `mdem run` (in-process) and `mdem watch` (a
// daemon's job): the progress bar, Ctrl-C, and the final report in words.
#include <atomic>
#include <chrono>
#include <optional>
#include <ostream>
#include <string>

#include "flags.h"
#include "mdem/job/job.h"

namespace mdem::cli {

// The terminal's width in columns: standard error's window size (ioctl TIOCGWINSZ), else
// $COLUMNS, else 80; at least 20.
int terminal_columns();

// Progress: a redrawn bar with ETA on a terminal, a plain line every 10 % otherwise. The ETA
// extrapolates from the first progress seen, so a watch that joins a job half-way is not misled
// by the part it did not see. The bar is exactly columns - 1 characters wide (the bar shrinks
// first, then the text is cut), so it never wraps; plain lines and notes go to `lines` when
// given (a run's log tee), else to `err`; the bar and its wipes go to `err` only.
class ProgressReporter {
 public:
  ProgressReporter(std::ostream& err, bool tty, bool quiet, std::ostream* lines = nullptr,
                   int columns = terminal_columns())
      : err_(err), lines_(lines ? *lines : err), tty_(tty), quiet_(quiet), columns_(columns) {}
  void operator()(const JobProgress& p);
  // A line of text (a log line, a notice) between progress updates: on a terminal the bar is
  // wiped first and redrawn by the next update.
  void note(const std::string& line);
  // Wipes a bar left on the terminal (before other text is written there); the next update
  // draws it again.
  void clear();
  // Ends a bar left open (a job that stopped before its last step).
  void finish();

 private:
  static std::string clock(double s);
  double seconds() const;
  std::ostream& err_;
  std::ostream& lines_;
  bool tty_, quiet_;
  int columns_;
  bool bar_open_ = false;
  int last_decile_ = -1;
  std::optional<double> frac0_;  // the first fraction seen
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

// True when `err` is std::cerr and that is a terminal (the bar), false when piped (plain lines).
bool is_terminal(const std::ostream& err);

// Catches Ctrl-C (SIGINT), SIGTERM and SIGHUP while alive, restoring the previous handlers
// after: the handler only sets the flag that interrupted() reads, the same flag a job's run loop
// polls (JobObserver::cancelled), so each of them stops a job at its next poll and the job ends
// CANCELLED with what it computed kept. signal_name(): "SIGINT", "SIGTERM", "SIGHUP" (the first
// caught since the guard was made), "" when none. A SIGHUP ignored before (nohup) stays ignored.
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  static bool interrupted();
  static const char* signal_name();

 private:
  static constexpr int kSignals = 3;
  void (*previous_[kSignals])(int);
};

// A job's final report (the document `mdem run <kind> --json` prints: job_id, kind, state,
// reason?, summary, accuracy, performance, and db) in words: the outcome on `out` (and a failure
// on `err`), the summary's highlights, accuracy and speed, and where the results are.
// time_ps: the simulated time, when known.
void print_report(std::ostream& out, std::ostream& err, const json& doc,
                  std::optional<double> time_ps);

}  // namespace mdem::cli
