// `mdem run` while and after a job runs: the thermo table (header with units, rows at
// --thermo-every showing what the results database stores), the log file beside the results
// (a byte-for-byte copy of piped output; none with --no-log; an unwritable path refused before
// the job exists), the "Loop time" block, and a progress bar that fits a 60-column terminal
// (the reporter at 60 columns, and the real binary on a pseudo-terminal of 60 columns).
#include <gtest/gtest.h>
#include <poll.h>
#include <pty.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <thread>

#include "../client/src/console.h"
#include "../client/src/loop_timing.h"
#include "../client/src/results_store.h"
#include "mdem/cli.h"
#include "support.h"

namespace {

namespace fs = std::filesystem;
using mdem::testing::contains;
using mdem::testing::slurp;
using mdem::testing::TempDir;
using mdem::testing::with;

// A small twist: 7 tubes x 6 segments, ramp 1 ps + hold 1 ps, frames every 1 ps (the default).
const std::vector<std::string> kSmall = {"--layers", "2",      "--length", "8",         "--torque",
                                         "1",        "--hold", "1",        "--threads", "1"};
constexpr double kDuration = 2.0;  // ps

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> v;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) v.push_back(l);
  return v;
}

std::vector<std::string> tokens(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> v;
  for (std::string t; in >> t;) v.push_back(t);
  return v;
}

bool is_number(const std::string& t, double* v = nullptr) {
  char* end = nullptr;
  const double x = std::strtod(t.c_str(), &end);
  if (v) *v = x;
  return end != t.c_str() && *end == '\0';
}

// The table in a run's standard output: its header tokens and its rows (lines right after the
// header with as many cells, all numbers).
struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
  int column(const std::string& h) const {
    const auto it = std::find(header.begin(), header.end(), h);
    return it == header.end() ? -1 : static_cast<int>(it - header.begin());
  }
};

Table parse_table(const std::string& out) {
  Table t;
  const auto ls = lines_of(out);
  std::size_t i = 0;
  while (i < ls.size() && (tokens(ls[i]).empty() || tokens(ls[i]).front() != "Step")) ++i;
  if (i == ls.size()) return t;
  t.header = tokens(ls[i]);
  for (++i; i < ls.size(); ++i) {
    const auto cells = tokens(ls[i]);
    if (cells.size() != t.header.size()) break;
    std::vector<double> row;
    for (const std::string& c : cells) {
      double v;
      if (!is_number(c, &v)) return t;
      row.push_back(v);
    }
    t.rows.push_back(row);
  }
  return t;
}

std::string job_id_of(const std::string& text) {
  std::smatch m;
  return std::regex_search(text, m, std::regex("j-[0-9a-z-]+")) ? m.str() : "";
}

TEST(CliThermo, TableHasUnitsAndRowsAtTheIntervalShowingTheStoredFrames) {
  TempDir d("mdem-thermo");
  const std::string db = d.file("r.db");
  for (const double every : {1.0, 2.0}) {
    SCOPED_TRACE(every);
    const auto r = mdem::testing::run_job(
        "twist", with(kSmall, {"--db", db, "--thermo-every", std::to_string(every)}));
    ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
    const Table t = parse_table(r.out);
    ASSERT_FALSE(t.header.empty()) << r.out;
    // Every header cell is name or name[unit].
    const std::regex cell(R"(^[A-Za-z_]+(\[[^\]]+\])?$)");
    for (const std::string& h : t.header) EXPECT_TRUE(std::regex_match(h, cell)) << h;
    for (const char* h : {"Step", "Time[ps]", "bond_tension[eV]", "bond_torsion[eV]", "vdw[eV]",
                          "kinetic[eV]", "balance_error", "applied_torque[nN·nm]",
                          "twist_angle[deg]", "rope_radius[nm]", "topological_charge"})
      EXPECT_GE(t.column(h), 0) << h << " missing from the header";
    // Terms a twist does not have are not shown.
    EXPECT_LT(t.column("np_cnt[eV]"), 0);
    EXPECT_LT(t.column("contact[eV]"), 0);

    // Rows at 0, every, 2 every, ... up to the end, plus the last frame if it falls between.
    const int n_bins = static_cast<int>(std::floor(kDuration / every + 1e-9)) + 1;
    ASSERT_GE(static_cast<int>(t.rows.size()), n_bins) << r.out;
    ASSERT_LE(static_cast<int>(t.rows.size()), n_bins + 1) << r.out;
    const int time = t.column("Time[ps]"), step = t.column("Step");
    EXPECT_EQ(t.rows.front()[step], 0);
    // Frames fall on whole steps (every round(1 ps / dt) steps): a row is within half a step
    // (dt = 24 fs here) per frame of the multiple it stands for.
    for (int k = 1; k < n_bins; ++k)
      EXPECT_NEAR(t.rows[k][time], k * every, 0.0125 * k * every) << k;
    EXPECT_NEAR(t.rows.back()[time], kDuration, 0.01);

    // Each row is the stored frame of its step, to the 6 digits printed.
    mdem::cli::ResultsStore store(db);
    const std::string id = job_id_of(r.err);
    const auto cols = store.columns(id);
    const auto frames = store.frames(id);
    auto col = [&](const std::string& name) {
      return static_cast<int>(std::find(cols.begin(), cols.end(), name) - cols.begin());
    };
    for (const auto& row : t.rows) {
      const auto f = std::find_if(frames.begin(), frames.end(),
                                  [&](const auto& fr) { return fr.step == row[step]; });
      ASSERT_NE(f, frames.end()) << "no stored frame at step " << row[step];
      auto near6 = [](double a, double b) { return std::abs(a - b) <= 1e-5 * std::abs(b) + 1e-12; };
      EXPECT_TRUE(near6(row[time], f->time_ps));
      EXPECT_TRUE(near6(row[t.column("vdw[eV]")], f->values[col("vdw_eV")]));
      EXPECT_TRUE(near6(row[t.column("kinetic[eV]")], f->values[col("kinetic_translational_eV")] +
                                                          f->values[col("kinetic_rotational_eV")]));
      EXPECT_TRUE(near6(row[t.column("twist_angle[deg]")], f->values[col("twist_angle_deg")]));
    }
    // The last row's balance error is the report's.
    const auto rec = store.find(id);
    ASSERT_TRUE(rec.has_value());
    const auto doc = nlohmann::json::parse(rec->summary_json);
    EXPECT_NEAR(t.rows.back()[t.column("balance_error")],
                doc["accuracy"]["energy_balance_error"].get<double>(),
                1e-5 * doc["accuracy"]["energy_balance_error"].get<double>());
  }
}

TEST(CliThermo, IntervalBelowTheFramesIsRefusedNamingWhatIsAllowed) {
  TempDir d("mdem-thermo");
  const auto r = mdem::testing::run_job(
      "twist", with(kSmall, {"--db", d.file("r.db"), "--thermo-every", "0.5"}));
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(r.err, "--thermo-every") && contains(r.err, "frame interval")) << r.err;
  EXPECT_FALSE(fs::exists(d.file("r.db")));
}

// The "Loop time" block of a text run: its sections' percentages and element-steps/s.
TEST(CliThermo, LoopTimeBlockAddsUpAndStatesTheRate) {
  TempDir d("mdem-thermo");
  const auto r = mdem::testing::run_job("twist", with(kSmall, {"--db", d.file("r.db")}));
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  const auto ls = lines_of(r.out);
  const auto head = std::find_if(
      ls.begin(), ls.end(), [](const std::string& l) { return l.rfind("Loop time of ", 0) == 0; });
  ASSERT_NE(head, ls.end()) << r.out;
  std::smatch m;
  const std::string perf = *(head + 1);
  ASSERT_TRUE(std::regex_search(perf, m, std::regex(R"(([0-9.e+-]+) element-steps/s)"))) << perf;
  EXPECT_GT(std::stod(m[1]), 0);
  ASSERT_TRUE(std::regex_search(perf, m, std::regex(R"(([0-9.e+-]+) ns/day)"))) << perf;
  EXPECT_GT(std::stod(m[1]), 0);
  auto it =
      std::find_if(head, ls.end(), [](const std::string& l) { return l.rfind("Section", 0) == 0; });
  ASSERT_NE(it, ls.end());
  double sum = 0;
  int rows = 0;
  for (++it; it != ls.end() && !it->empty(); ++it, ++rows) {
    const auto cells = tokens(*it);
    double pct;
    ASSERT_TRUE(is_number(cells.back(), &pct)) << *it;
    EXPECT_GE(pct, 0) << *it;
    sum += pct;
  }
  // The engine's row split by System::timers() (pair forces, neighbour search, integration,
  // updaters, observables), then snapshot capture, results DB, terminal, other.
  EXPECT_EQ(rows, 9) << r.out;
  EXPECT_TRUE(contains(r.out, "  Pair forces") && contains(r.out, "  Integration")) << r.out;
  EXPECT_NEAR(sum, 100, 1);
}

// The JSON report's timing sections are measured spans of the loop: they add up to the wall time
// the runner measured on its own clock.
TEST(CliThermo, JsonTimingAddsUpToTheWallTime) {
  TempDir d("mdem-thermo");
  const auto r = mdem::testing::run_job("twist", with(kSmall, {"--db", d.file("r.db"), "--json"}));
  ASSERT_EQ(r.code, mdem::cli::kOk) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  double sum = 0;
  for (const auto& [k, v] : j["timing"].items()) {
    EXPECT_GE(v.get<double>(), 0) << k;
    sum += v.get<double>();
  }
  const double wall = j["performance"]["wall_s"].get<double>();
  EXPECT_GT(j["timing"]["steps_s"].get<double>(), 0.5 * wall);
  EXPECT_NEAR(sum, wall, 0.05 * wall + 0.02);
  EXPECT_TRUE(fs::exists(j["log"].get<std::string>()));
}

// `mdem run KIND ARGS` as a shell command.
std::string mdem_cmd(const std::vector<std::string>& args, const std::string& kind) {
  std::string cmd = std::string(MDEM_CLI_PATH) + " run " + kind;
  for (const std::string& a : args) cmd += " '" + a + "'";
  return cmd;
}

// Piped: plain lines only, and the log (on by default, beside the database) holds exactly what
// was shown; --no-log writes none.
TEST(CliThermo, PipedOutputIsPlainAndTheLogIsItsCopy) {
  TempDir d("mdem-thermo");
  const std::string db = d.file("r.db");
  const auto r = mdem::testing::run_shell(mdem_cmd(with(kSmall, {"--db", db}), "twist") + " 2>&1");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_FALSE(contains(r.out, "\r"));
  const std::string id = job_id_of(r.out);
  const fs::path log = fs::path(d.file("logs")) / (id + ".log");
  ASSERT_TRUE(fs::exists(log)) << r.out;
  EXPECT_EQ(slurp(log), r.out);
  EXPECT_TRUE(contains(r.out, "log: " + log.string())) << r.out;
  EXPECT_FALSE(parse_table(r.out).rows.empty());

  const auto quiet = mdem::testing::run_job("twist", with(kSmall, {"--db", db, "--no-log"}));
  ASSERT_EQ(quiet.code, 0);
  EXPECT_FALSE(fs::exists(fs::path(d.file("logs")) / (job_id_of(quiet.err) + ".log")));
  EXPECT_FALSE(contains(quiet.out, "log: "));
  EXPECT_EQ(std::distance(fs::directory_iterator(d.file("logs")), fs::directory_iterator()), 1);
}

TEST(CliThermo, UnwritableLogIsRefusedBeforeTheJobExists) {
  TempDir d("mdem-thermo");
  std::ofstream(d.file("plain")) << "a file, not a directory\n";
  const std::string bad = d.file("plain") + "/run.log";
  const auto r =
      mdem::testing::run_job("twist", with(kSmall, {"--db", d.file("r.db"), "--log", bad}));
  EXPECT_EQ(r.code, mdem::cli::kUsage);
  EXPECT_TRUE(contains(r.err, "--log " + bad) && contains(r.err, "--no-log")) << r.err;
  EXPECT_FALSE(fs::exists(d.file("r.db"))) << "nothing of the job may exist";
  // A directory is not a log file either.
  const auto dir =
      mdem::testing::run_job("twist", with(kSmall, {"--db", d.file("r.db"), "--log", d.file("")}));
  EXPECT_EQ(dir.code, mdem::cli::kUsage) << dir.err;
  EXPECT_FALSE(fs::exists(d.file("r.db")));
}

// Every line the bar draws fits 59 columns of a 60-column terminal, however long the numbers.
TEST(CliThermo, BarFitsSixtyColumns) {
  std::ostringstream err;
  mdem::cli::ProgressReporter bar(err, true, false, nullptr, 60);
  for (long s = 0; s <= 1000; s += 50) {
    mdem::JobProgress p;
    p.step = s;
    p.total_steps = 1000;
    p.time_ps = 123456.7 * s;
    p.phase = "pre-relaxation";
    bar(p);
  }
  std::string seg;
  int draws = 0;
  for (char c : err.str()) {
    if (c == '\r' || c == '\n') {
      EXPECT_LE(seg.size(), 59u) << seg;
      draws += !seg.empty();
      seg.clear();
    } else {
      seg += c;
    }
  }
  EXPECT_EQ(draws, 21);
  // COLUMNS is the width when standard error is no terminal.
  if (!isatty(STDERR_FILENO)) {
    setenv("COLUMNS", "60", 1);
    EXPECT_EQ(mdem::cli::terminal_columns(), 60);
    unsetenv("COLUMNS");
    EXPECT_EQ(mdem::cli::terminal_columns(), 80);
  }
}

// The binary on a pseudo-terminal 60 columns wide: the bar is redrawn in place, no line wraps,
// and the log holds what was shown without the redraws.
TEST(CliThermo, OnASixtyColumnTerminalNothingWrapsAndTheLogHasNoRedraws) {
  TempDir d("mdem-thermo");
  const std::string db = d.file("r.db");
  winsize ws{};
  ws.ws_col = 60;
  ws.ws_row = 40;
  int master = -1;
  const pid_t pid = forkpty(&master, nullptr, nullptr, &ws);
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    std::vector<std::string> args = with(kSmall, {"--db", db, "--hold", "4"});
    args.insert(args.begin(), {"mdem", "run", "twist"});
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    unsetenv("COLUMNS");
    execv(MDEM_CLI_PATH, argv.data());
    _exit(127);
  }
  std::string shown;
  char buf[4096];
  for (;;) {
    const ssize_t n = read(master, buf, sizeof buf);
    if (n <= 0) break;  // EIO once the child has gone
    shown.append(buf, n);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  close(master);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << shown;
  EXPECT_TRUE(contains(shown, "\r[")) << "no bar drawn";
  // The terminal turns "\n" into "\r\n"; every stretch between returns is a line as drawn.
  std::string seg, logged;
  for (char c : shown) {
    if (c == '\r' || c == '\n') {
      if (seg.rfind("[", 0) != 0)
        EXPECT_LE(seg.size(), 2000u);  // table rows may be wide
      else
        EXPECT_LE(seg.size(), 59u) << seg;
      seg.clear();
    } else {
      seg += c;
    }
  }
  // What the log holds: the shown text without the bar's lines and wipes.
  std::string clean;
  for (const std::string& line : lines_of(shown)) {
    std::string l = line;
    if (!l.empty() && l.back() == '\r') l.pop_back();  // the terminal's "\r\n"
    if (l.find('\r') != std::string::npos) l = l.substr(l.rfind('\r') + 1);  // after the wipes
    if (l.rfind("[", 0) == 0) continue;                                      // a finished bar
    if (l.find_first_not_of(' ') == std::string::npos && !l.empty()) continue;
    clean += l + "\n";
  }
  const std::string id = job_id_of(shown);
  const std::string log = slurp(fs::path(d.file("logs")) / (id + ".log"));
  EXPECT_FALSE(contains(log, "\r"));
  EXPECT_EQ(log, clean);
}

// The sections get the time between the callbacks as the run loop's order implies, checked with
// known sleeps: the engine's steps before a chunk's first callback, the capture between a frame
// and its snapshot, the callbacks' own work where they say, the rest as other.
TEST(CliThermo, LoopTimingChargesEachSpanToItsSection) {
  using mdem::cli::LoopTiming;
  using Event = LoopTiming::Event;
  auto nap = [](int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); };
  LoopTiming t;
  t.begin();
  nap(40);  // initialize + step 0's observe
  t.enter(Event::Frame);
  nap(20);  // storing the frame
  t.split(LoopTiming::kStore);
  nap(10);  // its thermo row
  t.leave(LoopTiming::kTerminal);
  nap(30);  // capturing the snapshot
  t.enter(Event::Snapshot);
  t.leave(LoopTiming::kStore);
  t.enter(Event::Poll);
  t.leave(LoopTiming::kOther);
  nap(25);  // a chunk of steps that reports nothing
  t.enter(Event::Poll);
  t.leave(LoopTiming::kOther);
  nap(25);  // a chunk of steps
  t.enter(Event::Progress);
  t.leave(LoopTiming::kTerminal);
  nap(10);  // a stage change
  t.end();
  // A sleep lasts at least what it asks, and a busy machine may add a few ms to each.
  auto within = [](double s, double ms) { return s >= 0.001 * ms - 1e-4 && s < 0.001 * ms + 0.03; };
  EXPECT_TRUE(within(t.seconds(LoopTiming::kSteps), 90)) << t.seconds(LoopTiming::kSteps);
  EXPECT_TRUE(within(t.seconds(LoopTiming::kStore), 20)) << t.seconds(LoopTiming::kStore);
  EXPECT_TRUE(within(t.seconds(LoopTiming::kTerminal), 10)) << t.seconds(LoopTiming::kTerminal);
  EXPECT_TRUE(within(t.seconds(LoopTiming::kSnapshot), 30)) << t.seconds(LoopTiming::kSnapshot);
  EXPECT_TRUE(within(t.seconds(LoopTiming::kOther), 10)) << t.seconds(LoopTiming::kOther);

  // With the engine's own split (once System fills StepTimers), its row is split into the four
  // parts and the observables (the rest of it); the percentages still add up.
  mdem::StepTimers engine;
  engine.pair_s = 0.040;
  engine.neighbor_s = 0.010;
  engine.integrate_s = 0.020;
  engine.updaters_s = 0.005;
  std::ostringstream os;
  mdem::cli::print_loop_timing(os, t, {10, 42, 1, 1.0, 4200.0}, &engine);
  double sum = 0;
  int rows = 0;
  bool in = false;
  for (const std::string& l : lines_of(os.str())) {
    if (l.rfind("Section", 0) == 0) {
      in = true;
      continue;
    }
    if (!in || l.empty()) continue;
    sum += std::stod(tokens(l).back());
    ++rows;
  }
  EXPECT_EQ(rows, 9) << os.str();
  EXPECT_NEAR(sum, 100, 1) << os.str();
  EXPECT_TRUE(contains(os.str(), "Pair forces") && contains(os.str(), "Neighbour search"));
}

}  // namespace
