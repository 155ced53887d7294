// Grain bonds (elastic, plastic, brittle) and the dashpots of the failure stage (grain_bond.h).
//
// Plastic slip is a permanent relative displacement of the two grains: it is kept as an offset of
// grain i's bond point in its body frame, so the bond's total formulation (parallel_bond.h) stays
// exact: with the offset p (body frame of i) the gap is g − R_i p, the energy the same function of
// the shifted gap, and the forces and moments its exact gradient. Return mapping moves the offset
// by the part of the normal and shear gap beyond the elastic limits; the axis n does not depend on
// the offset, so after the update the normal and shear forces sit exactly on the caps.
#include "mdem/force/bond/grain_bond.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "mdem/core/limits.h"
#include "mdem/io/state_io.h"
#include "mdem/neighbor/neighbor_list.h"

namespace mdem {

namespace {

constexpr double kPi = std::numbers::pi;
// A force within this fraction above its cap is on the cap: a re-evaluation of a state that was
// just mapped (rounding puts it an ulp above or below) neither flows nor releases energy.
constexpr double kCapTolerance = 1e-12;

double section_area(double rb) { return kPi * rb * rb; }
double section_inertia(double rb) { return 0.25 * kPi * rb * rb * rb * rb; }

// The bond with the plastic offset added to grain i's arm.
Bond effective_bond(const GrainBondRecord& rec) {
  Bond b = rec.bond;
  if (rec.yielded) b.ci += rec.plastic_normal * rec.bond.ni + rec.plastic_shear;
  return b;
}

BondStress stress_of(const GrainBondRecord& rec, const BondDeformation& d) {
  const BondStiffness& k = rec.bond.k;
  const double rb = rec.radius;
  const double A = section_area(rb), I = section_inertia(rb), J = 2.0 * I;
  BondStress s;
  s.sigma = k.kn_area * d.u_n / A + k.kn_inertia * d.theta_b.norm() * rb / I;
  s.tau = k.ks_area * d.u_s.norm() / A + k.ks_polar * std::abs(d.theta_t) * rb / J;
  return s;
}

// Normal stiffness of the linear contact of a broken pair: Eq. 36 over the neck's section.
double broken_contact_stiffness(const GrainBondRecord& rec, double youngs, double ri, double rj) {
  return grain_contact_stiffness(youngs, ri, rj, rec.radius);
}

// Return mapping of one plastic bond at the current state: moves the plastic offset so that
// |F_n| ≤ σ_y·A and |F_s| ≤ τ_y·A, updates the record and returns the plastic work cap × slip.
double return_map(GrainBondRecord& rec, double strength, const Vec3& xi, const Quat& qi,
                  const Vec3& xj, const Quat& qj) {
  const Bond b = effective_bond(rec);
  const BondDeformation d = bond_deformation(b, xi, qi, xj, qj);
  const BondStiffness& k = rec.bond.k;
  const double A = section_area(rec.radius);
  const double cap_n = strength * A, cap_s = 0.5 * strength * A;

  double dn = 0;
  const bool flow_n = std::abs(k.kn_area * d.u_n) > cap_n * (1.0 + kCapTolerance);
  if (flow_n) dn = d.u_n - std::copysign(cap_n / k.kn_area, d.u_n);
  Vec3 ds = Vec3::Zero();
  const double fs = k.ks_area * d.u_s.norm();
  const bool flow_s = fs > cap_s * (1.0 + kCapTolerance);
  if (flow_s) ds = d.u_s * (1.0 - cap_s / fs);
  if (!flow_n && !flow_s) return 0.0;

  // World slip increment, stored in grain i's body frame: the normal part as a scalar along the
  // body bond direction n_i, the rest (the shear slip and the normal slip's small off-axis part
  // when n differs from R_i n_i) in plastic_shear.
  const Vec3 body = qi.conjugate() * (dn * d.n + ds);
  rec.plastic_normal += dn;
  rec.plastic_shear += body - dn * rec.bond.ni;
  rec.yielded = true;
  return cap_n * std::abs(dn) + cap_s * ds.norm();
}

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

}  // namespace

GrainBond::GrainBond(GrainBondParams p) : p_(p) {
  const GrainMaterial& m = p.material;
  require(std::isfinite(m.youngs) && m.youngs > 0,
          "grain bond material youngs (E) must be finite and > 0 eV/nm³, got " +
              std::to_string(m.youngs));
  require(std::isfinite(m.poisson) && m.poisson >= 0 && m.poisson < 0.5,
          "grain bond material poisson (ν) must be in [0, 0.5), got " + std::to_string(m.poisson));
  const int kind = static_cast<int>(p.behaviour);
  require(kind >= 0 && kind <= 2,
          "grain bond behaviour must be elastic, plastic or brittle, got " + std::to_string(kind));
  if (p.behaviour == BondBehaviour::Elastic)
    require(
        std::isfinite(p.strength) && p.strength >= 0,
        "grain bond strength must be finite and >= 0 eV/nm³, got " + std::to_string(p.strength));
  else
    require(std::isfinite(p.strength) && p.strength > 0,
            std::string("grain bond strength (") +
                (p.behaviour == BondBehaviour::Plastic ? "yield σ_y" : "failure σ_f") +
                ") must be finite and > 0 eV/nm³ for " +
                (p.behaviour == BondBehaviour::Plastic ? "plastic" : "brittle") + " bonds, got " +
                std::to_string(p.strength));
}

std::size_t GrainBond::add(const Elements& el, std::uint32_t i, std::uint32_t j) {
  const std::size_t n = el.size();
  require(i < n && j < n, "grain bond element index out of range: i = " + std::to_string(i) +
                              ", j = " + std::to_string(j) + ", " + std::to_string(n) +
                              " elements");
  require(i != j, "grain bond element indices i and j must differ, both are " + std::to_string(i));
  require(!owns(i, j), "grain bond pair (i, j) = (" + std::to_string(i) + ", " + std::to_string(j) +
                           ") is already bonded");
  const double L = (el.x[j] - el.x[i]).norm();
  require(std::isfinite(L) && L > 0,
          "grain bond centres of elements " + std::to_string(i) + " and " + std::to_string(j) +
              " coincide (centre distance L = " + std::to_string(L) + " nm)");
  const double rb = std::min(el.radius[i], el.radius[j]);
  const double A = section_area(rb), I = section_inertia(rb), J = 2.0 * I;
  const double kn = p_.material.youngs / L, ks = p_.material.shear() / L;
  BondStiffness k;
  k.kn_area = kn * A;
  k.ks_area = ks * A;
  k.kn_inertia = kn * I;
  k.ks_polar = ks * J;

  GrainBondRecord rec;
  rec.bond = make_bond(el, i, j, k);
  rec.radius = rb;
  rec.length = L;
  bonds_.push_back(rec);
  const std::size_t need = std::max(i, j) + std::size_t{1};
  if (partners_.size() < need) partners_.resize(need);
  partners_[i].push_back(j);
  partners_[j].push_back(i);
  return bonds_.size() - 1;
}

void GrainBond::reorder(std::span<const std::uint32_t> old_to_new) {
  for (GrainBondRecord& r : bonds_) {
    r.bond.i = old_to_new[r.bond.i];
    r.bond.j = old_to_new[r.bond.j];
  }
  // Partner lists grow only as far as the largest bonded index: extend to every element first.
  partners_.resize(old_to_new.size());
  std::vector<std::vector<std::uint32_t>> moved(old_to_new.size());
  for (std::size_t i = 0; i < partners_.size(); ++i) {
    for (std::uint32_t& j : partners_[i]) j = old_to_new[j];
    moved[old_to_new[i]] = std::move(partners_[i]);
  }
  partners_ = std::move(moved);
}

bool GrainBond::owns(std::size_t i, std::size_t j) const {
  if (i >= partners_.size()) return false;
  const auto& p = partners_[i];
  return std::find(p.begin(), p.end(), static_cast<std::uint32_t>(j)) != p.end();
}

std::size_t GrainBond::intact_count() const {
  return static_cast<std::size_t>(
      std::count_if(bonds_.begin(), bonds_.end(), [](const auto& b) { return !b.broken; }));
}

std::size_t GrainBond::broken_count() const { return bonds_.size() - intact_count(); }

std::size_t GrainBond::yielded_count() const {
  return static_cast<std::size_t>(
      std::count_if(bonds_.begin(), bonds_.end(), [](const auto& b) { return b.yielded; }));
}

BondStress GrainBond::stress(const Elements& el, std::size_t k) const {
  const GrainBondRecord& rec = bonds_.at(k);
  if (rec.broken) return {};
  const Bond b = effective_bond(rec);
  return stress_of(rec, bond_deformation(b, el.x[b.i], el.q[b.i],
                                         domain().image(el.x[b.i], el.x[b.j]), el.q[b.j]));
}

void GrainBond::compute(const Elements& el, const NeighborList*, ForceSink& sink) const {
  if (bonds_.empty()) return;
  const int nt = sink.threads();
  if (nt < 1) throw std::logic_error("grain_bond: force sink has no thread buffers");
  const long nb = static_cast<long>(bonds_.size());
  const Vec3* x = el.x.data();
  const Domain& dom = domain();
  const Quat* q = el.q.data();
  const double* radius = el.radius.data();
  const BondBehaviour behaviour = p_.behaviour;
  const double strength = p_.strength;
  const double youngs = p_.material.youngs;
#pragma omp parallel num_threads(nt) if (nb >= kParallelMinItems)
  {
    const int tid = omp_get_thread_num();
    Vec3* f = sink.force(tid);
    Vec3* t = sink.torque(tid);
    BondTally tally;
    double e_contact = 0, released = 0;
#pragma omp for schedule(static)
    for (long k = 0; k < nb; ++k) {
      GrainBondRecord& rec = bonds_[k];  // this thread's alone
      const std::uint32_t i = rec.bond.i, j = rec.bond.j;
      const double ri = radius[i], rj = radius[j];
      const Vec3 xj = dom.image(x[i], x[j]);  // the image of j bonded to i
      // Post-break contact: pushes when the centres are closer than the bonding distance.
      auto contact = [&](double& energy) {
        const Vec3 d = xj - x[i];
        const double r = d.norm();
        const double u = rec.length - r;
        if (!(u > 0) || !(r > 0)) return;
        const double kc = broken_contact_stiffness(rec, youngs, ri, rj);
        const Vec3 fj = (kc * u / r) * d;
        f[j] += fj;
        f[i] -= fj;
        energy += 0.5 * kc * u * u;
      };
      if (rec.broken) {
        contact(e_contact);
        continue;
      }
      if (behaviour == BondBehaviour::Plastic)
        released += return_map(rec, strength, x[i], q[i], xj, q[j]);
      const Bond b = effective_bond(rec);
      const BondResult r = bond_eval(b, x[i], q[i], xj, q[j]);
      if (behaviour == BondBehaviour::Brittle) {
        const BondStress s = stress_of(rec, bond_deformation(b, x[i], q[i], xj, q[j]));
        if (s.sigma >= strength || s.tau >= 0.5 * strength) {
          // Breaks for good: its stored energy goes, the contact's (if any) replaces it.
          rec.broken = true;
          double e_after = 0;
          contact(e_after);
          e_contact += e_after;
          released += r.energy() - e_after;
          continue;
        }
      }
      tally.apply(r, i, j, f, t);
    }
    EnergyTally& e = sink.energy(tid);
    tally.add_to(e);
    e.add(EnergyTerm::Contact, e_contact);
    e.released += released;
  }
}

void GrainBond::add_stiffness(const Elements& el, const NeighborList*, StiffnessSums& s) const {
  const double youngs = p_.material.youngs;
  for (const GrainBondRecord& rec : bonds_) {
    const Bond& b = rec.bond;
    if (rec.broken) {
      // Central and frictionless: translational only.
      s.add_pair(b.i, b.j, broken_contact_stiffness(rec, youngs, el.radius[b.i], el.radius[b.j]),
                 0.0, 0.0);
      continue;
    }
    add_bond_stiffness(b, s);
  }
}

void GrainBond::save_state(StateWriter& w) const {
  const std::size_t n = bonds_.size();
  std::vector<std::uint32_t> pairs(2 * n);
  std::vector<double> normal(n);
  std::vector<Vec3> shear(n);
  std::vector<std::uint8_t> flags(n);
  for (std::size_t k = 0; k < n; ++k) {
    const GrainBondRecord& b = bonds_[k];
    pairs[2 * k] = b.bond.i;
    pairs[2 * k + 1] = b.bond.j;
    normal[k] = b.plastic_normal;
    shear[k] = b.plastic_shear;
    flags[k] = static_cast<std::uint8_t>((b.yielded ? 1 : 0) | (b.broken ? 2 : 0));
  }
  w.put(static_cast<std::uint64_t>(n));
  w.put(pairs);
  w.put(normal);
  w.put(shear);
  w.put(flags);
}

void GrainBond::load_state(StateReader& r) {
  const std::size_t n = bonds_.size();
  const auto saved = r.get<std::uint64_t>("bond count");
  if (saved != n)
    r.fail("bond count", "checkpoint holds " + std::to_string(saved) +
                             " grain bonds, this job has " + std::to_string(n));
  std::vector<std::uint32_t> pairs;
  std::vector<double> normal;
  std::vector<Vec3> shear;
  std::vector<std::uint8_t> flags;
  r.get(pairs, "bond pairs", 2 * n);
  for (std::size_t k = 0; k < n; ++k)
    if (pairs[2 * k] != bonds_[k].bond.i || pairs[2 * k + 1] != bonds_[k].bond.j)
      r.fail("bond pairs", "bond " + std::to_string(k) +
                               " joins other grains than this job's (the checkpoint is of another "
                               "scene)");
  r.get(normal, "plastic_normal", n);
  r.get(shear, "plastic_shear", n);
  r.get(flags, "flags", n);
  for (std::size_t k = 0; k < n; ++k) {
    if (!std::isfinite(normal[k]) || !shear[k].allFinite())
      r.fail("plastic slip", "bond " + std::to_string(k) + " has a non-finite plastic slip");
    if (flags[k] > 3)
      r.fail("flags", "bond " + std::to_string(k) + " has unknown flags " +
                          std::to_string(static_cast<int>(flags[k])));
  }
  for (std::size_t k = 0; k < n; ++k) {
    GrainBondRecord& b = bonds_[k];
    b.plastic_normal = normal[k];
    b.plastic_shear = shear[k];
    b.yielded = (flags[k] & 1) != 0;
    b.broken = (flags[k] & 2) != 0;
  }
}

// ---------------------------------------------------------------------------------------------
// GrainDashpots

GrainDashpots::GrainDashpots(double ratio, const GrainBond* bonds, double contact_youngs,
                             double max_radius)
    : contacts_(ratio, bonds, contact_youngs, max_radius),
      ratio_(ratio),
      bonds_(bonds),
      contact_youngs_(contact_youngs),
      max_radius_(max_radius) {
  require(std::isfinite(ratio) && ratio >= 0 && ratio <= limits::kMaxDashpotRatio,
          "grain dashpots ratio (β) must be finite and in [0, " +
              std::to_string(static_cast<int>(limits::kMaxDashpotRatio)) +
              "] (critical damping), got " + std::to_string(ratio));
  require(std::isfinite(contact_youngs) && contact_youngs > 0,
          "grain dashpots contact_youngs must be finite and > 0 eV/nm³, got " +
              std::to_string(contact_youngs));
  require(std::isfinite(max_radius) && max_radius > 0,
          "grain dashpots max_radius must be finite and > 0 nm, got " + std::to_string(max_radius));
}

bool grain_contact_excluded(const Elements& el, std::size_t i, std::size_t j,
                            const GrainBond* bonds) {
  if (el.kind[i] != ElementKind::Grain || el.kind[j] != ElementKind::Grain) return true;
  return bonds && bonds->owns(i, j);
}

bool GrainContactDashpotKernel::excludes(const Elements& el, std::size_t i, std::size_t j) const {
  return grain_contact_excluded(el, i, j, bonds_);
}

bool GrainContactDashpotKernel::pair(const Elements& el, std::size_t i, std::size_t j,
                                     const Vec3& d, PairForces& out) const {
  const double reach = el.radius[i] + el.radius[j];
  const double r2 = d.squaredNorm();
  if (r2 >= reach * reach || r2 == 0) return false;
  const Vec3 nrm = d / std::sqrt(r2);
  const double k = grain_contact_stiffness(contact_youngs_, el.radius[i], el.radius[j]);
  out.f2 =
      (-dashpot_coefficient(ratio_, el.mass[i], el.mass[j], k) * nrm.dot(el.v[j] - el.v[i])) * nrm;
  out.f1 = -out.f2;
  return true;
}

void GrainContactDashpotKernel::stiffness(const Elements& el, std::size_t i, std::size_t j,
                                          const Vec3& d, StiffnessSums& s) const {
  if (d.squaredNorm() >= cutoff() * cutoff()) return;
  const double c =
      dashpot_coefficient(ratio_, el.mass[i], el.mass[j],
                          grain_contact_stiffness(contact_youngs_, el.radius[i], el.radius[j]));
  s.c[i] += c;
  s.c[j] += c;
}

template class PairModel<GrainContactDashpotKernel>;

void GrainDashpots::compute(const Elements& el, const NeighborList* pairs, ForceSink& sink) const {
  if (ratio_ == 0 || el.size() == 0) return;
  if (!sink.has_damping())
    throw std::logic_error("grain_dashpots: force sink has no damping buffers");
  const long n = static_cast<long>(el.size());
  platens_.update(el);
  const std::size_t nw = platens_.size();
  static const std::vector<GrainBondRecord> kNone;
  const std::vector<GrainBondRecord>& recs = bonds_ ? bonds_->bonds() : kNone;
  const double bond_youngs = bonds_ ? bonds_->params().material.youngs : 0.0;
  const long nb = static_cast<long>(recs.size());
  const double beta2 = 2.0 * ratio_;
  const bool threaded = std::max(n, nb) >= kParallelMinItems;
  const Vec3* x = el.x.data();
  const Domain& dom = domain();
  const Vec3* v = el.v.data();
  const double* mass = el.mass.data();
  const double* radius = el.radius.data();

#pragma omp parallel num_threads(sink.threads()) if (threaded)
  {
    const int tid = omp_get_thread_num();
    Vec3* fd = sink.damping_force(tid);
    // −c·(n·v_rel)·n on j, the opposite on i.
    auto dashpot = [&](std::size_t i, std::size_t j, const Vec3& nrm, double k) {
      const double c = dashpot_coefficient(ratio_, mass[i], mass[j], k);
      const Vec3 fj = (-c * nrm.dot(v[j] - v[i])) * nrm;
      fd[j] += fj;
      fd[i] -= fj;
    };

    // Intact bonds, and broken pairs in compression.
#pragma omp for schedule(static)
    for (long k = 0; k < nb; ++k) {
      const GrainBondRecord& rec = recs[k];
      const std::size_t i = rec.bond.i, j = rec.bond.j;
      const Vec3 d = dom.delta(x[i], x[j]);
      const double r = d.norm();
      if (!(r > 0)) continue;
      double kn;
      if (!rec.broken) {
        kn = rec.bond.k.kn_area;
      } else {
        if (r >= rec.length) continue;
        kn = broken_contact_stiffness(rec, bond_youngs, radius[i], radius[j]);
      }
      dashpot(i, j, d / r, kn);
    }

    // Grains against platens: the grain's mass, the rigid-platen stiffness π·R·E.
    if (nw > 0) {
#pragma omp for schedule(static)
      for (long i = 0; i < n; ++i) {
        if (el.kind[i] != ElementKind::Grain) continue;
        const double R = radius[i];
        for (std::size_t w = 0; w < nw; ++w) {
          const Vec3& nrm = platens_.normal(w);
          if (R - platens_.height(w, x[i]) <= 0) continue;
          const std::size_t p = platens_.index(w);
          const double c = beta2 * std::sqrt(mass[i] * wall_contact_stiffness(contact_youngs_, R));
          const Vec3 fi = (-c * nrm.dot(v[i] - v[p])) * nrm;
          fd[i] += fi;
          fd[p] -= fi;
        }
      }
    }
  }

  // Unbonded grain pairs in contact: the linear contact's pairs.
  if (pairs && pairs->offsets().size() == el.size() + 1)
    drive_pairs(contacts_, el, *pairs, sink, !list_is_for(*pairs, *this));
}

void GrainDashpots::add_stiffness(const Elements& el, const NeighborList* pairs,
                                  StiffnessSums& s) const {
  if (ratio_ == 0) return;
  const double beta2 = 2.0 * ratio_;
  auto pair_c = [&](std::size_t i, std::size_t j, double k) {
    const double c = dashpot_coefficient(ratio_, el.mass[i], el.mass[j], k);
    s.c[i] += c;
    s.c[j] += c;
  };
  if (bonds_) {
    const double youngs = bonds_->params().material.youngs;
    // Every bond: intact, or broken and possibly pressed back into contact.
    for (const GrainBondRecord& rec : bonds_->bonds()) {
      const std::size_t i = rec.bond.i, j = rec.bond.j;
      pair_c(i, j,
             rec.broken ? broken_contact_stiffness(rec, youngs, el.radius[i], el.radius[j])
                        : rec.bond.k.kn_area);
    }
  }
  if (pairs) drive_stiffness(contacts_, el, *pairs, s, !list_is_for(*pairs, *this));
  // The platen moves as prescribed, so only the grain's row sees the dashpot.
  platens_.update(el);
  platens_.for_each_grain_near(el, [&](std::size_t i) {
    s.c[i] += beta2 * std::sqrt(el.mass[i] * wall_contact_stiffness(contact_youngs_, el.radius[i]));
  });
}

}  // namespace mdem
