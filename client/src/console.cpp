#include "console.h"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <iterator>
#include <sstream>

#include "mdem/job_kinds.h"
#include "mdem/job_state.h"

namespace mdem::cli {
namespace {

constexpr int kCaught[] = {SIGINT, SIGTERM, SIGHUP};
std::atomic<int> g_signal{0};  // the first signal caught; 0: none
static_assert(std::atomic<int>::is_always_lock_free);
extern "C" void on_interrupt(int sig) {
  int none = 0;
  g_signal.compare_exchange_strong(none, sig);
}

constexpr int kBarWidth = 30;  // the bar's cells at most

}  // namespace

int terminal_columns() {
  int cols = 0;
  winsize ws{};
  if (ioctl(STDERR_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0) {
    cols = ws.ws_col;
  } else if (const char* env = std::getenv("COLUMNS")) {
    char* end = nullptr;
    const long c = std::strtol(env, &end, 10);
    if (end != env && *end == '\0' && c > 0 && c < 10000) cols = static_cast<int>(c);
  }
  return std::max(20, cols ? cols : 80);
}

void ProgressReporter::operator()(const JobProgress& p) {
  if (quiet_ || p.total_steps <= 0) return;
  const double frac = static_cast<double>(p.step) / p.total_steps;
  if (!frac0_) frac0_ = frac;
  const double wall = seconds();
  const double done = frac - *frac0_;
  const double eta = done > 0 ? wall * (1 - frac) / done : 0;
  if (tty_) {
    std::ostringstream tail;
    tail << "] " << std::setw(3) << static_cast<int>(frac * 100) << "%  t " << std::fixed
         << std::setprecision(1) << p.time_ps << " ps  " << std::setw(9) << p.phase << "  ETA "
         << clock(eta);
    // The line fills columns - 1 (the last column would wrap on some terminals): the bar takes
    // what the text leaves, up to kBarWidth cells; a terminal too narrow for a bar of 5 cells
    // gets the text cut instead.
    const int room = columns_ - 1;
    const int cells = std::clamp(room - 1 - static_cast<int>(tail.str().size()), 5, kBarWidth);
    const int filled = static_cast<int>(frac * cells);
    std::string line(1, '[');
    line.append(filled, '#').append(cells - filled, '-').append(tail.str());
    line.resize(room, ' ');
    err_ << "\r" << line << std::flush;
    bar_open_ = p.step != p.total_steps;
    if (!bar_open_) err_ << "\n";
  } else if (p.step == 0 || static_cast<int>(frac * 10) > last_decile_) {
    last_decile_ = static_cast<int>(frac * 10);
    lines_ << "  step " << p.step << "/" << p.total_steps << "  t = " << std::fixed
           << std::setprecision(1) << p.time_ps << " ps  " << p.phase << "  wall " << clock(wall)
           << "  ETA " << clock(eta) << "\n"
           << std::defaultfloat << std::flush;
  }
}

void ProgressReporter::clear() {
  if (bar_open_) err_ << "\r" << std::string(columns_ - 1, ' ') << "\r" << std::flush;
  bar_open_ = false;
}

void ProgressReporter::note(const std::string& line) {
  clear();
  lines_ << line << "\n" << std::flush;
}

void ProgressReporter::finish() {
  if (bar_open_) err_ << "\n";
  bar_open_ = false;
}

std::string ProgressReporter::clock(double s) {
  const long t = static_cast<long>(s + 0.5);
  std::ostringstream o;
  o << t / 60 << ":" << std::setw(2) << std::setfill('0') << t % 60;
  return o.str();
}

double ProgressReporter::seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
}

bool is_terminal(const std::ostream& err) { return &err == &std::cerr && isatty(STDERR_FILENO); }

InterruptGuard::InterruptGuard() {
  static_assert(std::size(kCaught) == kSignals);
  g_signal = 0;
  for (int k = 0; k < kSignals; ++k) {
    previous_[k] = std::signal(kCaught[k], on_interrupt);
    // Under nohup SIGHUP is ignored on purpose: it stays so.
    if (kCaught[k] == SIGHUP && previous_[k] == SIG_IGN) std::signal(SIGHUP, SIG_IGN);
  }
}

InterruptGuard::~InterruptGuard() {
  for (int k = 0; k < kSignals; ++k) std::signal(kCaught[k], previous_[k]);
}

bool InterruptGuard::interrupted() { return g_signal.load() != 0; }

const char* InterruptGuard::signal_name() {
  switch (g_signal.load()) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "";
  }
}

namespace {

// The value at key of an object, or nullopt when absent or of another type.
template <class T>
std::optional<T> get(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key)) return std::nullopt;
  const json& v = j[key];
  if constexpr (std::is_same_v<T, std::string>) {
    if (v.is_string()) return v.get<std::string>();
  } else if constexpr (std::is_arithmetic_v<T>) {
    if (v.is_number()) return v.get<T>();
  }
  return std::nullopt;
}

}  // namespace

void print_report(std::ostream& out, std::ostream& err, const json& doc,
                  std::optional<double> time_ps) {
  const std::string id = get<std::string>(doc, "job_id").value_or("?");
  const std::string kind = get<std::string>(doc, "kind").value_or("job");
  const std::string state = get<std::string>(doc, "state").value_or("?");
  const std::string reason = get<std::string>(doc, "reason").value_or("");
  const json summary = doc.is_object() && doc.contains("summary") ? doc["summary"] : json();
  const json acc = doc.is_object() && doc.contains("accuracy") ? doc["accuracy"] : json();
  const json perf = doc.is_object() && doc.contains("performance") ? doc["performance"] : json();
  if (!time_ps) time_ps = get<double>(summary, "simulated_ps");

  const std::optional<JobState> st = parse_job_state(state);
  const bool failed = st == v1::FAILED;
  if (failed) err << kind << " " << id << ": FAILED: " << reason << "\n";
  out << kind << " " << id << ": " << state;
  if (const auto steps = get<long>(perf, "steps")) {
    out << " after " << *steps << " steps";
    if (time_ps) out << " (" << *time_ps << " ps)";
  }
  out << "\n";
  if (st == v1::CANCELLED && !reason.empty()) out << "  " << reason << "\n";
  if (!failed) {
    // The kind's declared summary layout (jobs/src/<kind>_job_kind.cpp), line by line.
    if (const SummaryLayout* layout = summary_layout(kind))
      for (const std::string& line : summary_lines(*layout, summary)) out << "  " << line << "\n";
    else if (summary.is_object() && !summary.empty())
      out << "  summary " << summary.dump() << "\n";
    const auto balance = get<double>(acc, "energy_balance_error");
    const auto dt = get<double>(acc, "dt_ps");
    const auto ratio = get<double>(acc, "dt_over_critical");
    if (balance && dt && ratio)
      out << "  energy balance error " << *balance << ", dt " << *dt * 1000 << " fs = " << *ratio
          << " x critical step\n";
  }
  const auto wall = get<double>(perf, "wall_s");
  const auto rate = get<double>(perf, "element_steps_per_s");
  if (wall && rate) out << "  " << *wall << " s wall, " << *rate << " element-steps/s\n";
  if (const auto db = get<std::string>(doc, "db"))
    out << "  results: mdem show " << id << " --db " << *db << "\n";
}

}  // namespace mdem::cli
