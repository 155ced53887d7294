#include "loop_timing.h"

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <utility>
#include <vector>

#include "mdem/process_memory.h"

namespace mdem::cli {

void LoopTiming::begin() {
  s_ = {};
  mark_ = Clock::now();
  last_ = Event::Start;
}

void LoopTiming::charge(Section s) {
  const Clock::time_point now = Clock::now();
  s_[s] += std::chrono::duration<double>(now - mark_).count();
  mark_ = now;
}

void LoopTiming::enter(Event e) {
  // After the start or a poll the engine stepped (beginning a stage, initializing, and for a
  // frame observing), also up to the next poll: a chunk of steps that reported nothing (on a
  // large system most chunks end between frames); between a frame and a snapshot the snapshot
  // was captured; anything else is the loop's own.
  Section s = kOther;
  if (last_ == Event::Start || last_ == Event::Poll)
    s = kSteps;
  else if (last_ == Event::Frame && e == Event::Snapshot)
    s = kSnapshot;
  charge(s);
  last_ = e;
}

void LoopTiming::leave(Section s) { charge(s); }

void LoopTiming::split(Section s) { charge(s); }

void LoopTiming::end() { charge(kOther); }

double LoopTiming::total() const { return std::accumulate(s_.begin(), s_.end(), 0.0); }

const char* LoopTiming::key(Section s) {
  static constexpr const char* k[kSections] = {"steps_s", "snapshot_capture_s", "results_db_s",
                                               "terminal_s", "other_s"};
  return k[s];
}

namespace {

std::string fmt(const char* f, double v) {
  char buf[48];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

}  // namespace

void print_loop_timing(std::ostream& os, const LoopTiming& t, const LoopFigures& f,
                       const StepTimers* engine) {
  const double wall = t.total();
  os << "Loop time of " << fmt("%.4g", wall) << " s on " << f.threads << " thread(s) for "
     << f.steps << " steps with " << f.elements << " elements (" << fmt("%.4g", f.simulated_ps)
     << " ps simulated)\n";
  const double ns_per_day = wall > 0 ? f.simulated_ps * 1e-3 / (wall / 86400.0) : 0;
  os << "Performance: " << fmt("%.4g", ns_per_day) << " ns/day, "
     << fmt("%.4g", ns_per_day > 0 ? 24.0 / ns_per_day : 0) << " hours/ns, "
     << fmt("%.4g", f.element_steps_per_s) << " element-steps/s\n";
  // As sacct's MaxRSS: the whole process (getrusage), the results database and terminal included.
  os << "Memory: process peak RSS " << fmt("%.1f", process_rss_peak_bytes() / 1e6) << " MB\n\n";

  std::vector<std::pair<std::string, double>> rows;
  const double steps = t.seconds(LoopTiming::kSteps);
  if (engine) {
    rows.push_back({"  Pair forces", engine->pair_s});
    rows.push_back({"  Neighbour search", engine->neighbor_s});
    rows.push_back({"  Integration", engine->integrate_s});
    rows.push_back({"  Updaters", engine->updaters_s});
    rows.push_back({"  Observables (frames)", std::max(0.0, steps - engine->total())});
  } else {
    rows.push_back({"Engine steps + observables", steps});
  }
  rows.push_back({"Snapshot capture", t.seconds(LoopTiming::kSnapshot)});
  rows.push_back({"Results DB", t.seconds(LoopTiming::kStore)});
  rows.push_back({"Terminal (progress, thermo)", t.seconds(LoopTiming::kTerminal)});
  rows.push_back({"Other (stage changes, loop)", t.seconds(LoopTiming::kOther)});
  char line[128];
  std::snprintf(line, sizeof line, "%-30s %10s %8s\n", "Section", "time (s)", "%total");
  os << line;
  for (const auto& [name, s] : rows) {
    std::snprintf(line, sizeof line, "%-30s %10.4g %8.1f\n", name.c_str(), s,
                  wall > 0 ? 100.0 * s / wall : 0.0);
    os << line;
  }
}

}  // namespace mdem::cli
