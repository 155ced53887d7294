#pragma once
// Where a local run's wall time went, measured from outside the engine at the run loop's
// callbacks (run_job calls them in a fixed order in every chunk of steps: cancelled() before the
// steps, then frame, snapshot and progress as due), and printed as LAMMPS's "Loop time" block.
// What each section holds:
//   engine steps        from the poll before a chunk to its first callback: System::run (pair
//                       forces, neighbour search, integration, updaters) and, in a chunk that
//                       ends on a frame, the job's observables of that frame (Job::observe)
//   snapshot capture    from the frame callback to the snapshot callback (capture + decorate)
//   results DB          inside the frame and snapshot callbacks: storing them
//   terminal            inside the callbacks: progress bar or lines, thermo rows
//   other               the rest of the loop: stage changes (building a system from a packing),
//                       the loop's bookkeeping
// The engine's own split of its steps (System::timers() of every system the job ran, summed by
// Job::work(); engine/include/mdem/integrate/step_timers.h) splits the engine-steps row: pair
// forces, neighbour search, integration, updaters, and the rest of the row (the frames'
// observables, stage starts) as observables.
#include <array>
#include <chrono>
#include <ostream>
#include <string>

#include "mdem/integrate/step_timers.h"

namespace mdem::cli {

class LoopTiming {
 public:
  enum Section { kSteps, kSnapshot, kStore, kTerminal, kOther, kSections };
  // What the loop did last: where the time until the next callback goes.
  enum class Event { Start, Poll, Frame, Snapshot, Progress };

  // The loop starts now.
  void begin();
  // A callback of kind `e` starts: the time since the last callback ended goes to the section
  // the previous event implies.
  void enter(Event e);
  // The callback ends: time since the last mark goes to `s` (its own work), and the mark moves.
  void leave(Section s);
  // Inside a callback: the time since the last mark goes to `s` (for a callback doing two
  // things, e.g. storing a frame then printing its thermo row).
  void split(Section s);
  // The loop ended: the time since the last callback goes to kOther.
  void end();

  double seconds(Section s) const { return s_[s]; }
  double total() const;
  // The section's key in a report's JSON "timing" object ("steps_s", ...).
  static const char* key(Section s);

 private:
  using Clock = std::chrono::steady_clock;
  void charge(Section s);
  std::array<double, kSections> s_{};
  Clock::time_point mark_ = Clock::now();
  Event last_ = Event::Start;
};

// What the block states besides the sections.
struct LoopFigures {
  long steps = 0, elements = 0;
  int threads = 1;
  double simulated_ps = 0;
  double element_steps_per_s = 0;
};

// The "Loop time" block: wall time, ns/day and hours/ns, element-steps/s, then each section's
// seconds and % of the loop (the engine-steps row split by `engine` when given).
void print_loop_timing(std::ostream& os, const LoopTiming& t, const LoopFigures& f,
                       const StepTimers* engine = nullptr);

}  // namespace mdem::cli
