#pragma once
// The grip reactions and the film stress of a tensile or cyclic test (tensile.md §3.5).
//
// F_L and F_R are the x components of the internal forces on each grip: bonds, vdW, NP contacts
// (Elements::f of the last force evaluation) and contact dashpots (System::damping_forces; local
// damping acts on free DOFs only, so on a grip that is the dashpots alone), summed over the grip's
// elements. Forces between two elements of one grip cancel in the sum.
//   σ = (F_L − F_R)/(2 W H)   positive in tension (the film pulls the right grip towards −x),
// with W the film's nominal width and H its thickness (11 nm). Forces are in eV/nm, so σ comes
// out in eV/nm³ and is reported in GPa: 1 eV/nm³ = 1.602176634e-19 J / 1e-27 m³ = 0.1602176634 GPa
// (units::to_GPa). F_L + F_R is ≈ 0 in a quasi-static test: it is the momentum the film between
// the grips gains per unit time, plus the local damping on it.
#include <cstddef>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "mdem/integrate/system.h"

namespace mdem {

struct GripForces {
  double left = 0;   // F_L (eV/nm)
  double right = 0;  // F_R (eV/nm)
  double sum() const { return left + right; }
};

// The x reactions on two sets of elements (indices), from the system's last force evaluation.
GripForces grip_forces(const System& sys, std::span<const std::size_t> left,
                       std::span<const std::size_t> right);

struct GripStressSettings {
  double width = 0;      // W (nm): the film's nominal width (its side, tensile.md Table 5-1)
  double height = 11.0;  // H (nm): the film's thickness
  double every = 1.0;    // sampling interval (ps)
  std::string left_group = "tensile.grip_left";
  std::string right_group = "tensile.grip_right";
};

// σ (GPa) from the grip reactions over the cross-section W·H.
double grip_stress_gpa(const GripForces& f, double width, double height);

// One sampled frame.
struct GripSample {
  double t = 0;                    // system time of the force evaluation (ps)
  double strain = 0;               // ε at t
  double stress = 0;               // σ (GPa)
  double f_left = 0, f_right = 0;  // eV/nm
};

// The series (t, ε, σ, F_L, F_R) of a test, sampled every `every` ps of system time as an
// observer of the test's stage. It is called before each force evaluation, when the forces in
// the system are those of the previous evaluation: it samples that evaluation, at the time it was
// made (the time of the previous call), when that time has reached the next sampling time. So the
// first sample is that of the evaluation made at the first call's time, and the run's last
// evaluation is sampled by the next run's first call.
class GripStressSampler final : public Updater {
 public:
  // strain: ε at a system time (e.g. the protocol's closed form). Throws std::invalid_argument
  // naming the field for a width, height or interval that is not finite and > 0, or empty group
  // names.
  GripStressSampler(std::function<double(double)> strain, GripStressSettings s);
  void apply(System& sys, double t) override;
  // Only when the next call samples (the grips' forces of the evaluation made at this call).
  bool reads_forces() const override;
  bool applies_loads() const override { return false; }  // an observer
  // It finds the grips' elements by group at each sample: it holds no index.
  bool follows_reorder() const override { return true; }

  const std::vector<GripSample>& samples() const { return samples_; }
  // Columns of the series, for the stress–strain and cycle analyses.
  std::vector<double> times() const;
  std::vector<double> strains() const;
  std::vector<double> stresses() const;
  const GripStressSettings& settings() const { return s_; }

  // The series and where sampling stands (last call's time, next sampling time).
  void save_state(StateWriter& w) const override;
  void load_state(StateReader& r) override;

 private:
  std::function<double(double)> strain_;
  GripStressSettings s_;
  std::vector<GripSample> samples_;
  // Whether the next call samples (the evaluation made at the previous call's time is due).
  bool due() const;
  bool have_prev_ = false;
  double prev_t_ = 0;
  double next_ = 0;  // next sampling time; set from the first call's time
};

}  // namespace mdem
