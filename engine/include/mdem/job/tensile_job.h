#pragma once
// The tensile job (tensile.md §3.1–3.6, thesis Ch. 5; issue 14): a thin film of randomly laid
// (10,10) tubes, optionally filled with Si nanoparticles (NPs), pre-relaxed, relaxed hands-off
// with contact dashpots, then pulled by two clamped grips (monotonic) or compressed to −ε_a and
// back (cyclic). Its force loop: intra-tube parallel bonds, the anisotropic CNT–CNT vdW contact,
// the NP–CNT and NP–NP contacts and the dashpots of all three (no walls, no granular contacts).
//
// Stages, in order (names as in progress lines and checkpoints):
//   "prerelax"     local damping α (0.7) until PrerelaxCriterion holds or its cap (50 ps); then
//                  every velocity and spin is zeroed and the film goes into a new system (clock,
//                  step count and energy ledger from 0) at a step picked anew. Its stop reason,
//                  duration and step are reported.
//   "relax"        hands-off: contact dashpots ψ only (plus local_damping if > 0), relax_ps long;
//                  left out when relax_ps = 0 (the ready-to-relax variant, Table 5-3).
//   "deposit"      only for nanoparticles > 0 with np_deposit = AfterRelax: the NPs are placed in
//                  the relaxed film (place_nanoparticles, the film's NP stream); the tubes keep
//                  their velocities, the NPs start at rest.
//   "np_prerelax"  after "deposit": the pre-relaxation again, run only when the placement left a
//                  pair on an overlap branch (otherwise it ends at once, taking no step); when
//                  run, a new system at rest and a step picked anew after it, as after "prerelax".
//   "tensile"      grips selected at the stage's start (select_grips, width grip_width), then the
//                  TensileProtocol: monotonic (ramp, constant rate, to target_strain) or cyclic.
// With np_deposit = BeforeRelax the NPs are part of the generated film and pre-relaxed with it.
//
// Units are the engine's internal ones: nm, ps, eV (forces eV/nm); strain rates in 1/ps (the
// thesis's 1e-7/fs is 1e-4/ps); stresses in the reports are converted to GPa.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/integrate/spectrum.h"
#include "mdem/job/job.h"
#include "mdem/job/prerelax_criterion.h"
#include "mdem/protocol/tensile_protocol.h"
#include "mdem/scene/tensile_film.h"

namespace mdem {

class GripStressSampler;
class ParallelBond;

// The choices of law a comparison with the thesis may change (TensileJobSpec::laws): the
// CNT–CNT vdW law's parameters, and whether the contact dashpots (CNT–CNT, NP–CNT, NP–NP) also
// damp shear.
struct FilmLaws {
  VdwParams vdw;
  bool dashpot_shear = false;
};

// The tensile job's force loop on `el`: intra-tube parallel bonds (their rest state `rest`'s
// bonds when given, else el's configuration, from el.topology), the CNT–CNT, NP–CNT and NP–NP
// contacts and, with dashpot_ratio ψ > 0, the dashpots of all three, with `laws`.
std::unique_ptr<System> tensile_film_system(Elements el, const IntegratorSettings& settings,
                                            double dashpot_ratio,
                                            const ParallelBond* rest = nullptr,
                                            const FilmLaws& laws = {});

// When the NPs enter the film (tensile.md §3.2).
enum class NpDeposit {
  AfterRelax,   // placed in the relaxed film just before the test (L797; the tensile default)
  BeforeRelax,  // placed in the generated film, relaxed with it (Fig. 5-8)
};
// "after_relax" / "before_relax"; anything else throws std::invalid_argument naming both.
NpDeposit np_deposit_from_name(std::string_view name);
std::string_view np_deposit_name(NpDeposit d);

struct TensileJobSpec {
  // The film's geometry: TensileFilmSpec::of_size(film_size_from_name("small" | "medium" |
  // "large")) for Table 5-1's films, or numbers (side, thickness, tubes, segments per tube, tilt,
  // containment). Its `nanoparticles` and `seed` fields are not read: the job's own below are.
  TensileFilmSpec film = TensileFilmSpec::of_size(FilmSize::Small);
  int nanoparticles = 0;  // NP count, in [0, 10^7]
  NpDeposit np_deposit = NpDeposit::AfterRelax;
  std::uint64_t seed = 1;  // tubes: mt19937_64(seed); NPs: np_stream(seed)

  // Pre-relaxation (§3.3): the stop test's limits (D per kind of pair, speed nm/ps, cap ps,
  // check interval steps) and the local damping α during it, in [0, 1).
  PrerelaxLimits prerelax;
  double prerelax_damping = 0.7;

  // Relaxation (§3.4): its length (ps; 4.5 ns = 4500 ps, L797); 0 = the ready-to-relax variant
  // (no relaxation stage). In [0, 10^7] ps.
  double relax_ps = 4500;
  // ψ of the contact dashpots on CNT–CNT, NP–CNT and NP–NP pairs (k = 100 eV/nm², the pair's
  // reduced mass), in [0, 1]; 0 = none. Present in every stage.
  double dashpot_ratio = 0.03;
  // PFC local damping α during relaxation and test, in [0, 1); 0 = none (the thesis's hands-off
  // dynamics; waLBerla's film app used 0.2).
  double local_damping = 0;

  // The test (§3.5–3.6): monotonic (strain_rate 1/ps, ramp_time ps, target_strain, a fraction:
  // 0.2 = 20 %) or cyclic (amplitude ε_a, a fraction; mean_rate 1/ps or period ps, exactly one;
  // cycles). L0 is the film's side. The cyclic default rate is Table 5-5's 5.7e-8/fs (L892).
  TensileMode mode = TensileMode::Monotonic;
  MonotonicLoading monotonic{};
  CyclicLoading cyclic{0.01, 5.7e-5, 0, 6};
  double grip_width = 15.0;  // nm from each film end (§3.5, L1088), > 0
  // Zero every velocity and spin at the test's start (§6 #37: kept by default).
  bool zero_velocities_at_test = false;
  // Sampling interval of the stress (t, ε, σ, F_L, F_R) in ps, > 0 (§3.5: 1 ps).
  double sample_every_ps = 1.0;

  // When the relaxation's aligned pairs (both counts) and pores are recorded (ps since the
  // relaxation's start, each in [0, 10^7], at most 1000; times past relax_ps are dropped and
  // relax_ps itself is always one; §3.4: 0, 1, 2, 3, 4, 4.5 ns). The registry-free
  // count for the stabilisation time is sampled every relax_count_every_ps (> 0; §3.4: 15 ps).
  std::vector<double> relax_report_ps = {0, 1000, 2000, 3000, 4000, 4500};
  double relax_count_every_ps = 15.0;
  // Strains at which a monotonic test records aligned pairs, pores, bending energy and width
  // (fractions, each in [0, 10], at most 1000; strains past the target are not reached; unused
  // by a cyclic test; §3.5: 0, 2, 10, 20 %). The fraction of tubes in tension is taken
  // at 2 % when the test reaches it; fragments at 50, 100, 150, 200 % when reached.
  std::vector<double> test_report_strains = {0, 0.02, 0.1, 0.2};

  // For comparisons with the thesis: the CNT–CNT vdW law (laws.vdw: its torque and
  // flip_blend, not in the proto; validate_tensile's --vdw-law sets them), the energy-conserving
  // default (VdwTorque::Exact, flip_blend 0.2, in [0, 0.5]) or the thesis's literal Table 2-3 as
  // run in PFC (VdwTorque::Pfc and flip_blend 0; model.md §4); and the CNT contact dashpot
  // and the contact dashpots (laws.dashpot_shear), normal-only (default) or with the thesis's
  // shear part (Eq. 33–34, ContactDampingParams::shear, NpDampingParams::shear; the proto's
  // vdw_dashpot_shear, `mdem run tensile --dashpot-shear`) on the CNT–CNT, NP–CNT and NP–NP
  // pairs alike.
  FilmLaws laws;

  // Kelvin; only 0 is accepted (§6 #16: the thesis's films start at rest).
  double temperature_k = 0;

  // Throws std::invalid_argument naming the field and its allowed range (film and loading
  // fields through TensileFilmSpec::validate and TensileProtocol).
  void validate() const;
};

// What the pre-relaxation stage did (one per pre-relaxation: the film's, and after an NP deposit).
struct PrerelaxRecord {
  bool ran = false;
  std::string reason;  // PrerelaxCriterion::reason() at its end
  double duration_ps = 0;
  long steps = 0;
  double dt_after_ps = 0;  // the step picked for the stages after it (0 when skipped)
};

// How the step of the relaxation and the test was set: the last check (after the pre-relaxation,
// and again at an NP deposit and after the NPs' pre-relaxation), of the state the stages after it
// start from.
struct StepCheck {
  double dt_ps = 0;     // the step (0: no check yet)
  bool given = false;   // the caller's dt (else the job's own, pick_dt)
  double bound_ps = 0;  // the automatic step's critical-step bound (System::critical_dt)
  // The measured critical step (2/ω_max with the dashpots' damping, System::damped_critical_dt),
  // which a given dt above safety × bound_ps was checked against; 0 when not measured.
  double measured_ps = 0;
};

// The check of a given step dt above safety × the automatic bound (TensileJob, settings.dt) from
// two Lanczos estimates of the film's largest frequency (two random starts): both must have
// converged and agree within 1 % (else ConfigError: "not converged" or "not agreeing"); the
// larger Ritz frequency plus its residual, ω, gives the critical step damped_critical(ω)
// (System::damped_critical_dt), and dt must be within safety × it (else ConfigError naming dt,
// the limit, the critical step and the bound). Returns the check with the measured step.
StepCheck judge_given_step(double dt, double safety, double bound, const SpectrumEstimate& e1,
                           const SpectrumEstimate& e2,
                           const std::function<double(double)>& damped_critical);

// The relaxation's records at relax_report_ps.
struct RelaxFrame {
  double t = 0;  // ps since the relaxation's start
  long aligned_thesis = 0, aligned_registry_free = 0;
  long pores_large = 0;  // pores > 200 nm²
  double void_fraction = 0;
  double bending_share = 0;  // bond bending energy / all bond energy
};

// The test's records at test_report_strains (reached strains only).
struct StrainFrame {
  double strain = 0;
  long aligned_thesis = 0, aligned_registry_free = 0;
  long pores_large = 0;
  double bending_eV = 0;
  double mid_width_nm = 0;  // P99 − P1 of y over the mid slab (width_profile.h)
};

class TensileJob final : public Job {
 public:
  // Validates the spec, generates the film (quick: no dynamics) and sets up the stages. The time
  // step: the job picks 0.9 × the auto step (safety × critical) of the state each run of stages
  // starts from — the generated film (pre-relaxation), the pre-relaxed film (relaxation, test),
  // the film with its deposited NPs (np_prerelax) and the NP-pre-relaxed film (test) — fixed
  // within a stage so the grips' motion law is integrated exactly. settings.dt, if given, is the
  // step of the relaxation and the test instead (tensile.md §3.4: the thesis's 30 fs); the
  // pre-relaxations still pick theirs. A given step must be within safety × the critical step of
  // the film those stages start from: where the automatic step's Gershgorin bound is too low
  // for it, the true critical step is measured (integrate/spectrum.h), and a step above
  // safety × that makes the job fail there with a message naming both. A picked or checked step
  // is a stage result, restored from checkpoints. The
  // test stage runs one sampling interval past the loading's end (the sampler lags one
  // evaluation). Throws std::invalid_argument for a bad spec or a film whose NPs do not fit.
  TensileJob(const TensileJobSpec& spec, IntegratorSettings settings);
  // The same on a film built by the caller (e.g. straight tubes for an analytic check): `film`
  // holds its CNT segments, bonded along their chains in film.topology, and any NPs. Of
  // spec.film only side (L0 and W) and thickness are read; the rest of the spec as above
  // (nanoparticles > 0 with AfterRelax deposits that many more).
  TensileJob(Elements film, const TensileJobSpec& spec, IntegratorSettings settings);
  TensileJob(const TensileJob&) = delete;
  TensileJob& operator=(const TensileJob&) = delete;
  ~TensileJob() override;

  std::string_view kind() const override { return "tensile"; }
  System& system() override { return *sys_; }
  // Pre-relaxation cap + relaxation + the test's loading time (the longest the job can run).
  double duration() const override;
  // time_ps, stage code (0 prerelax, 1 relax, 2 deposit/np_prerelax, 3 test), strain, stress_GPa,
  // F_L_eV_per_nm, F_R_eV_per_nm, aligned_thesis, aligned_registry_free, bending_share, then the
  // energy columns (bond terms, vdw, np_cnt, np_np separate, kinetic, work, dissipated, ...).
  std::vector<std::string> columns() const override;
  std::vector<double> observe() override;
  // Film report (element counts, density, porosity), pre-relaxation stop reason and duration,
  // relaxation stabilisation time and aligned pairs/pores at its start and end, then the test:
  // monotonic — E (GPa, 1–2 %) and its intercept, 0.2 %-offset yield strain, fraction of tubes in
  // tension at 2 %, mid-length width shrinkage at the end, aligned pairs and pores > 200 nm² at
  // the test's start and end, peak stress, and for target strains ≥ 50 % toughness (GJ/m³),
  // failure strain and fragments; cyclic — per cycle k (1-based keys cycle_k_...) loop area
  // (J/cm³), modulus (GPa) and phase lead (fraction of P). A monotonic curve ends at the target
  // strain (frames past it dropped, the stress at it interpolated: final_strain is the target).
  // np_deposit only for a film with NPs. Figures a short run cannot give (no frame in the 1–2 %
  // window, no yield) are left out of the summary.
  Summary summary() override;

  const TensileJobSpec& spec() const { return spec_; }
  const TensileFilm& film() const { return film_; }
  const TensileProtocol& protocol() const { return *protocol_; }
  const GripStressSampler& stress_sampler() const { return *sampler_; }
  const PrerelaxRecord& prerelax_record() const;
  const PrerelaxRecord& np_prerelax_record() const;
  const StepCheck& step_check() const;
  const std::vector<RelaxFrame>& relax_frames() const;
  const std::vector<StrainFrame>& strain_frames() const;
  // The relaxation's registry-free aligned-pair count every relax_count_every_ps, and its
  // stabilisation time (ps since the relaxation's start; stabilisation_time, 5 %); empty without
  // a relaxation or with fewer than two samples.
  std::optional<double> relax_stabilisation_ps() const;

 private:
  class Records;
  class RelaxTracker;
  class TestTracker;
  class DepositStage;
  class PrerelaxStage;
  void stage_finished(std::size_t k) override;
  void build(Elements el);  // the system from the film, then the stages
  // A system of the job's models on `el` (bonds at rest as in `rest`, or el's own) at the auto
  // step, initialized: for picking and checking steps.
  std::unique_ptr<System> probe(const Elements& el, const ParallelBond* rest) const;
  // The job's own step for a system on `el`: 0.9 × the auto step of that state (with
  // respa_k > 1, of the smaller of it and the slow forces' safe outer step ÷ respa_k), with the
  // bound it was picked from.
  StepCheck pick_dt(const Elements& el, const ParallelBond* rest) const;
  // The step of the stages after a pre-relaxation: the caller's dt (checked_given_dt), else
  // pick_dt.
  StepCheck step_after_prerelax(const Elements& el, const ParallelBond* rest) const;
  // The caller's dt if it is within safety × the critical step of a system on `el`: the
  // automatic step's bound, or where that is too low, the measured 2/ω_max (largest_frequency,
  // with the dashpots' damping, Ritz value plus residual); with respa_k > 1 the outer step within
  // the slow forces' bound; with the bound and the measured step (if measured). Else throws
  // ConfigError naming dt, the limit and the critical step.
  StepCheck checked_given_dt(const Elements& el, const ParallelBond* rest) const;
  // sys_ replaced by a new system on `el` at step dt (bonds at rest as in `rest`).
  void rebuild(Elements el, double dt, const ParallelBond* rest);

  TensileJobSpec spec_;
  IntegratorSettings settings_;
  TensileFilm film_;
  std::unique_ptr<System> sys_;
  std::shared_ptr<TensileProtocol> protocol_;
  std::shared_ptr<GripStressSampler> sampler_;
  std::shared_ptr<Records> records_;
  std::shared_ptr<RelaxTracker> relax_tracker_;
  std::shared_ptr<TestTracker> test_tracker_;
  std::shared_ptr<PrerelaxCriterion> prerelax_, np_prerelax_;
  DepositStage* deposit_ = nullptr;          // owned by the stage list; null without one
  PrerelaxStage* prerelax_stage_ = nullptr;  // likewise, never null after build
  PrerelaxStage* np_stage_ = nullptr;        // null without a deposit
  std::optional<double> given_dt_;           // ps, the caller's step for relaxation and test
  double dt_start_ = 0;                      // ps, the pre-relaxation's step
  std::size_t prerelax_index_ = 0, relax_index_ = 0, deposit_index_ = 0, np_prerelax_index_ = 0,
              test_index_ = 0;  // stage positions (npos-like: stages().size() when absent)
};

}  // namespace mdem
