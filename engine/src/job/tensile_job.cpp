// The tensile job (tensile_job.h, tensile.md §3, thesis Ch. 5).
#include "mdem/job/tensile_job.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "mdem/core/cnt.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/contact/np_cnt_contact.h"
#include "mdem/force/contact/np_np_contact.h"
#include "mdem/force/damping/np_contact_damping.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/integrate/spectrum.h"
#include "mdem/observe/aligned_pairs.h"
#include "mdem/observe/cycle_analysis.h"
#include "mdem/observe/film_report.h"
#include "mdem/observe/fragments.h"
#include "mdem/observe/grip_bridges.h"
#include "mdem/observe/grip_stress.h"
#include "mdem/observe/pore_raster.h"
#include "mdem/observe/stress_strain.h"
#include "mdem/observe/tube_tension.h"
#include "mdem/observe/width_profile.h"
#include "mdem/scene/nanoparticle.h"

namespace mdem {

std::unique_ptr<System> tensile_film_system(Elements el, const IntegratorSettings& settings,
                                            double dashpot_ratio, const ParallelBond* rest,
                                            const FilmLaws& laws) {
  std::unique_ptr<ParallelBond> pb;
  if (rest) {
    pb = std::make_unique<ParallelBond>();
    for (const Bond& b : rest->bonds()) pb->add(b);
  } else {
    pb = ParallelBond::from_topology(el, BondType::Cnt, cnt_bond_stiffness());
  }
  auto sys = std::make_unique<System>(std::move(el), settings);
  sys->add(std::move(pb));
  sys->add(std::make_unique<AnisotropicVdw>(laws.vdw));
  sys->add(std::make_unique<NpCntContact>());
  sys->add(std::make_unique<NpNpContact>());
  if (dashpot_ratio > 0) {
    ContactDampingParams d;
    d.ratio = dashpot_ratio;
    d.shear = laws.dashpot_shear;
    sys->add(std::make_unique<ViscousContactDamping>(d));
    const double k = NpDampingParams{}.stiffness;
    sys->add(std::make_unique<NpContactDamping>(
        np_cnt_dashpot(dashpot_ratio, {}, k, laws.dashpot_shear)));
    sys->add(std::make_unique<NpContactDamping>(
        np_np_dashpot(dashpot_ratio, {}, k, laws.dashpot_shear)));
  }
  return sys;
}

NpDeposit np_deposit_from_name(std::string_view name) {
  if (name == "after_relax") return NpDeposit::AfterRelax;
  if (name == "before_relax") return NpDeposit::BeforeRelax;
  throw std::invalid_argument(
      "tensile np_deposit must be \"after_relax\" or \"before_relax\", got \"" + std::string(name) +
      "\"");
}

std::string_view np_deposit_name(NpDeposit d) {
  return d == NpDeposit::AfterRelax ? "after_relax" : "before_relax";
}

namespace {

constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
// The job's step is this fraction of the auto step (safety × critical step) of the state it is
// picked on: the margin covers the stiffening a stage's own motion brings.
constexpr double kAutoDtFactor = 0.9;
// Largest move of any element's point (nm) in the differences that measure the true critical
// step of a caller's dt (checked_given_dt). Finer moves resolve W's knee, where a crossed pair's
// force jumps (docs/stability.md): on the medium film pre-relaxed 50 ps, Lanczos at 1e-4 nm did
// not converge in 300 steps and two starts differed by 27 %; at 1e-3 nm they converged (58 and
// 82 steps) and agreed to 1e-4. A vibration's own amplitude in these films is larger.
constexpr double kGivenDtProbeMove = 1e-3;
// The strain at which the fraction of tubes in tension is taken (§3.5), its averaging window (ps)
// and the strains at which fragments are counted (§3.5 large strain).
constexpr double kTensionStrain = 0.02;
constexpr double kTensionWindow = 10.0;
constexpr std::array<double, 4> kFragmentStrains = {0.5, 1.0, 1.5, 2.0};

[[noreturn]] void bad(const std::string& field, const std::string& range, double got) {
  throw std::invalid_argument("tensile " + field + " must be " + range + ", got " +
                              std::to_string(got));
}

void check_range(const std::string& field, double v, double lo, double hi, bool lo_open = false) {
  if (!std::isfinite(v) || v < lo || v > hi || (lo_open && v == lo))
    bad(field,
        std::string("finite and in ") + (lo_open ? "(" : "[") + std::to_string(lo) + ", " +
            std::to_string(hi) + "]",
        v);
}

TensileFilmSpec film_spec(const TensileJobSpec& s, bool with_nps) {
  TensileFilmSpec f = s.film;
  f.seed = s.seed;
  f.nanoparticles = with_nps ? s.nanoparticles : 0;
  return f;
}

bool deposit_after(const TensileJobSpec& s) {
  return s.nanoparticles > 0 && s.np_deposit == NpDeposit::AfterRelax;
}

TensileLoading loading_of(const TensileJobSpec& s) {
  TensileLoading l;
  l.mode = s.mode;
  l.length = s.film.side;
  l.monotonic = s.monotonic;
  l.cyclic = s.cyclic;
  return l;
}

std::vector<EnergyTerm> energy_terms() {
  return {EnergyTerm::BondTension, EnergyTerm::BondShear, EnergyTerm::BondBending,
          EnergyTerm::BondTorsion, EnergyTerm::Vdw,       EnergyTerm::NpCnt,
          EnergyTerm::NpNp};
}

double bond_energy(const System& sys) {
  const auto& e = sys.energy().potential.stored;
  return e[static_cast<int>(EnergyTerm::BondTension)] + e[static_cast<int>(EnergyTerm::BondShear)] +
         e[static_cast<int>(EnergyTerm::BondBending)] +
         e[static_cast<int>(EnergyTerm::BondTorsion)];
}

double bending_energy(const System& sys) {
  return sys.energy().potential.stored[static_cast<int>(EnergyTerm::BondBending)];
}

// The bending share of the bond energy (§3.4, L736: 96 %); 0 without bond energy.
double bending_share(const System& sys) {
  const double all = bond_energy(sys);
  return all > 0 ? bending_energy(sys) / all : 0.0;
}

// The counts over the CNT–CNT vdW list's candidate pairs (its cutoff 4T ≫ the counts' reach; its
// exclusion is the counts'), which the last force evaluation left current; a list of their own
// only when that one cannot serve (not yet built, or stale after the positions moved on).
AlignedPairCounts aligned(const System& sys) {
  const AlignedPairCriteria c;
  const auto* vdw = sys.find<AnisotropicVdw>();
  const NeighborList* list = vdw ? sys.neighbors(*vdw) : nullptr;
  if (list && vdw->params().intra_tube_exclusion <= c.exclusion)
    if (auto n = count_aligned_pairs(sys.elements(), *list, c)) return *n;
  return count_aligned_pairs(sys.elements(), c);
}

PoreStats pores(const System& sys, const Window2D* window = nullptr) {
  const ProjectedFrame frame = projected_frame(sys.elements());
  if (frame.segment_centre.size() < 2) return {};
  const Window2D w = window ? *window : percentile_window(frame.segment_centre);
  if (!(w.x_hi - w.x_lo > 1.0) || !(w.y_hi - w.y_lo > 1.0)) return {};
  return pore_stats(rasterize(frame, w));
}

// A monotonic test's curve ends at its target strain: the samples past it (the stage runs one
// sampling interval on, so that the sampler records the loading's end) are dropped and the last
// point is at the target, its stress linear between the samples either side. A curve that has
// not reached the target (a run still going) is left as it is.
void end_at_target(std::vector<double>& eps, std::vector<double>& sig, double target) {
  const auto past = std::find_if(eps.begin(), eps.end(), [&](double e) { return e > target; });
  if (past == eps.end() || past == eps.begin()) return;
  const std::size_t k = static_cast<std::size_t>(past - eps.begin());
  const double w = (target - eps[k - 1]) / (eps[k] - eps[k - 1]);
  const double s = sig[k - 1] + w * (sig[k] - sig[k - 1]);
  eps.resize(k);
  sig.resize(k);
  if (eps.back() < target) {
    eps.push_back(target);
    sig.push_back(s);
  }
}

// A time for messages: "0.030000 ps".
std::string ps(double t) { return std::to_string(t) + " ps"; }

}  // namespace

void TensileJobSpec::validate() const {
  film_spec(*this, true).validate();
  if (nanoparticles < 0 || nanoparticles > 10000000)
    bad("nanoparticles", "in [0, 10000000]", nanoparticles);
  (void)PrerelaxCriterion(prerelax);
  check_range("prerelax_damping", prerelax_damping, 0, 1);
  if (prerelax_damping >= 1) bad("prerelax_damping", "in [0, 1)", prerelax_damping);
  check_range("relax_ps", relax_ps, 0, 1e7);
  check_range("dashpot_ratio", dashpot_ratio, 0, 1);
  check_range("local_damping", local_damping, 0, 1);
  if (local_damping >= 1) bad("local_damping", "in [0, 1)", local_damping);
  check_range("grip_width", grip_width, 0, 0.5 * film.side, true);
  check_range("sample_every_ps", sample_every_ps, 0, 1e6, true);
  check_range("relax_count_every_ps", relax_count_every_ps, 0, 1e6, true);
  check_range("vdw_flip_blend", laws.vdw.flip_blend, 0, 0.5);
  if (laws.vdw.torque != VdwTorque::Exact && laws.vdw.torque != VdwTorque::Pfc)
    bad("vdw_torque", "Exact or Pfc", static_cast<double>(laws.vdw.torque));
  if (temperature_k != 0) bad("temperature_k", "0 (the films start at rest)", temperature_k);
  const TensileProtocol check(loading_of(*this));  // rates, ramp, target, amplitude, period
  // Times and strains the run does not reach are simply not reported.
  if (relax_report_ps.size() > 1000)
    bad("relax_report_ps", "at most 1000 times", static_cast<double>(relax_report_ps.size()));
  for (double t : relax_report_ps) check_range("relax_report_ps", t, 0, 1e7);
  if (test_report_strains.size() > 1000)
    bad("test_report_strains", "at most 1000 strains",
        static_cast<double>(test_report_strains.size()));
  for (double e : test_report_strains) check_range("test_report_strains", e, 0, 10);
}

// What the job records outside its stages' observers: the pre-relaxations' outcomes. A part of
// the job (add_state), so checkpoints carry it.
class TensileJob::Records final : public Stateful {
 public:
  PrerelaxRecord prerelax, np_prerelax;
  StepCheck step;
  void save_state(StateWriter& w) const override {
    w.begin("tensile records");
    for (const PrerelaxRecord* p : {&prerelax, &np_prerelax}) {
      w.put(p->ran);
      w.put_string(p->reason);
      w.put(p->duration_ps);
      w.put(p->steps);
      w.put(p->dt_after_ps);
    }
    w.put(step.dt_ps);
    w.put(step.given);
    w.put(step.bound_ps);
    w.put(step.measured_ps);
  }
  void load_state(StateReader& r) override {
    r.begin("tensile records");
    for (PrerelaxRecord* p : {&prerelax, &np_prerelax}) {
      p->ran = r.get_bool("prerelax ran");
      p->reason = r.get_string("prerelax reason");
      p->duration_ps = r.get<double>("prerelax duration");
      p->steps = r.get<long>("prerelax steps");
      p->dt_after_ps = r.get<double>("prerelax dt after");
    }
    const auto time = [&](const char* what) {
      const double t = r.get<double>(what);
      if (!(std::isfinite(t) && t >= 0)) r.fail(what, "finite and >= 0 ps");
      return t;
    };
    step.dt_ps = time("step check dt");
    step.given = r.get_bool("step check given");
    step.bound_ps = time("step check bound");
    step.measured_ps = time("step check measured");
  }
};

// The relaxation's observer: aligned pairs (both counts), pores and the bending share at the
// report times, and the registry-free count every count_every ps (for the stabilisation time).
// Called before each force evaluation, with the positions at t (the energies are those of the
// evaluation before, one step behind).
class TensileJob::RelaxTracker final : public Updater {
 public:
  // Times past the relaxation's end are dropped; its end is always a report time.
  RelaxTracker(const std::vector<double>& report_times, double relax_ps, double count_every)
      : every_(count_every) {
    for (double t : report_times)
      if (t < relax_ps) times_.push_back(t);
    times_.push_back(relax_ps);
    std::sort(times_.begin(), times_.end());
    times_.erase(std::unique(times_.begin(), times_.end()), times_.end());
  }
  // Positions, the bonds' energies and forces (their own state): not the elements' forces.
  bool reads_forces() const override { return false; }
  bool applies_loads() const override { return false; }
  // It holds no element index: its counts, pores and bending share come from the system as it is.
  bool follows_reorder() const override { return true; }
  void apply(System& sys, double t) override {
    const double tol = 0.5 * sys.dt();
    while (next_report_ < times_.size() && t >= times_[next_report_] - tol) {
      const AlignedPairCounts a = aligned(sys);
      const PoreStats p = pores(sys);
      frames.push_back(
          {t, a.thesis, a.registry_free, p.large, p.void_fraction, bending_share(sys)});
      ++next_report_;
    }
    if (t >= next_count_ - tol) {
      count_t.push_back(t);
      count.push_back(static_cast<double>(aligned(sys).registry_free));
      next_count_ = t + every_;
    }
  }
  void save_state(StateWriter& w) const override {
    w.begin("tensile relax tracker");
    w.put(static_cast<std::uint64_t>(next_report_));
    w.put(next_count_);
    w.put(frames);
    w.put(count_t);
    w.put(count);
  }
  void load_state(StateReader& r) override {
    r.begin("tensile relax tracker");
    next_report_ = static_cast<std::size_t>(r.get<std::uint64_t>("next report"));
    if (next_report_ > times_.size()) r.fail("next report", "beyond the report times");
    next_count_ = r.get<double>("next count");
    r.get(frames, "relax frames");
    r.get(count_t, "count times");
    r.get(count, "counts", count_t.size());
  }

  std::vector<RelaxFrame> frames;
  std::vector<double> count_t, count;

 private:
  std::vector<double> times_;
  double every_;
  std::size_t next_report_ = 0;
  double next_count_ = 0;
};

// The test's observer: at its first call (the test's start) the references (mid-slab width,
// aligned pairs, pores between the grips); at each report strain reached, a StrainFrame; around
// 2 % the bonds' axial forces averaged over 10 ps for the fraction of tubes in tension; at 50,
// 100, 150, 200 % the fragments. Strains are the protocol's closed form at t.
class TensileJob::TestTracker final : public Updater {
 public:
  TestTracker(const TensileJob& job, std::vector<double> strains)
      : job_(job), strains_(std::move(strains)) {
    std::sort(strains_.begin(), strains_.end());
  }

  // Positions and the bonds' own state: not the elements' forces.
  bool reads_forces() const override { return false; }
  bool applies_loads() const override { return false; }
  void apply(System& sys, double t) override {
    const TensileProtocol& p = *job_.protocol_;
    if (!p.started()) return;
    const double eps = p.strain(t);
    const Elements& el = sys.elements();
    if (!started_) {
      started_ = true;
      const auto left = el.group_indices(kGripLeft), right = el.group_indices(kGripRight);
      double xl = -std::numeric_limits<double>::infinity(), xr = -xl;
      for (std::size_t i : left) xl = std::max(xl, el.x[i].x());
      for (std::size_t i : right) xr = std::min(xr, el.x[i].x());
      x_mid0_ = 0.5 * (xl + xr);
      half_slab_ = 0.05 * job_.spec_.film.side;  // |x − x_mid| < L/20
      window_ = Window2D{xl, xr, -0.5 * job_.spec_.film.side, 0.5 * job_.spec_.film.side};
      width0 = width(sys, 0);
      if (!bonds(sys).bonds().empty())
        bridges =
            grip_bridges(el, left, right, axial_stiffness(sys),
                         {p.loading().length, job_.spec_.film.side, job_.spec_.film.thickness});
      const AlignedPairCounts a = aligned(sys);
      start = {0,     a.thesis, a.registry_free, pores(sys, &window_).large, bending_energy(sys),
               width0};
      t2_ = job_.protocol_->loading().mode == TensileMode::Monotonic &&
                    job_.protocol_->loading().monotonic.target_strain >= kTensionStrain
                ? p.start_time() + p.time_to_strain(kTensionStrain)
                : std::numeric_limits<double>::infinity();
    }
    const double tol = 1e-12;
    while (next_strain_ < strains_.size() && eps >= strains_[next_strain_] - tol &&
           p.loading().mode == TensileMode::Monotonic) {
      const AlignedPairCounts a = aligned(sys);
      frames.push_back({eps, a.thesis, a.registry_free, pores(sys, &window_).large,
                        bending_energy(sys), width(sys, eps)});
      ++next_strain_;
    }
    // Axial bond forces averaged over [t2 − 5, t2 + 5] ps (§3.5).
    if (std::abs(t - t2_) <= 0.5 * kTensionWindow) accumulate_tension(sys);
    if (!tension_done && t > t2_ + 0.5 * kTensionWindow && tension_samples_ > 0)
      finish_tension(sys);
    while (next_fragment_ < kFragmentStrains.size() && eps >= kFragmentStrains[next_fragment_] &&
           p.loading().mode == TensileMode::Monotonic) {
      fragments.push_back(static_cast<double>(count_fragments_now(sys)));
      fragment_strains.push_back(kFragmentStrains[next_fragment_]);
      ++next_fragment_;
    }
  }

  // Mid-slab width at strain eps: the slab follows the film's midpoint, which the symmetric
  // grips keep in place.
  double width(const System& sys, double /*eps*/) const {
    return mid_width(sys.elements().x, x_mid0_, half_slab_).width;
  }

  void save_state(StateWriter& w) const override {
    w.begin("tensile test tracker");
    w.put(started_);
    w.put(x_mid0_);
    w.put(half_slab_);
    w.put(window_);
    w.put(width0);
    w.put(bridges);
    w.put(start);
    w.put(t2_);
    w.put(static_cast<std::uint64_t>(next_strain_));
    w.put(static_cast<std::uint64_t>(next_fragment_));
    w.put(frames);
    w.put(fragments);
    w.put(fragment_strains);
    w.put(force_sum_);
    w.put(tension_samples_);
    w.put(tension_done);
    w.put(tension);
  }
  void load_state(StateReader& r) override {
    r.begin("tensile test tracker");
    started_ = r.get_bool("started");
    x_mid0_ = r.get<double>("x_mid0");
    half_slab_ = r.get<double>("half slab");
    window_ = r.get<Window2D>("window");
    width0 = r.get<double>("width0");
    bridges = r.get<GripBridges>("grip bridges");
    start = r.get<StrainFrame>("start");
    t2_ = r.get<double>("t2");
    next_strain_ = static_cast<std::size_t>(r.get<std::uint64_t>("next strain"));
    next_fragment_ = static_cast<std::size_t>(r.get<std::uint64_t>("next fragment"));
    if (next_strain_ > strains_.size() || next_fragment_ > kFragmentStrains.size())
      r.fail("next strain", "beyond the report strains");
    r.get(frames, "strain frames");
    r.get(fragments, "fragments");
    r.get(fragment_strains, "fragment strains", fragments.size());
    r.get(force_sum_, "bond force sums");
    tension_samples_ = r.get<long>("tension samples");
    tension_done = r.get_bool("tension done");
    tension = r.get<TubeTension>("tension");
  }

  bool started() const { return started_; }

  double width0 = 0;
  GripBridges bridges;  // the pieces both grips hold, at the test's start
  StrainFrame start;
  std::vector<StrainFrame> frames;
  std::vector<double> fragments, fragment_strains;
  bool tension_done = false;
  TubeTension tension;

  // The tension from the bond forces averaged so far (none before the window opens): the test
  // may end before the window does (a 2 % target ends it 1 ps after 2 %); then the average runs
  // from 2 % − 5 ps to the test's end.
  std::optional<TubeTension> tension_so_far(const System& sys) const {
    if (tension_done) return tension;
    if (tension_samples_ == 0) return std::nullopt;
    return tension_of(sys);
  }

 private:
  const ParallelBond& bonds(const System& sys) const { return *sys.find<ParallelBond>(); }
  // EA (eV/nm) of the film's tubes (one tube type): kn·A times the rest length (centre to bond
  // point on either side) of the first bond.
  double axial_stiffness(const System& sys) const {
    const Bond& b = bonds(sys).bonds().front();
    return b.k.kn_area * (b.ci.norm() + b.cj.norm());
  }

  void accumulate_tension(const System& sys) {
    const Elements& el = sys.elements();
    const auto& b = bonds(sys).bonds();
    if (force_sum_.empty()) force_sum_.assign(b.size(), 0.0);
    for (std::size_t k = 0; k < b.size(); ++k) {
      const BondDeformation d =
          bond_deformation(b[k], el.x[b[k].i], el.q[b[k].i], el.x[b[k].j], el.q[b[k].j]);
      force_sum_[k] += b[k].k.kn_area * d.u_n;
    }
    ++tension_samples_;
  }

  void finish_tension(const System& sys) {
    tension = tension_of(sys);
    tension_done = true;
    force_sum_.clear();
  }

  TubeTension tension_of(const System& sys) const {
    const Elements& el = sys.elements();
    const auto& b = bonds(sys).bonds();
    std::vector<char> in_grip(el.size(), 0);
    for (auto g : {kGripLeft, kGripRight})
      for (std::size_t i : el.group_indices(g)) in_grip[i] = 1;
    std::vector<BondAxialForce> f(b.size());
    for (std::size_t k = 0; k < b.size(); ++k) {
      const std::int32_t piece = el.tube[b[k].i];
      const Chain* c = el.topology.chain(piece);
      f[k] = {piece, c && c->parent >= 0 ? c->parent : piece,
              force_sum_[k] / static_cast<double>(tension_samples_),
              in_grip[b[k].i] && in_grip[b[k].j]};
    }
    return tube_tension(f);
  }

  // Components of the graph of bonds plus attracting contact pairs (U < 0; §3.5).
  static std::size_t count_fragments_now(const System& sys) {
    return count_film_fragments(sys).count;
  }

  const TensileJob& job_;
  std::vector<double> strains_;
  bool started_ = false;
  double x_mid0_ = 0, half_slab_ = 0;
  Window2D window_;
  double t2_ = std::numeric_limits<double>::infinity();
  std::size_t next_strain_ = 0, next_fragment_ = 0;
  std::vector<double> force_sum_;
  long tension_samples_ = 0;
};

// Places the NPs in the relaxed film (tensile.md §3.2, deposit after relaxation). It takes no
// step: begin() draws the NPs on a copy of the film and keeps their positions, which the job adds
// to a new system when the stage has finished (stage_finished), and which checkpoints taken later
// carry (its result), with whether the placement left an overlap to pre-relax.
class TensileJob::DepositStage final : public Stage {
 public:
  explicit DepositStage(TensileJob& job) : Stage("deposit"), job_(job) {}
  System& system() override { return *job_.sys_; }
  bool reports() const override { return false; }
  void begin() override {
    Elements el = job_.sys_->elements();
    const std::size_t before = el.size();
    NpPlacementSpec s;
    s.count = job_.spec_.nanoparticles;
    s.side = job_.spec_.film.side;
    s.thickness = job_.spec_.film.thickness;
    s.seed = job_.spec_.seed;
    const NpPlacement placed = place_nanoparticles(el, s);
    positions.clear();
    for (std::size_t i = before; i < el.size(); ++i) positions.push_back(el.x[i]);
    candidates = placed.candidates;
    done_ = true;
    decided = false;
  }
  bool finished() const override { return done_; }
  void advance(long) override {}
  long steps_done() const override { return 0; }
  long planned_steps() const override { return 0; }
  void save_state(StateWriter& w) const override {
    w.begin("deposit");
    w.put(done_);
    save_result(w);
  }
  void load_state(StateReader& r) override {
    r.begin("deposit");
    done_ = r.get_bool("done");
    load_result(r);
  }
  void save_result(StateWriter& w) const override {
    w.begin("deposit result");
    w.put(positions);
    w.put(candidates);
    w.put(decided);
    w.put(overlaps);
    w.put(dt);
  }
  void load_result(StateReader& r) override {
    r.begin("deposit result");
    r.get(positions, "np positions");
    candidates = r.get<long>("candidates");
    decided = r.get_bool("decided");
    overlaps = r.get_bool("overlaps");
    dt = r.get<double>("dt");
    if (!(std::isfinite(dt) && dt > 0)) r.fail("dt", "finite and > 0 ps");
    done_ = true;
  }

  std::vector<Vec3> positions;
  long candidates = 0;
  bool decided = false;  // whether `overlaps` was measured on the system with the NPs
  bool overlaps = false;
  double dt = 0;  // ps, the step picked for the film with the NPs (with `decided`)

 private:
  TensileJob& job_;
  bool done_ = false;
};

// A pre-relaxation (the film's, or the one after an NP deposit): a SystemStage made when the
// stage is installed, so that its cap in steps follows the job's step at that time. The job may
// skip it before it begins (after a deposit that left no overlap): it then ends at once, taking
// no step. Its result is the step the job picked at its end for the stages after it (0 until
// picked): a live run's stage_finished picks it from the relaxed state, a checkpoint restores it
// (the resumed job's film is then still the generated one, from which no step can be picked).
class TensileJob::PrerelaxStage final : public Stage {
 public:
  using Factory = std::function<std::unique_ptr<SystemStage>()>;
  PrerelaxStage(const std::string& name, TensileJob& job, Factory make)
      : Stage(name), job_(job), make_(std::move(make)) {}
  System& system() override { return *job_.sys_; }
  void install() override {
    s_ = make_();
    s_->install();
  }
  void begin() override {
    dt_after = 0;
    if (!skip) s_->begin();
  }
  bool finished() const override { return skip || (s_ && s_->finished()); }
  void advance(long n) override {
    if (!skip) s_->advance(n);
  }
  long steps_done() const override { return skip || !s_ ? 0 : s_->steps_done(); }
  long planned_steps() const override { return skip || !s_ ? 0 : s_->planned_steps(); }
  std::string phase() const override { return s_ ? s_->phase() : name(); }
  void save_state(StateWriter& w) const override {
    w.put(skip);
    s_->save_state(w);
  }
  void load_state(StateReader& r) override {
    skip = r.get_bool("skip");
    s_->load_state(r);
  }
  void save_result(StateWriter& w) const override {
    w.begin(name() + " result");
    w.put(dt_after);
  }
  void load_result(StateReader& r) override {
    r.begin(name() + " result");
    dt_after = r.get<double>("dt after");
    if (!(std::isfinite(dt_after) && dt_after >= 0))
      r.fail("dt after", "finite and >= 0 ps (0: skipped)");
  }

  bool skip = false;
  double dt_after = 0;  // ps

 private:
  TensileJob& job_;
  Factory make_;
  std::unique_ptr<SystemStage> s_;
};

TensileJob::TensileJob(const TensileJobSpec& spec, IntegratorSettings settings)
    : spec_(spec), settings_(settings) {
  spec_.validate();
  Elements el;
  film_ = add_tensile_film(el, film_spec(spec_, !deposit_after(spec_)));
  build(std::move(el));
}

TensileJob::TensileJob(Elements film, const TensileJobSpec& spec, IntegratorSettings settings)
    : spec_(spec), settings_(settings) {
  spec_.validate();
  if (film.size() == 0) throw std::invalid_argument("tensile film: no elements given");
  build(std::move(film));
}

std::unique_ptr<System> TensileJob::probe(const Elements& el, const ParallelBond* rest) const {
  IntegratorSettings probe_settings = settings_;
  probe_settings.dt.reset();
  auto p = tensile_film_system(el, probe_settings, spec_.dashpot_ratio, rest, spec_.laws);
  p->initialize();
  return p;
}

StepCheck TensileJob::pick_dt(const Elements& el, const ParallelBond* rest) const {
  const auto probe = this->probe(el, rest);
  // With multiple time stepping the outer step respa_k·dt must also stay within safety × the
  // slow forces' own critical step (System::initialize refuses a given dt beyond it; the job
  // picks its step itself, so it keeps to both limits rather than stop mid-run on the guard).
  double dt = probe->dt();
  if (settings_.respa_k > 1)
    dt = std::min(dt, settings_.safety * probe->critical_outer_dt() / settings_.respa_k);
  return {kAutoDtFactor * dt, false, probe->critical_dt(), 0.0};
}

StepCheck TensileJob::step_after_prerelax(const Elements& el, const ParallelBond* rest) const {
  return given_dt_ ? checked_given_dt(el, rest) : pick_dt(el, rest);
}

StepCheck TensileJob::checked_given_dt(const Elements& el, const ParallelBond* rest) const {
  const double dt = *given_dt_, safety = settings_.safety;
  const auto probe = this->probe(el, rest);
  if (settings_.respa_k > 1 && settings_.respa_k * dt > safety * probe->critical_outer_dt())
    throw ConfigError("tensile: the outer step respa_k x dt = " + ps(settings_.respa_k * dt) +
                      " is above the slow forces' safe limit " +
                      ps(safety * probe->critical_outer_dt()) + " on the film the relaxation " +
                      "or test starts from: lower respa_k or dt, or use dt: auto");
  const double bound = probe->critical_dt();
  if (dt <= safety * bound) return {dt, true, bound, 0.0};
  // Above the automatic step's bound, which is up to 2x below the true limit on a relaxed film
  // (docs/stability.md): measure the true one, from two random starts that must agree (the top
  // of a film's spectrum is dense, and a Ritz value that met its tolerance early can be an
  // interior one), the larger Ritz value plus its residual.
  SpectrumSettings s;
  s.displacement = kGivenDtProbeMove;
  s.tolerance = 1e-4;
  s.max_iterations = 300;
  s.check_smoothness = false;
  const SpectrumEstimate e1 = largest_frequency(*probe, s);
  s.seed = 2;
  const SpectrumEstimate e2 = largest_frequency(*probe, s);
  return judge_given_step(dt, safety, bound, e1, e2,
                          [&](double omega) { return probe->damped_critical_dt(omega); });
}

StepCheck judge_given_step(double dt, double safety, double bound, const SpectrumEstimate& e1,
                           const SpectrumEstimate& e2,
                           const std::function<double(double)>& damped_critical) {
  const auto upper = [](const SpectrumEstimate& e) {
    return std::sqrt(e.omega_max * e.omega_max + e.residual);
  };
  const double omega = std::max(upper(e1), upper(e2));
  const bool agree = std::abs(e1.omega_max - e2.omega_max) <= 0.01 * omega;
  if (!e1.converged || !e2.converged || !agree)
    throw ConfigError("tensile: time step dt = " + ps(dt) + " is above the automatic step's safe " +
                      "limit " + ps(safety * bound) + " on the film the relaxation or test " +
                      "starts from, and its true critical step could not be measured (Lanczos " +
                      "from two starts: " + std::to_string(2.0 / e1.omega_max) + " and " +
                      std::to_string(2.0 / e2.omega_max) + " ps, " +
                      (agree ? "not converged" : "not agreeing") +
                      "): lower dt below that limit, or use dt: auto");
  const double critical = damped_critical(omega);
  if (dt <= safety * critical) return {dt, true, bound, critical};
  throw ConfigError("tensile: time step dt = " + ps(dt) + " is above the safe limit " +
                    ps(safety * critical) + " of the film the relaxation or test starts from " +
                    "(safety " + std::to_string(safety) + " x its critical step " + ps(critical) +
                    ", 2/omega_max measured over its forces, with the dashpots' damping; the " +
                    "automatic step's bound is " + ps(bound) + "): lower dt, raise safety " +
                    "(at most 1), or use dt: auto");
}

void TensileJob::rebuild(Elements el, double dt, const ParallelBond* rest) {
  settings_.dt = dt;
  sys_ = tensile_film_system(std::move(el), settings_, spec_.dashpot_ratio, rest, spec_.laws);
}

void TensileJob::build(Elements el) {
  // The pre-relaxation always picks its step (tensile.md §3.3: dt auto; the generated film's
  // overlaps need a few fs); a caller's dt is the step of the relaxation and the test (§3.4: 30 fs
  // as the thesis, or auto), checked when they start (checked_given_dt). The job checks every
  // step itself, from the state each stage starts from, and a checkpoint restores it: a resumed
  // job's initialize() runs on the generated film before the checkpoint overwrites it, where a
  // step picked on the relaxed film would be refused.
  given_dt_ = settings_.dt;
  settings_.check_dt = false;
  settings_.dt = pick_dt(el, nullptr).dt_ps;
  dt_start_ = *settings_.dt;
  sys_ = tensile_film_system(std::move(el), settings_, spec_.dashpot_ratio, nullptr, spec_.laws);

  records_ = std::make_shared<Records>();
  protocol_ = std::make_shared<TensileProtocol>(loading_of(spec_));
  GripStressSettings gs;
  gs.width = spec_.film.side;
  gs.height = spec_.film.thickness;
  gs.every = spec_.sample_every_ps;
  sampler_ = std::make_shared<GripStressSampler>(
      [p = protocol_.get()](double t) { return p->strain(t); }, gs);
  relax_tracker_ = std::make_shared<RelaxTracker>(spec_.relax_report_ps, spec_.relax_ps,
                                                  spec_.relax_count_every_ps);
  test_tracker_ = std::make_shared<TestTracker>(*this, spec_.test_report_strains);

  // Each pre-relaxation's cap in steps follows the step in force when it is installed.
  auto prerelax_stage = [&](const std::string& name, std::shared_ptr<PrerelaxCriterion>& c) {
    c = std::make_shared<PrerelaxCriterion>(spec_.prerelax);
    return std::make_unique<PrerelaxStage>(name, *this, [this, name, c] {
      SystemStage::Settings st;
      st.local_damping = spec_.prerelax_damping;
      st.memory_order = MemoryOrder::Slabs;
      st.stop = PrerelaxCriterion::stop(c, *settings_.dt);
      return std::make_unique<SystemStage>(name, *this, std::move(st));
    });
  };
  prerelax_index_ = relax_index_ = deposit_index_ = np_prerelax_index_ = kNone;
  prerelax_index_ = stages().size();
  auto p = prerelax_stage("prerelax", prerelax_);
  prerelax_stage_ = p.get();
  add_stage(std::move(p));
  if (spec_.relax_ps > 0) {
    SystemStage::Settings st;
    st.local_damping = spec_.local_damping;
    st.observers = {relax_tracker_};
    st.memory_order = MemoryOrder::Slabs;
    st.stop = StopCondition::after(spec_.relax_ps);
    relax_index_ = stages().size();
    add_stage(std::make_unique<SystemStage>("relax", *this, std::move(st)));
  }
  if (deposit_after(spec_)) {
    auto d = std::make_unique<DepositStage>(*this);
    deposit_ = d.get();
    deposit_index_ = stages().size();
    add_stage(std::move(d));
    auto o = prerelax_stage("np_prerelax", np_prerelax_);
    np_stage_ = o.get();
    np_prerelax_index_ = stages().size();
    add_stage(std::move(o));
  }
  SystemStage::Settings st;
  st.protocol = protocol_;
  st.local_damping = spec_.local_damping;
  st.observers = {sampler_, test_tracker_};
  // One sampling interval (and at least one step: the pre-relaxation's step, no longer than the
  // test's) past the loading's end, so that the sampler, one evaluation behind, records a frame
  // past the loading's end (summary() ends the curve at the target strain).
  st.stop = StopCondition::after(protocol_->duration() + spec_.sample_every_ps +
                                 std::max(dt_start_, given_dt_.value_or(0.0)));
  test_index_ = stages().size();
  add_stage(std::make_unique<SystemStage>("tensile", *this, std::move(st)));
  add_state(records_);
  // The relaxation's records outlive its stage: later checkpoints carry them too (inside the
  // relaxation they are saved twice, and loaded twice alike).
  add_state(relax_tracker_);
}

TensileJob::~TensileJob() = default;

void TensileJob::stage_finished(std::size_t k) {
  System& sys = *sys_;
  if (k == prerelax_index_ || k == np_prerelax_index_) {
    PrerelaxStage& stage = k == prerelax_index_ ? *prerelax_stage_ : *np_stage_;
    PrerelaxRecord& rec = k == prerelax_index_ ? records_->prerelax : records_->np_prerelax;
    const bool skipped = stage.skip;
    rec.ran = !skipped;
    rec.reason = skipped ? "skipped: the NP placement left no overlap"
                         : (k == prerelax_index_ ? prerelax_ : np_prerelax_)->reason();
    rec.duration_ps = skipped ? 0.0 : sys.time();
    rec.steps = skipped ? 0 : sys.steps();
    if (!skipped) {
      // The pre-relaxed film at rest, in a new system (clock, steps and energy ledger from 0)
      // whose step is picked anew: the overlaps that set the first step are gone.
      Elements el = sys.elements();
      zero_motion(el);
      if (stage.dt_after == 0) {
        records_->step = step_after_prerelax(el, sys.find<ParallelBond>());
        stage.dt_after = records_->step.dt_ps;
      }
      rebuild(std::move(el), stage.dt_after, sys.find<ParallelBond>());
      rec.dt_after_ps = stage.dt_after;
    }
  }
  if (k == deposit_index_) {
    // The relaxed film (velocities kept) plus the NPs at rest, in a new system whose bonds keep
    // the generated film's rest state, at a step picked for it (NPs may overlap tubes).
    Elements el = sys.elements();
    for (const Vec3& x : deposit_->positions) el.add(nanoparticle(x));
    // (rebuild() replaces the system, and with it the bonds: `sys` and its bond model are not
    // to be used after it; the new system's bonds keep the same rest state.)
    if (!deposit_->decided) {
      records_->step = pick_dt(el, sys.find<ParallelBond>());
      deposit_->dt = records_->step.dt_ps;
    }
    rebuild(el, deposit_->dt, sys.find<ParallelBond>());
    sys_->initialize();
    if (!deposit_->decided) {
      deposit_->overlaps = !np_prerelax_->measure(*sys_).overlap_free;
      deposit_->decided = true;
      // No NP pre-relaxation: the test follows on this film, at the caller's step if given.
      if (!deposit_->overlaps && given_dt_) {
        const ParallelBond* rest = sys_->find<ParallelBond>();
        records_->step = checked_given_dt(el, rest);
        deposit_->dt = records_->step.dt_ps;
        rebuild(std::move(el), deposit_->dt, rest);
        sys_->initialize();
      }
    }
    np_stage_->skip = !deposit_->overlaps;
  }
  if (k + 1 == test_index_) {
    System& s = *sys_;
    if (spec_.zero_velocities_at_test) zero_motion(s.elements());
    GripSettings g;
    g.width = spec_.grip_width;
    select_grips(s.elements(), g);
    protocol_->start(s);
  }
}

const PrerelaxRecord& TensileJob::prerelax_record() const { return records_->prerelax; }
const PrerelaxRecord& TensileJob::np_prerelax_record() const { return records_->np_prerelax; }
const StepCheck& TensileJob::step_check() const { return records_->step; }
const std::vector<RelaxFrame>& TensileJob::relax_frames() const { return relax_tracker_->frames; }
const std::vector<StrainFrame>& TensileJob::strain_frames() const { return test_tracker_->frames; }

std::optional<double> TensileJob::relax_stabilisation_ps() const {
  if (relax_tracker_->count.size() < 2) return std::nullopt;
  return stabilisation_time(relax_tracker_->count_t, relax_tracker_->count);
}

double TensileJob::duration() const {
  double d =
      spec_.prerelax.max_time + spec_.relax_ps + protocol_->duration() + spec_.sample_every_ps;
  if (deposit_after(spec_)) d += spec_.prerelax.max_time;
  return d;
}

std::vector<std::string> TensileJob::columns() const {
  std::vector<std::string> c = {"time_ps",
                                "stage",
                                "strain",
                                "stress_GPa",
                                "grip_force_left_eV_per_nm",
                                "grip_force_right_eV_per_nm",
                                "aligned_pairs_thesis",
                                "aligned_pairs_registry_free",
                                "bending_share"};
  for (std::string& e : energy_columns(energy_terms())) c.push_back(std::move(e));
  return c;
}

std::vector<double> TensileJob::observe() {
  const System& sys = *sys_;
  const std::size_t k = stage_index();
  double code = 0;
  if (k == relax_index_) code = 1;
  if (k == deposit_index_ || k == np_prerelax_index_) code = 2;
  if (k >= test_index_) code = 3;
  double strain = 0, stress = 0;
  GripForces f;
  if (code == 3 && protocol_->started()) {
    const Elements& el = sys.elements();
    f = grip_forces(sys, el.group_indices(kGripLeft), el.group_indices(kGripRight));
    strain = protocol_->strain(sys.time());
    stress = grip_stress_gpa(f, spec_.film.side, spec_.film.thickness);
  }
  const AlignedPairCounts a = aligned(sys);
  std::vector<double> v = {sys.time(),
                           code,
                           strain,
                           stress,
                           f.left,
                           f.right,
                           static_cast<double>(a.thesis),
                           static_cast<double>(a.registry_free),
                           bending_share(sys)};
  for (double e : energy_values(sys, energy_terms())) v.push_back(e);
  return v;
}

Summary TensileJob::summary() {
  const System& sys = *sys_;
  const FilmReport fr = film_report(sys.elements(), spec_.film.side, spec_.film.thickness);
  Summary s = {{"segments", static_cast<long>(fr.segments)},
               {"nanoparticles", static_cast<long>(fr.nanoparticles)},
               {"tubes", static_cast<long>(fr.tubes)},
               {"pieces", static_cast<long>(fr.pieces)},
               {"density_g_cm3", fr.density},
               {"porosity", fr.porosity}};
  if (spec_.nanoparticles > 0 || fr.nanoparticles > 0)
    s.emplace_back("np_deposit", std::string(np_deposit_name(spec_.np_deposit)));
  s.emplace_back("prerelax_reason", records_->prerelax.reason);
  s.emplace_back("prerelax_ps", records_->prerelax.duration_ps);
  s.emplace_back("prerelax_steps", records_->prerelax.steps);
  s.emplace_back("prerelax_dt_ps", dt_start_);
  if (deposit_after(spec_) && deposit_->finished()) {
    s.emplace_back("np_candidates", deposit_->candidates);
    s.emplace_back("np_prerelax_reason", records_->np_prerelax.reason);
    s.emplace_back("np_prerelax_ps", records_->np_prerelax.duration_ps);
  }
  // The step of the relaxation and the test, and what it was checked against (the accuracy
  // line's "x critical step" is over the automatic bound, which a given step may exceed).
  if (const StepCheck& c = records_->step; c.dt_ps > 0) {
    s.emplace_back("step_origin", std::string(c.given ? "given" : "picked"));
    s.emplace_back("step_dt_ps", c.dt_ps);
    if (c.measured_ps > 0) {
      s.emplace_back("step_critical_measured_ps", c.measured_ps);
      s.emplace_back("step_over_measured", c.dt_ps / c.measured_ps);
    }
    s.emplace_back("step_bound_ps", c.bound_ps);
    s.emplace_back("step_over_bound", c.dt_ps / c.bound_ps);
  }
  s.emplace_back("relax_ps", spec_.relax_ps);
  if (auto ts = relax_stabilisation_ps()) s.emplace_back("relax_stabilisation_ps", *ts);
  if (const auto& rf = relax_tracker_->frames; !rf.empty()) {
    s.emplace_back("relax_aligned_registry_free_start", rf.front().aligned_registry_free);
    s.emplace_back("relax_aligned_registry_free_end", rf.back().aligned_registry_free);
    s.emplace_back("relax_aligned_thesis_start", rf.front().aligned_thesis);
    s.emplace_back("relax_aligned_thesis_end", rf.back().aligned_thesis);
    s.emplace_back("relax_pores_gt200nm2_start", rf.front().pores_large);
    s.emplace_back("relax_pores_gt200nm2_end", rf.back().pores_large);
    s.emplace_back("relax_bending_share_end", rf.back().bending_share);
  }
  if (const TestTracker& tt = *test_tracker_; tt.started()) {
    s.emplace_back("grip_bridging_pieces", static_cast<long>(tt.bridges.pieces));
    s.emplace_back("grip_bridging_affine_modulus_GPa", tt.bridges.affine_modulus);
  }
  std::vector<double> eps = sampler_->strains(), sig = sampler_->stresses();
  if (spec_.mode == TensileMode::Monotonic && !eps.empty()) {
    end_at_target(eps, sig, spec_.monotonic.target_strain);
    try {
      const LineFit fit = modulus_fit(eps, sig);
      s.emplace_back("youngs_modulus_GPa", fit.slope);
      s.emplace_back("modulus_intercept_GPa", fit.intercept);
      if (auto y = offset_yield_strain(eps, sig, fit)) s.emplace_back("yield_strain", *y);
    } catch (const std::invalid_argument&) {
      // No frame in the 1–2 % window yet: no modulus.
    }
    s.emplace_back("peak_stress_GPa", *std::max_element(sig.begin(), sig.end()));
    s.emplace_back("final_strain", eps.back());
    const TestTracker& tt = *test_tracker_;
    if (const auto tension = tt.tension_so_far(sys)) {
      s.emplace_back("tubes_in_tension_at_2pct", tension->fraction_pieces);
      s.emplace_back("parents_in_tension_at_2pct", tension->fraction_parents);
    }
    if (tt.width0 > 0)
      s.emplace_back("mid_width_shrinkage_end", shrinkage(tt.width(sys, eps.back()), tt.width0));
    const AlignedPairCounts a = aligned(sys);
    s.emplace_back("aligned_registry_free_test_start", tt.start.aligned_registry_free);
    s.emplace_back("aligned_registry_free_test_end", a.registry_free);
    s.emplace_back("aligned_thesis_test_start", tt.start.aligned_thesis);
    s.emplace_back("aligned_thesis_test_end", a.thesis);
    s.emplace_back("pores_gt200nm2_test_start", tt.start.pores_large);
    if (!tt.frames.empty())
      s.emplace_back("pores_gt200nm2_test_last_report", tt.frames.back().pores_large);
    if (spec_.monotonic.target_strain >= kFragmentStrains.front()) {
      s.emplace_back("toughness_GJ_m3", toughness(eps, sig));
      if (auto f = failure_strain(eps, sig)) s.emplace_back("failure_strain", *f);
      for (std::size_t i = 0; i < tt.fragments.size(); ++i)
        s.emplace_back(
            "fragments_at_" + std::to_string(std::lround(100 * tt.fragment_strains[i])) + "pct",
            static_cast<long>(tt.fragments[i]));
    }
  }
  if (spec_.mode == TensileMode::Cyclic && eps.size() > 2) {
    CycleSettings cs;
    cs.period = protocol_->period();
    // The sampler's first frame comes one step after the protocol's start (it records the
    // evaluation before each of its calls): the cycles are counted from there, at most one step
    // (dt << P) late. From the start itself, a test after a relaxation reported no cycle.
    cs.t0 = std::max(protocol_->start_time(), sampler_->times().front());
    try {
      const auto cycles = analyse_cycles(sampler_->times(), eps, sig, cs);
      s.emplace_back("cycles_complete", static_cast<long>(cycles.size()));
      for (const CycleResult& c : cycles) {
        const std::string k = "cycle_" + std::to_string(c.cycle + 1) + "_";
        s.emplace_back(k + "loop_area_J_cm3", c.loop_area_j_per_cm3);
        s.emplace_back(k + "modulus_GPa", c.modulus);
        s.emplace_back(k + "phase_lead", c.phase_lead);
      }
    } catch (const std::invalid_argument&) {
      // No complete cycle yet.
    }
  }
  s.emplace_back("energy_balance_error", sys.energy_balance_error());
  s.emplace_back("dt_ps", sys.dt());
  s.emplace_back("simulated_ps", sys.time());
  return s;
}

}  // namespace mdem
