#pragma once
// Torsion of a rope by its grips (scenes.md "twist", thesis §4.2–4.3): a torque T about the rope
// axis, opposite at the two ends, raised at a constant rate to T_max, then held; optionally
// unloaded to measure the residual twist.
//
// The torque on a grip is a load, not a kinematic constraint: every grip element i gets a
// tangential force F_i = λ m_i ẑ × r_i and a torque τ_i = λ I_i ẑ (r_i its offset from the grip's
// mass centroid, perpendicular to the axis; I_i its moment of inertia about ẑ), with
// λ = T / Σ(m_i r_i² + I_i). The grip's moment about the axis is then exactly T, the net force on
// it is zero, and a grip left to itself would turn as a rigid body: the load does not distort it.
// λ is recomputed from the current positions before every force evaluation, so the moment stays
// T as the grip expands or slides; grips move freely along the axis.
//
// Boundary conditions during the hold:
//   constant-moment   the grips keep the held torque and turn with the rope;
//   twist-relaxation  the grip positions are held where they are (prescribed zero velocity; the
//                     kinetic energy this removes is booked as constraint work) and the torque is
//                     removed. What else is held is GripHold: with Positions (the thesis's "fixed
//                     but allowed free spin", §4.3 end) the grip elements spin freely, so physical
//                     twist relaxes while the geometric twist stays; with PositionsAndSpins their
//                     orientations are held too (prescribed zero angular velocity), a clamp that
//                     keeps the twist each tube stores in its end elements' rotations.
// Unloading: constant-moment ramps the torque down at the same rate, then relaxes at zero torque;
// twist-relaxation releases the grips and relaxes.
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "mdem/core/math.h"
#include "mdem/protocol/protocol.h"

namespace mdem {

struct Elements;

enum class TwistBoundary { ConstantMoment, TwistRelaxation };

// What a twist-relaxation hold keeps where the ramp left it.
enum class GripHold {
  // The grip elements' positions; their spins are free (§4.3: the physical twist relaxes).
  Positions,
  // Positions and orientations: each grip element is clamped, and a tube twisted at its own end
  // (the per-element load) keeps its twist.
  PositionsAndSpins,
};

// How a grip carries the torque.
enum class GripLoad {
  // The grip's moment about the rope axis is T (forces and torques as described above): a rope
  // twisted as a whole by a clamp that lets each tube end spin.
  RigidGrip,
  // Every grip element carries the moment T about the axis through its own centre, no force: the
  // thesis's PFC reading (an applied moment on each grip ball). Each tube end is twisted by T, the
  // grip as a whole by n·T, and the rope turns only as far as the twisted tubes make it.
  PerElement,
};
// A loaded grip element turning in the sense of its applied moment: the moment is doing work that
// nothing stores (its tube has unwound or separated and spins up), the thesis's "separation due to
// over twist".
struct SpunUpGrip {
  std::size_t element = 0;
  int tube = -1, segment = -1;
  double moment = 0;  // the load's moment on the element about the axis (eV, > 0)
  double spin = 0;    // its angular velocity about the axis, in the sense of the moment (rad/ps)
};

enum class TwistPhase { Loading, Holding, Unloading, Relaxing, Done };
std::string_view twist_phase_name(TwistPhase p);

struct TwistLoading {
  double torque_max = 0;  // eV (internal units: 1 nN·nm = 6.2415 eV)
  double rate = 0;        // eV/ps
  double hold = 0;        // ps
  TwistBoundary boundary = TwistBoundary::ConstantMoment;
  bool unload = false;
  double unload_hold = 0;  // ps at zero load after unloading
  GripLoad grip_load = GripLoad::RigidGrip;
  GripHold grip_hold = GripHold::Positions;  // twist-relaxation only
};

class TwistProtocol final : public Protocol {
 public:
  // Throws std::invalid_argument for a non-positive or non-finite torque or rate, negative hold
  // times, empty grips, a zero axis, or held spins under a constant moment (nothing is held).
  TwistProtocol(TwistLoading loading, std::vector<std::size_t> grip_a,
                std::vector<std::size_t> grip_b, Vec3 axis = Vec3::UnitZ());

  double ramp_time() const { return loading_.torque_max / loading_.rate; }
  double duration() const;
  TwistPhase phase_at(double t) const;
  // Magnitude of the torque the grips carry at time t (0 on twist-relaxation grips once held).
  double torque_at(double t) const;

  // The updater: sets the grips' loads and DOF modes for time t. Grip b (z > 0) gets +T about
  // the axis, grip a gets −T.
  void apply(System& sys, double t) override;
  // The fastest loaded grip element of tube `tube` (any tube when -1) that spins in the sense of
  // its moment faster than spin_up_limit(sys); none if there is none.
  std::optional<SpunUpGrip> spun_up_grip(const System& sys, int tube = -1) const;
  // A quarter of the run guard's limit of one radian per step. An elastically held grip element
  // only rocks about its twisted state: ω·dt stayed below 0.004 on the Table 4-1 rope under
  // 64 nN·nm per element until it buckled, and below 0.1 while its bird cage formed; one driven
  // round by its moment passes the limit tens of picoseconds before the guard stops the run.
  static double spin_up_limit(const System& sys) { return 0.25 / sys.dt(); }
  // The run guard's account of a runaway element whose tube's grip is spun up by its moment.
  std::string explain_runaway(const System& sys, std::size_t i) const override;
  std::string phase(double t) const override { return std::string(twist_phase_name(phase_at(t))); }

  const TwistLoading& loading() const { return loading_; }
  const std::vector<std::size_t>& grip_a() const { return grip_a_; }
  const std::vector<std::size_t>& grip_b() const { return grip_b_; }
  const Vec3& axis() const { return axis_; }

  // The phase apply() last saw (it acts on phase changes), for checkpoints. load_state throws
  // CheckpointError when the checkpoint's loading differs from this protocol's.
  void save_state(StateWriter& w) const override;
  void load_state(StateReader& r) override;

 private:
  void load_grip(Elements& el, const std::vector<std::size_t>& grip, double torque) const;
  // Holds what loading_.grip_hold says (prescribed zero velocities) and removes the load.
  void hold_grip(Elements& el, const std::vector<std::size_t>& grip) const;
  void release_grip(Elements& el, const std::vector<std::size_t>& grip) const;

  TwistLoading loading_;
  std::vector<std::size_t> grip_a_, grip_b_;
  Vec3 axis_;
  TwistPhase last_phase_ = TwistPhase::Loading;
};

// Moment about `axis` (through the grip's mass centroid) of the internal forces and torques on a
// grip's elements: at static equilibrium it balances the applied torque.
double grip_reaction_moment(const Elements& el, const std::vector<std::size_t>& grip,
                            const Vec3& axis);
// Mass centroid of a set of elements.
Vec3 mass_centroid(const Elements& el, const std::vector<std::size_t>& ids);

}  // namespace mdem
