#pragma once
// The twist job (scenes.md "twist"): a hexagonal rope of (10,10) tubes with intra-tube bonds, the
// anisotropic vdW contact and its viscous dashpots, loaded in torsion by TwistProtocol. It brings
// in nothing else: no walls, nanoparticles or granular contacts.
#include <memory>
#include <optional>

#include "mdem/job/job.h"
#include "mdem/job/stage.h"
#include "mdem/observe/rope_observables.h"
#include "mdem/protocol/twist_protocol.h"
#include "mdem/scene/hex_rope.h"

namespace mdem {

struct TwistJobSpec {
  RopeSpec rope;
  TwistLoading loading;             // internal units (eV, eV/ps, ps)
  double vdw_damping_ratio = 0.03;  // ψ of the vdW contact dashpots; 0 = none
  // Seeded random velocities and spins of this temperature at the start (K; 0 = at rest): a
  // perfect lattice is symmetric, and only noise lets an instability (buckling, coiling) start.
  double temperature_k = 0;
  unsigned seed = 1;
};

// Everything the twist job reports at one instant.
struct TwistReport {
  double applied_torque_nNnm = 0;
  double grip_reaction_nNnm = 0;  // internal moment on the grips, mean of both ends
  double twist_angle_deg = 0;
  double shift_angle_deg = 0;
  double rope_radius_nm = 0;
  double length_nm = 0;
  double core_void_nm = 0;
  double axis_deviation_nm = 0;
  int clusters = 0;
  int topological_charge = 0;
  Morphology morphology = Morphology::Straight;
};

// What ended a stage by over twist.
enum class OverTwistRule {
  None,
  // A tube's kinetic energy rose by at least kUnresistedFraction of the work its grip loads did,
  // over every window of kWindowChecks checks ending at kSustainChecks checks in a row: the work
  // is no longer stored or dissipated but goes into the tube's motion.
  UnresistedWork,
  // The backstop: a grip element spins in the sense of its moment faster than
  // TwistProtocol::spin_up_limit at kChecksInARow checks in a row.
  SpinUp,
};

// The figures of the unresisted-work rule for one tube over its window (eV, ps).
struct UnresistedTube {
  int tube = -1;
  double window_ps = 0;          // length of the window
  double work = 0;               // work of the tube's grip loads over the window
  double kinetic_rise = 0;       // rise of the tube's kinetic energy over the window
  double kinetic = 0;            // the tube's kinetic energy now
  double total_work = 0;         // work of its grip loads since the start of the stage
  double rope_work = 0;          // work of all grip loads over the window
  double rope_bending_rise = 0;  // rise of the rope's bending energy over the window
};

// The over-twist outcome (the thesis's "separation due to over twist"): the twist stage ends early,
// results kept, when a tube stops storing the work of its grip loads while they are loaded (the
// ramp, and the constant-moment hold). Every kCheckEvery steps it books, per tube, the work its
// grip loads did since the last check (trapezoidal in the loads, exact in the displacements and
// rotations, so exact under a held load) and the tube's kinetic energy (translation and rotation
// of all its elements). It fires on the first of:
//  - UnresistedWork: over a sliding window of kWindowChecks checks, the tube's kinetic energy rose
//    by at least kUnresistedFraction of that work, the work was at least kMinWorkFraction of all
//    the work its loads did so far, the rope's bending energy rose by less than the work of all
//    grip loads over the window, and this held at kSustainChecks checks in a row. An elastic
//    tube under a dead load turns its work half into stored energy at most half into motion (a
//    travelling torsion wave splits it evenly; a rocking end converts less the smaller the
//    rocking), and bending a buckling tube stores energy too; an unresisted one turns it all into
//    motion, less the local damping (0.9 at damping 0.1), for as long as it is loaded. When a
//    helix or bird cage forms, stored torsion turns into bending and motion without any work:
//    a tube's kinetic energy can then rise faster than its work, but the rope's bending rises
//    faster than all the work, which the bending clause excludes.
//  - SpinUp (the backstop, the old check): a grip element spinning in the sense of its moment
//    faster than TwistProtocol::spin_up_limit at kChecksInARow checks in a row.
// Its state (the books, the window, the counters) is part of the checkpoint. The first call of
// met() after construction or load only starts the books if none were loaded.
class OverTwistSeparation final : public StopCriterion {
 public:
  static constexpr long kCheckEvery = 10;
  static constexpr int kChecksInARow = 3;
  static constexpr int kWindowChecks = 32;   // ~5.8 ps at the (10,10) rope's 18.2 fs
  static constexpr int kSustainChecks = 55;  // ~10 ps of checks in a row
  static constexpr double kUnresistedFraction = 0.5;
  static constexpr double kMinWorkFraction = 0.01;
  // The rule books at the first check at least this long after its last booking, so that its
  // window (kWindowChecks bookings, ~5.8 ps) and its sustain (kSustainChecks, ~10 ps) are times
  // of the rope's motion (a torsion wave's transit, a rocking period), not of the step: at the
  // ropes' 18.2 fs it books every check; a run at 0.3 fs (bonds 10^4 times stiffer) books every
  // 57th, where a window of 32 checks would span 0.1 ps of a ramp's start.
  static constexpr double kBookEveryPs = 0.18;

  // `el`: the job's elements (its tube count and grip elements size the books).
  OverTwistSeparation(std::shared_ptr<const TwistProtocol> protocol, const Elements& el);
  bool met(const System& sys) override;
  // When it separated (ps) and by which rule; empty / None while it has not.
  std::optional<double> time() const { return time_; }
  OverTwistRule rule() const { return rule_; }
  // The tube that separated (-1 while none did).
  int tube() const;
  // The backstop's grip element (rule SpinUp).
  const SpunUpGrip& grip() const { return grip_; }
  // The unresisted-work rule's figures at the separation (rule UnresistedWork), or, before it,
  // of the tube with the largest kinetic rise over work at the last check.
  const UnresistedTube& unresisted() const { return unresisted_; }
  // Work of the grip loads on tube k since the start and its kinetic energy at the last check.
  double tube_work(int k) const { return work_[static_cast<std::size_t>(k)]; }
  double tube_kinetic(int k) const { return kinetic_[static_cast<std::size_t>(k)]; }
  int tubes() const { return static_cast<int>(work_.size()); }
  void save_state(StateWriter& w) const override;
  void load_state(StateReader& r) override;

 private:
  void book(const System& sys);  // work since the last check, kinetic energies now
  bool unresisted_work(const System& sys, bool loaded);

  std::shared_ptr<const TwistProtocol> protocol_;
  std::vector<std::size_t> grips_;  // grip a then grip b
  // Backstop state.
  int in_a_row_ = 0;
  SpunUpGrip grip_;
  // Books: the grip elements' positions, orientations and loads at the last check; per tube the
  // work since the start, the kinetic energy now, and the last kWindowChecks + 1 checks' work
  // and kinetic energy (ring, slot-major); per tube the checks in a row the rule held.
  std::vector<Vec3> last_x_, last_f_, last_t_;
  std::vector<Quat> last_q_;
  std::vector<double> work_, kinetic_;
  std::vector<double> ring_work_, ring_kinetic_;
  std::vector<double> ring_bending_;  // the rope's bending energy, per slot
  long checks_ = 0;          // checks booked (the ring's head is checks_ % (kWindowChecks + 1))
  double last_book_ps_ = 0;  // time of the last booking
  std::vector<int> held_;
  UnresistedTube unresisted_;
  // Outcome.
  std::optional<double> time_;
  OverTwistRule rule_ = OverTwistRule::None;
};

class TwistJob final : public Job {
 public:
  // Throws std::invalid_argument for an impossible rope or load (see build_hex_rope and
  // TwistProtocol).
  TwistJob(const TwistJobSpec& spec, IntegratorSettings settings);
  // Its stage and observers refer to the rope and system it holds: it stays where it was built.
  TwistJob(const TwistJob&) = delete;
  TwistJob& operator=(const TwistJob&) = delete;

  std::string_view kind() const override { return "twist"; }
  System& system() override { return sys_; }
  double duration() const override { return protocol_->duration(); }
  std::vector<std::string> columns() const override;
  std::vector<double> observe() override;
  Summary summary() override;

  TwistReport report();
  const Rope& rope() const { return rope_; }
  const TwistProtocol& protocol() const { return *protocol_; }
  const OverTwistSeparation& separation() const { return *separation_; }

  // Largest values seen at any report (the summary's figures are those at the end: after
  // unloading, the end shift is the residual twist and these are the loaded ones).
  struct Peaks final : Stateful {
    int max_charge = 0;
    double twist = 0, shift = 0;
    void save_state(StateWriter& w) const override;
    void load_state(StateReader& r) override;
  };

 private:
  static std::vector<EnergyTerm> energy_terms();

  Rope rope_;
  System sys_;
  std::shared_ptr<TwistProtocol> protocol_;
  std::shared_ptr<ShiftAngleSampler> shift_;
  std::shared_ptr<Peaks> peaks_;
  std::shared_ptr<OverTwistSeparation> separation_;
};

}  // namespace mdem
