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

// The over-twist outcome (the thesis's "separation due to over twist"): the twist stage ends early,
// results kept, when a grip element spins in the sense of its moment faster than
// TwistProtocol::spin_up_limit at three checks in a row (every 10 steps) while the grips are
// loaded: its tube has unwound or separated, and the held moment would spin it up until the run
// guard stops the run.
class OverTwistSeparation final : public StopCriterion {
 public:
  static constexpr long kCheckEvery = 10;
  static constexpr int kChecksInARow = 3;
  explicit OverTwistSeparation(std::shared_ptr<const TwistProtocol> protocol);
  bool met(const System& sys) override;
  // When it separated (ps) and the grip element that spun up; empty while it has not.
  std::optional<double> time() const { return time_; }
  const SpunUpGrip& grip() const { return grip_; }
  void save_state(StateWriter& w) const override;
  void load_state(StateReader& r) override;

 private:
  std::shared_ptr<const TwistProtocol> protocol_;
  int in_a_row_ = 0;
  std::optional<double> time_;
  SpunUpGrip grip_;
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
