// The compression job (compression_job.h, scenes.md compression, thesis Ch. 6).
#include "mdem/job/compression_job.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

#include "mdem/core/limits.h"
#include "mdem/core/units.h"
#include "mdem/force/contact/linear_contact.h"
#include "mdem/force/wall/planar_wall.h"
#include "mdem/job/packing_stage.h"

namespace mdem {
namespace {

// Checks what the packing and the protocol do not, before the (possibly long) packing runs.
const CompressionJobSpec& validated(const CompressionJobSpec& s) {
  (void)CompressionProtocol(s.loading, 0, 1);  // speed, peak_displacement
  if (std::isfinite(s.particle.r_outer) && s.loading.peak_displacement >= 2.0 * s.particle.r_outer)
    throw std::invalid_argument(
        "compression loading peak_displacement must be below the particle's diameter " +
        std::to_string(2.0 * s.particle.r_outer) + " nm, got " +
        std::to_string(s.loading.peak_displacement));
  if (!std::isfinite(s.viscous_ratio) || s.viscous_ratio < 0 ||
      s.viscous_ratio > limits::kMaxDashpotRatio)
    throw std::invalid_argument("compression viscous_ratio must be in [0, " +
                                std::to_string(static_cast<int>(limits::kMaxDashpotRatio)) +
                                "] (critical damping), got " + std::to_string(s.viscous_ratio));
  GrainBondParams bp = s.bond;
  bp.material = s.particle.material;
  GrainBond check(bp);  // bond behaviour and strength
  return s;
}

PackingSpec packing_spec(const CompressionJobSpec& s, const IntegratorSettings& st) {
  PackingSpec p = s.particle;
  if (p.threads == 0) p.threads = st.threads;  // the run's thread count packs it too
  return p;
}

// The packed grains, then the top and bottom platens just touching the particle's z extremes.
Elements with_platens(const PackedParticle& packed, const PackingSpec& p) {
  Elements el = packed.grains;
  double top = -std::numeric_limits<double>::infinity();
  double bottom = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < el.size(); ++i) {
    top = std::max(top, el.x[i].z() + el.radius[i]);
    bottom = std::min(bottom, el.x[i].z() - el.radius[i]);
  }
  // A platen's mass only enters the kinetic energy of its prescribed motion: that of the largest
  // grain keeps it negligible next to the work done.
  const double mass =
      p.material.density * 4.0 / 3.0 * std::numbers::pi * std::pow(p.grain_r_max, 3);
  const std::size_t t = add_platen(el, Vec3(0, 0, top), Vec3(0, 0, -1), mass, p.r_outer);
  const std::size_t b = add_platen(el, Vec3(0, 0, bottom), Vec3(0, 0, 1), mass, p.r_outer);
  el.groups.add(std::string(kTopPlaten), {el.tag[t]});
  el.groups.add(std::string(kBottomPlaten), {el.tag[b]});
  el.groups.add(std::string(kPlatens), {el.tag[t], el.tag[b]});
  return el;
}

}  // namespace

// Peak force and the first loading's stiffness, tracked before every force evaluation, one
// evaluation behind: the forces in the system are those of the previous evaluation, made at the
// displacement recorded at the previous call. An observer of the compression stage.
class CompressionJob::Tracker final : public Updater {
 public:
  explicit Tracker(const CompressionJob& job) : job_(job) {}
  bool applies_loads() const override { return false; }  // an observer
  void apply(System& sys, double) override {
    if (have_prev) {
      const double F = job_.platen_force_nN();
      if (F > peak_force) {
        peak_force = F;
        peak_at = prev_disp;
      }
      if (prev_loading && prev_disp <= 0.5 * job_.protocol_->params().peak_displacement) {
        sum_fh += F * prev_disp;
        sum_hh += prev_disp * prev_disp;
      }
    }
    prev_disp = job_.displacement();
    prev_loading = job_.protocol_->loading(sys.time());
    have_prev = true;
  }
  void save_state(StateWriter& w) const override {
    w.begin("compression");
    w.put(peak_force);
    w.put(peak_at);
    w.put(prev_disp);
    w.put(have_prev);
    w.put(prev_loading);
    w.put(sum_fh);
    w.put(sum_hh);
  }
  void load_state(StateReader& r) override {
    r.begin("compression");
    peak_force = r.get<double>("peak_force");
    peak_at = r.get<double>("peak_at");
    prev_disp = r.get<double>("prev_disp");
    have_prev = r.get_bool("have_prev");
    prev_loading = r.get_bool("prev_loading");
    sum_fh = r.get<double>("sum_fh");
    sum_hh = r.get<double>("sum_hh");
  }

  double peak_force = 0, peak_at = 0;
  double prev_disp = 0;
  bool have_prev = false, prev_loading = false;
  double sum_fh = 0, sum_hh = 0;  // least squares F = k·h over the first half of the loading

 private:
  const CompressionJob& job_;
};

CompressionJob::CompressionJob(const CompressionJobSpec& spec, IntegratorSettings settings)
    : spec_(validated(spec)), settings_(settings) {
  auto packing = std::make_unique<PackingStage>(packing_spec(spec_, settings_));
  packing_stage_ = packing.get();
  add_stage(std::move(packing));
  add_compression_stage();
}

CompressionJob::CompressionJob(PackedParticle packed, const CompressionJobSpec& spec,
                               IntegratorSettings settings)
    : spec_(validated(spec)), settings_(settings) {
  build(std::move(packed));
  add_compression_stage();
}

CompressionJob::~CompressionJob() = default;

void CompressionJob::add_compression_stage() {
  // The platens' indices are set when the system is built.
  protocol_ = std::make_shared<CompressionProtocol>(spec_.loading, 0, 1);
  if (sys_) protocol_->set_platens(top_, bottom_);
  tracker_ = std::make_shared<Tracker>(*this);
  SystemStage::Settings st;
  st.protocol = protocol_;
  st.observers = {tracker_};
  st.stop = StopCondition::after(protocol_->duration());
  add_stage(std::make_unique<SystemStage>("compression", *this, std::move(st)));
}

void CompressionJob::stage_finished(std::size_t k) {
  if (packing_stage_ && k == 0) {
    build(packing_stage_->result());
    protocol_->set_platens(top_, bottom_);
  }
}

System& CompressionJob::system() { return sys_ ? *sys_ : packing_stage_->system(); }

const System& CompressionJob::sys() const {
  if (!sys_)
    throw std::logic_error("compression job: the particle is not packed yet (run the packing)");
  return *sys_;
}

const GrainBond& CompressionJob::bonds() const {
  sys();
  return *bonds_;
}

void CompressionJob::build(PackedParticle packed) {
  packed_ = std::move(packed);
  const PackingSpec& p = spec_.particle;
  sys_ = std::make_unique<System>(with_platens(packed_, p), settings_);
  System& sys = *sys_;
  n_grains_ = packed_.grains.size();
  const Elements& el = sys.elements();
  top_ = el.group_indices(kTopPlaten).front();
  bottom_ = el.group_indices(kBottomPlaten).front();
  z_top0_ = el.x[top_].z();
  z_bottom0_ = el.x[bottom_].z();
  height0_ = z_top0_ - z_bottom0_;
  x0_ = el.x;

  GrainBondParams bp = spec_.bond;
  bp.material = p.material;
  auto bonds = std::make_unique<GrainBond>(bp);
  for (const auto& [i, j] : packed_.touching) bonds->add(el, i, j);
  bonds_ = sys.add(std::move(bonds));
  initial_bonds_ = bonds_->bonds().size();
  sys.add(std::make_unique<LinearContact>(p.material.youngs, p.grain_r_max, bonds_));
  sys.add(std::make_unique<PlanarWallContact>(p.material.youngs));
  if (spec_.viscous_ratio > 0)
    sys.add(std::make_unique<GrainDashpots>(spec_.viscous_ratio, bonds_, p.material.youngs,
                                            p.grain_r_max));

  // Slip reference: each grain's bonded neighbours at the start of loading.
  std::vector<std::uint32_t> count(n_grains_ + 1, 0);
  for (const GrainBondRecord& b : bonds_->bonds()) {
    ++count[b.bond.i + 1];
    ++count[b.bond.j + 1];
  }
  for (std::size_t i = 0; i < n_grains_; ++i) count[i + 1] += count[i];
  slip_offsets_ = count;
  slip_partners_.resize(count.back());
  std::vector<std::uint32_t> fill(count.begin(), count.end() - 1);
  for (const GrainBondRecord& b : bonds_->bonds()) {
    slip_partners_[fill[b.bond.i]++] = b.bond.j;
    slip_partners_[fill[b.bond.j]++] = b.bond.i;
  }
}

double CompressionJob::duration() const { return protocol_->duration(); }

std::vector<EnergyTerm> CompressionJob::energy_terms() {
  return {EnergyTerm::BondTension, EnergyTerm::BondShear, EnergyTerm::BondBending,
          EnergyTerm::BondTorsion, EnergyTerm::Contact};
}

double CompressionJob::platen_force_nN() const {
  const Elements& el = sys().elements();
  const auto& fd = sys().damping_forces();
  auto fz = [&](std::size_t p) { return el.f[p].z() + (p < fd.size() ? fd[p].z() : 0.0); };
  return units::to_nN(0.5 * (fz(top_) - fz(bottom_)));
}

double CompressionJob::displacement() const {
  const Elements& el = sys().elements();
  return (z_top0_ - el.x[top_].z()) + (el.x[bottom_].z() - z_bottom0_);
}

double CompressionJob::height() const {
  const Elements& el = sys().elements();
  double top = -std::numeric_limits<double>::infinity();
  double bottom = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n_grains_; ++i) {
    top = std::max(top, el.x[i].z() + el.radius[i]);
    bottom = std::min(bottom, el.x[i].z() - el.radius[i]);
  }
  return top - bottom;
}

Mat3 CompressionJob::rigid_rotation() const {
  // Kabsch: the rotation R minimising Σ |(x_i − c) − R (X_i − C)|² over the bonded grains.
  const Elements& el = sys().elements();
  Vec3 c = Vec3::Zero(), c0 = Vec3::Zero();
  long n = 0;
  for (std::size_t i = 0; i < n_grains_; ++i)
    if (slip_offsets_[i + 1] > slip_offsets_[i]) {
      c += el.x[i];
      c0 += x0_[i];
      ++n;
    }
  if (n < 3) return Mat3::Identity();
  c /= static_cast<double>(n);
  c0 /= static_cast<double>(n);
  Mat3 H = Mat3::Zero();
  for (std::size_t i = 0; i < n_grains_; ++i)
    if (slip_offsets_[i + 1] > slip_offsets_[i]) H += (x0_[i] - c0) * (el.x[i] - c).transpose();
  const Eigen::JacobiSVD<Mat3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 D = Mat3::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixV() * D * svd.matrixU().transpose();
}

std::vector<double> CompressionJob::slip() const {
  const Elements& el = sys().elements();
  const Mat3 R = rigid_rotation();
  std::vector<double> s(el.size(), 0.0);
  for (std::size_t i = 0; i < n_grains_; ++i) {
    const std::uint32_t b = slip_offsets_[i], e = slip_offsets_[i + 1];
    if (b == e) continue;
    double sum = 0;
    for (std::uint32_t k = b; k < e; ++k) {
      const std::uint32_t j = slip_partners_[k];
      sum += ((el.x[j] - el.x[i]) - R * (x0_[j] - x0_[i])).norm();
    }
    s[i] = sum / static_cast<double>(e - b);
  }
  return s;
}

long CompressionJob::fragments() const {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  edges.reserve(bonds_->bonds().size());
  for (const GrainBondRecord& b : bonds_->bonds())
    if (!b.broken) edges.emplace_back(b.bond.i, b.bond.j);
  // Grains never bonded (rattlers) are isolated vertices, not fragments.
  long never_bonded = 0;
  for (std::size_t i = 0; i < n_grains_; ++i)
    never_bonded += slip_offsets_[i + 1] == slip_offsets_[i];
  return connected_components(n_grains_, edges) - never_bonded;
}

std::vector<std::string> CompressionJob::columns() const {
  std::vector<std::string> c = {"time_ps",      "displacement_nm", "force_nN",
                                "bonds_intact", "bonds_yielded",   "bonds_broken",
                                "fragments",    "slip_max_nm",     "slip_mean_nm"};
  for (std::string& e : energy_columns(energy_terms())) c.push_back(std::move(e));
  return c;
}

namespace {
struct SlipFigures {
  double max = 0, mean = 0;
};
SlipFigures slip_figures(const std::vector<double>& s, const std::vector<std::uint32_t>& offsets) {
  SlipFigures f;
  long n = 0;
  for (std::size_t i = 0; i + 1 < offsets.size(); ++i) {
    if (offsets[i] == offsets[i + 1]) continue;  // unbonded grains have no slip
    f.max = std::max(f.max, s[i]);
    f.mean += s[i];
    ++n;
  }
  if (n) f.mean /= static_cast<double>(n);
  return f;
}
}  // namespace

std::vector<double> CompressionJob::observe() {
  const SlipFigures sf = slip_figures(slip(), slip_offsets_);
  std::vector<double> v = {sys().time(),
                           displacement(),
                           platen_force_nN(),
                           static_cast<double>(bonds_->intact_count()),
                           static_cast<double>(bonds_->yielded_count()),
                           static_cast<double>(bonds_->broken_count()),
                           static_cast<double>(fragments()),
                           sf.max,
                           sf.mean};
  for (double e : energy_values(sys(), energy_terms())) v.push_back(e);
  return v;
}

void CompressionJob::decorate(Snapshot& s) const {
  s.scalars.emplace_back("slip_nm", slip());
  if (!bonds_) return;
  s.bonds.reserve(bonds_->bonds().size());
  for (const GrainBondRecord& b : bonds_->bonds())
    s.bonds.push_back({static_cast<std::int32_t>(b.bond.i), static_cast<std::int32_t>(b.bond.j),
                       b.broken    ? BondState::Broken
                       : b.yielded ? BondState::Yielded
                                   : BondState::Intact});
}

Summary CompressionJob::summary() {
  if (!built())  // stopped while packing: how far it got
    return {{"packing_steps", packing_stage_->steps_done()}, {"simulated_ps", 0.0}};
  // The peak includes the current state (the tracker lags one evaluation behind).
  const double force = platen_force_nN(), disp = displacement();
  double peak = tracker_->peak_force, peak_at = tracker_->peak_at;
  if (force > peak) {
    peak = force;
    peak_at = disp;
  }
  const SlipFigures sf = slip_figures(slip(), slip_offsets_);
  return {{"grains", static_cast<long>(n_grains_)},
          {"bonds", static_cast<long>(initial_bonds_)},
          {"rattlers", packed_.rattlers},
          {"porosity", packed_.porosity},
          {"porosity_error", packed_.porosity_error},
          {"packing_steps", packed_.steps},
          {"packing_unbalanced_ratio", packed_.unbalanced_ratio},
          {"packing_wall_shift_nm", packed_.wall_shift},
          {"peak_force_nN", peak},
          {"peak_force_displacement_nm", peak_at},
          {"loading_stiffness_nN_per_nm",
           tracker_->sum_hh > 0 ? tracker_->sum_fh / tracker_->sum_hh : 0.0},
          {"final_force_nN", force},
          {"final_displacement_nm", disp},
          {"residual_height_loss_nm", height0_ - height()},
          {"bonds_intact", static_cast<long>(bonds_->intact_count())},
          {"bonds_yielded", static_cast<long>(bonds_->yielded_count())},
          {"bonds_broken", static_cast<long>(bonds_->broken_count())},
          {"fragments", fragments()},
          {"slip_max_nm", sf.max},
          {"slip_mean_nm", sf.mean},
          {"energy_balance_error", sys().energy_balance_error()},
          {"dt_ps", sys().dt()},
          {"critical_dt_ps", sys().critical_dt()},
          {"simulated_ps", sys().time()}};
}

}  // namespace mdem
