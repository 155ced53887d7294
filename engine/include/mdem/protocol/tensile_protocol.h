#pragma once
// The tensile and cyclic grip protocol (tensile.md §3.5–3.6): two clamped slabs at the film's x
// ends, moved apart (or together) along x by a prescribed motion law.
//
// Grips (§3.5): x_lo and x_hi are the 0.5th and 99.5th percentiles of segment-centre x at the
// start; the left grip holds every element (segments and NPs) with x ≤ x_lo + w, the right grip
// every element with x ≥ x_hi − w (w = 15 nm). They are declared as the groups kGripLeft and
// kGripRight. A grip element's x velocity is prescribed, its y and z velocities are prescribed 0
// and its rotations are fixed (a clamp).
//
// Motion laws, in loading time s (system time minus the protocol's start), with L0 the nominal
// film length and ε the engineering strain (u_R − u_L)/L0; the right grip sits at +½L0·ε(s) from
// where it started, the left at −½L0·ε(s):
//   monotonic  ε̇(s) = ε̇·σ(s/t_a), σ(τ) = 3τ² − 2τ³ for τ < 1 and 1 after (a C¹ smoothstep ramp),
//              so ε(s) = ε̇ t_a S(s/t_a), S(τ) = τ³ − τ⁴/2, during the ramp and
//              ε(s) = ε̇ (s − t_a/2) after it (½ ε̇ t_a at the ramp's end);
//   cyclic     ε(s) = −(ε_a/2)(1 − cos 2πs/P), P = 2ε_a/ε̇_avg, for n cycles, then held at 0.
// The velocity prescribed for a step [t, t + dt] is the motion law's mean over it, (u(t + dt) −
// u(t))/dt, the exact derivative integrated over the step: the grips then sit on the closed form
// at every step (to rounding), however the rate changes. Before the step is known (dt = 0 and no
// dt in the settings, at the first initialisation) the instantaneous derivative is used.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mdem/protocol/protocol.h"

namespace mdem {

struct Elements;

inline constexpr std::string_view kGripLeft = "tensile.grip_left";
inline constexpr std::string_view kGripRight = "tensile.grip_right";

struct GripSettings {
  double width = 15.0;          // w (nm): each grip's depth from its film end
  double min_fraction = 0.005;  // each grip must hold at least this fraction of the elements
};

struct GripSelection {
  double x_lo = 0, x_hi = 0;             // P0.5 and P99.5 of segment-centre x (nm)
  std::vector<std::size_t> left, right;  // element indices, ascending
};

// Selects both grips by the rule above and declares them as the groups kGripLeft and kGripRight
// in el.groups. Throws std::invalid_argument naming the field and its allowed range for a width
// that is not finite and > 0 or that makes the grips meet (2w ≥ x_hi − x_lo), a min_fraction
// outside [0, 1), no CNT segment, grip groups already declared, or a grip holding fewer than
// min_fraction of the elements (the message gives the counts).
GripSelection select_grips(Elements& el, const GripSettings& s = {});

enum class TensileMode { Monotonic, Cyclic };

struct MonotonicLoading {
  double strain_rate = 1e-4;   // ε̇ (/ps); 1e-7/fs
  double ramp_time = 600.0;    // t_a (ps)
  double target_strain = 0.2;  // where the test ends (duration())
};

struct CyclicLoading {
  double amplitude = 0.01;  // ε_a: the strain swings from 0 to −ε_a and back
  // Give exactly one of the two: ε̇_avg (/ps), the mean |dε/dt| over a half cycle, or the period
  // P (ps); P = 2ε_a/ε̇_avg.
  double mean_rate = 0;
  double period = 0;
  int cycles = 6;
};

struct TensileLoading {
  TensileMode mode = TensileMode::Monotonic;
  double length = 0;  // L0, the nominal film length (nm)
  MonotonicLoading monotonic;
  CyclicLoading cyclic;
};

class TensileProtocol final : public Protocol {
 public:
  // Throws std::invalid_argument naming the field and its allowed range for a length, rate,
  // ramp time, target strain, amplitude or period that is not finite and > 0, both or neither of
  // mean_rate and period, or fewer than one cycle.
  explicit TensileProtocol(TensileLoading loading);

  // Closed forms in loading time s (ps since the start; 0 before it).
  double strain_after(double s) const;       // ε(s)
  double strain_rate_after(double s) const;  // dε/ds
  // Loading time at which a monotonic test reaches strain ε (> 0); for a cyclic test, duration().
  double time_to_strain(double strain) const;
  double period() const;    // P (cyclic), 0 for monotonic
  double duration() const;  // loading time to the target strain, or n·P
  // The same at system time t.
  double strain(double t) const { return strain_after(elapsed(t)); }
  double elapsed(double t) const { return t - start_; }
  // Right grip's displacement ½L0·ε at system time t (the left grip's is its negative).
  double grip_displacement(double t) const { return 0.5 * loading_.length * strain(t); }

  // Starts the loading at the system's current time and puts the grips under the motion law for
  // the coming step. Call it when a stage begins on a system that has already run (its first step
  // then moves the grips); otherwise the first apply() starts the loading at its time.
  void start(System& sys);
  bool started() const { return started_; }
  double start_time() const { return start_; }

  // The updater: the grip DOF modes and velocities for the step from system time t. The grips'
  // element indices are kept from call to call (found from the groups at the first, and again
  // whenever one no longer holds its group's tag) and follow a reordering of the elements.
  void apply(System& sys, double t) override;
  bool follows_reorder() const override { return true; }
  void reorder(std::span<const std::uint32_t> old_to_new) override;
  bool reads_forces() const override { return false; }   // grip motion from the time alone
  bool applies_loads() const override { return false; }  // prescribed motion, no loads
  // "ramp", "straining" (monotonic); "cycle k/n", then "done" (cyclic).
  std::string phase(double t) const override;
  // A runaway element one of whose bonds is drawn out past its own rest length: the model's
  // bonds never break, so past the film's failure a piece held by both grips is stretched far
  // beyond a CNT's failure strain, and the bond's load stiffens its rotation past the step picked
  // at the test's start (docs/stability.md, 300 % strain). Empty otherwise.
  std::string explain_runaway(const System& sys, std::size_t i) const override;

  const TensileLoading& loading() const { return loading_; }

  // The start time (and whether started), with the loading to check against: load_state throws
  // CheckpointError when the checkpoint's loading differs from this protocol's.
  void save_state(StateWriter& w) const override;
  void load_state(StateReader& r) override;

 private:
  double grip_velocity(double s, double dt) const;  // right grip's x velocity over [s, s + dt]
  TensileLoading loading_;
  double start_ = 0;
  bool started_ = false;
  std::vector<std::size_t> grip_[2];  // the left and right grips' element indices
};

}  // namespace mdem
