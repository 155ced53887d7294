#pragma once
// The end of the tensile film's pre-relaxation (tensile.md §3.3): no pair left on an overlap
// branch of its contact law and nothing moving fast, checked every 100 steps, at most 50 ps.
#include <memory>
#include <string>

#include "mdem/job/stage.h"

namespace mdem {

struct PrerelaxLimits {
  double cnt_cnt = 0.4;  // CNT–CNT pairs need D >= this (the vdW law's linear branch starts there)
  double np_cnt = 0.8;   // NP–CNT pairs: D >= this
  double np_np = 0.1;    // NP–NP pairs: D >= this
  double max_speed = 0.05;  // every element slower than this (nm/ps)
  double max_time = 50;     // ps: the stage ends then whatever the state
  long check_every = 100;   // steps
};

// What the last check saw. A kind of pair the system has no model for (or no pair of) reads +inf.
struct PrerelaxStatus {
  double min_cnt_cnt = 0, min_np_cnt = 0, min_np_np = 0;  // smallest D per kind of pair
  double max_speed = 0;                                   // nm/ps
  bool overlap_free = false, slow = false;
  bool checked = false;
};

// Met when, over the pairs of each contact model the system holds (AnisotropicVdw, NpCntContact,
// NpNpContact; its neighbour sub-list), no D is below its limit and the largest element speed is
// below max_speed. D is each kernel's own (vdw_separation, NpCntKernel::separation,
// NpNpKernel::separation). The system must be initialized (its lists are current after a step).
class PrerelaxCriterion final : public StopCriterion {
 public:
  // Throws std::invalid_argument naming the limit and its range (all finite; speeds, time and
  // check_every > 0).
  explicit PrerelaxCriterion(PrerelaxLimits limits = {});
  bool met(const System& sys) override;
  // Figures of the state of `sys` now (what met() compares).
  PrerelaxStatus measure(const System& sys) const;
  const PrerelaxStatus& last() const { return last_; }
  const PrerelaxLimits& limits() const { return limits_; }
  // Why the stage stopped, from the last check: "settled: ..." when met, else "cap of 50 ps
  // reached: <the conditions that still fail>".
  std::string reason() const;
  // The stop condition of the pre-relaxation stage at step dt (ps): this criterion every
  // check_every steps, at most ceil(max_time / dt) steps. Throws std::invalid_argument for a dt
  // that is not finite and > 0.
  static StopCondition stop(std::shared_ptr<PrerelaxCriterion> c, double dt);
  // The last check's figures are part of a checkpoint: a run resumed after it stops with the
  // same reason as one never stopped (the stage's end reads them).
  void save_state(StateWriter& w) const override;
  void load_state(StateReader& r) override;

 private:
  PrerelaxLimits limits_;
  PrerelaxStatus last_;
};

// After the pre-relaxation: every element's velocity and angular velocity zero (the clock and the
// energy ledger: System::restart_clock).
void zero_motion(Elements& el);

}  // namespace mdem
