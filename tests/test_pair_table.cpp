// The per-kind-pair table with a stand-in nanoparticle contact (an isotropic Lennard-Jones-like
// kernel defined here, Nanoparticle–CntSegment, 8 nm cutoff) registered next to the CNT vdW
// contact and its dashpot: the dashpot acts on exactly the vdW's pairs (never on NP–CNT pairs),
// the 8 nm model does not enlarge the CNT–CNT sub-list, and the forces are the sum of the models'
// pair forces computed directly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "mdem/core/cnt.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/force/pair_driver.h"
#include "mdem/integrate/system.h"
#include "mdem/scene/tube_builder.h"

using namespace mdem;

namespace {

// U(r) = 4ε((σ/r)^12 − (σ/r)^6), shifted in value and slope so that U and U' vanish at the cutoff.
class NpCntStandIn {
 public:
  static constexpr bool kDissipative = false;
  static constexpr bool kTorques = false;
  static constexpr EnergyTerm kTerm = EnergyTerm::NpCnt;
  static constexpr double kCutoff = 8.0, kSigma = 3.0, kEps = 0.5;

  std::string_view name() const { return "np_cnt_standin"; }
  double cutoff() const { return kCutoff; }
  KindPairs kinds() const {
    return KindPairs::of(ElementKind::Nanoparticle, ElementKind::CntSegment);
  }
  bool excludes(const Elements& el, std::size_t i, std::size_t j) const {
    return !kinds().has(el.kind[i], el.kind[j]);
  }
  static void lj(double r, double& u, double& du) {
    const double s6 = std::pow(kSigma / r, 6);
    u = 4 * kEps * (s6 * s6 - s6);
    du = 4 * kEps * (-12 * s6 * s6 + 6 * s6) / r;
  }
  static double energy(double r) {
    double u, du, uc, duc;
    lj(r, u, du);
    lj(kCutoff, uc, duc);
    return u - uc - (r - kCutoff) * duc;
  }
  bool pair(const Elements&, std::size_t, std::size_t, const Vec3& d, PairForces& out) const {
    const double r = d.norm();
    if (!(r < kCutoff)) return false;
    double u, du, uc, duc;
    lj(r, u, du);
    lj(kCutoff, uc, duc);
    out.energy = u - uc - (r - kCutoff) * duc;
    out.f2 = -(du - duc) / r * d;  // on j
    out.f1 = -out.f2;
    return true;
  }
  void stiffness(const Elements&, std::size_t i, std::size_t j, const Vec3& d,
                 StiffnessSums& s) const {
    if (d.norm() < kCutoff) s.add_pair(i, j, 72 * kEps / (kSigma * kSigma), 0, 0);
  }
};

using NpCntModel = PairModel<NpCntStandIn>;

constexpr double kSkin = 0.5;

// Three tubes (two bundled along x, one crossing them along y) and four nanoparticles 4–5 nm from
// the tubes, everything moving.
Elements scene() {
  Elements el;
  add_straight_tube(el, Vec3(0, 0, 0), Vec3::UnitX(), 20, 0);
  add_straight_tube(el, Vec3(0, 1.75, 0), Vec3::UnitX(), 20, 1);
  add_straight_tube(el, Vec3(14, -8, 1.7), Vec3::UnitY(), 20, 2);
  for (const Vec3& x : {Vec3(5, -4, 0), Vec3(10, 5.8, 0), Vec3(20, 0.9, 4.2), Vec3(14, 8, -3.5)}) {
    ElementInit e;
    e.kind = ElementKind::Nanoparticle;
    e.x = x;
    e.mass = 50;
    e.inertia = Vec3::Constant(0.4 * 50 * 2.5 * 2.5);
    e.radius = 2.5;
    el.add(e);
  }
  std::mt19937_64 g(11);
  std::normal_distribution<double> vel(0.0, 0.5);
  for (std::size_t i = 0; i < el.size(); ++i) {
    el.v[i] = Vec3(vel(g), vel(g), vel(g));
    el.w[i] = Vec3(vel(g), vel(g), vel(g));
  }
  return el;
}

System make(bool with_np, ContactDampingParams damping = {}) {
  IntegratorSettings s;
  s.dt = 0.002;
  s.skin = kSkin;
  System sys(scene(), s);
  sys.add(std::make_unique<AnisotropicVdw>());
  if (with_np) sys.add(std::make_unique<NpCntModel>());
  sys.add(std::make_unique<ViscousContactDamping>(damping));
  sys.initialize();
  return sys;
}

bool is(const Elements& el, std::size_t i, ElementKind k) { return el.kind[i] == k; }

// Brute-force count of the pairs of kinds (a, b) closer than `range`, not excluded by `excl`.
template <class Excl>
std::size_t count_pairs(const Elements& el, ElementKind a, ElementKind b, double range, Excl excl) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < el.size(); ++i)
    for (std::size_t j = i + 1; j < el.size(); ++j) {
      const bool kinds = (is(el, i, a) && is(el, j, b)) || (is(el, i, b) && is(el, j, a));
      if (kinds && !excl(i, j) && (el.x[j] - el.x[i]).norm() < range) ++n;
    }
  return n;
}

}  // namespace

TEST(PairTable, NamesTheKernelsAndCutoffOfEachKindPair) {
  const System sys = make(true);
  const PairTable& t = sys.pair_table();
  ASSERT_EQ(t.entries().size(), 2u);  // vdW (+ its dashpot), and the NP contact

  const auto cc = t.lookup(ElementKind::CntSegment, ElementKind::CntSegment);
  ASSERT_EQ(cc.size(), 1u);
  EXPECT_EQ(cc[0]->cutoff, VdwParams{}.cutoff());
  ASSERT_EQ(cc[0]->members.size(), 2u);
  EXPECT_EQ(cc[0]->members[0]->name(), "anisotropic_vdw");
  EXPECT_EQ(cc[0]->members[1]->name(), "viscous_contact_damping");

  const auto nc = t.lookup(ElementKind::CntSegment, ElementKind::Nanoparticle);
  ASSERT_EQ(nc.size(), 1u);
  EXPECT_EQ(nc[0]->cutoff, 8.0);
  ASSERT_EQ(nc[0]->members.size(), 1u);
  EXPECT_EQ(nc[0]->members[0]->name(), "np_cnt_standin");

  EXPECT_TRUE(t.lookup(ElementKind::Nanoparticle, ElementKind::Nanoparticle).empty());
  EXPECT_TRUE(t.lookup(ElementKind::Grain, ElementKind::CntSegment).empty());
  // The dashpot shares the vdW's sub-list; the NP contact has its own.
  EXPECT_EQ(sys.neighbors(*sys.models()[2]), sys.neighbors(*sys.models()[0]));
  EXPECT_NE(sys.neighbors(*sys.models()[1]), sys.neighbors(*sys.models()[0]));
  const std::string d = t.describe();
  EXPECT_NE(d.find("CntSegment-CntSegment: anisotropic_vdw + viscous_contact_damping"),
            std::string::npos)
      << d;
  EXPECT_NE(d.find("CntSegment-Nanoparticle: np_cnt_standin, cutoff 8 nm"), std::string::npos) << d;
}

// (b) Each sub-list holds its own kind pairs within its own cutoff + skin, so the 8 nm model
// leaves the CNT–CNT list as it is without it.
TEST(PairTable, TheLongReachModelDoesNotEnlargeTheCntList) {
  const System with = make(true), without = make(false);
  const Elements& el = with.elements();
  const double rc = VdwParams{}.cutoff();
  auto vdw_excl = [&](std::size_t i, std::size_t j) { return el.cnt_pair_excluded(i, j, 20); };
  auto none = [](std::size_t, std::size_t) { return false; };
  const std::size_t cc =
      count_pairs(el, ElementKind::CntSegment, ElementKind::CntSegment, rc + kSkin, vdw_excl);
  const std::size_t nc =
      count_pairs(el, ElementKind::Nanoparticle, ElementKind::CntSegment, 8.0 + kSkin, none);
  ASSERT_GT(cc, 50u);
  ASSERT_GT(nc, 10u);
  const NeighborList* vdw_list = with.neighbors(*with.models()[0]);
  const NeighborList* np_list = with.neighbors(*with.models()[1]);
  EXPECT_EQ(vdw_list->pair_count(), cc);
  EXPECT_EQ(without.neighbors(*without.models()[0])->pair_count(), cc);
  EXPECT_EQ(np_list->pair_count(), nc);
  // One list at the longest reach (the old design) would have listed many more CNT–CNT pairs.
  const std::size_t cc_at_8 =
      count_pairs(el, ElementKind::CntSegment, ElementKind::CntSegment, 8.0 + kSkin, vdw_excl);
  EXPECT_GT(cc_at_8, cc + cc / 4);
  std::printf("CNT-CNT sub-list %zu pairs (%zu if listed at 8 nm), NP-CNT sub-list %zu pairs\n", cc,
              cc_at_8, nc);
}

// (a) The CNT dashpot acts on exactly the vdW's CNT–CNT pairs: no damping force on a
// nanoparticle, although NPs move against tubes within the dashpot's reach; and (c) every force
// is the sum of the models' pair forces computed directly over all pairs.
TEST(PairTable, ForcesAreTheSumOfTheModelsPairForces) {
  const System sys = make(true);
  const Elements& el = sys.elements();
  const std::size_t n = el.size();
  const VdwParams vp;
  const ContactDampingKernel dashpot{ContactDampingParams{}};
  const NpCntStandIn np;
  std::vector<Vec3> f(n, Vec3::Zero()), t(n, Vec3::Zero()), fd(n, Vec3::Zero());
  double e_vdw = 0, e_np = 0;
  int np_near_tube = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) {
      const Vec3 d = el.x[j] - el.x[i];
      const bool cnt_pair = !el.cnt_pair_excluded(i, j, vp.intra_tube_exclusion);
      if (cnt_pair) {
        const VdwPairResult r = vdw_pair(vp, el.x[i], el.axis(i), el.x[j], el.axis(j));
        e_vdw += r.energy;
        f[i] += r.f1;
        f[j] += r.f2;
        t[i] += r.t1;
        t[j] += r.t2;
        PairForces c;
        if (dashpot.pair(el, i, j, d, c)) {
          fd[i] += c.f1;
          fd[j] += c.f2;
        }
      } else if (!np.excludes(el, i, j)) {
        PairForces c;
        if (np.pair(el, i, j, d, c)) {
          e_np += c.energy;
          f[i] += c.f1;
          f[j] += c.f2;
        }
        if (d.norm() < ContactDampingParams{}.cutoff) ++np_near_tube;
      }
    }
  ASSERT_GT(np_near_tube, 5);  // pairs the dashpot would damp if it did not filter kinds
  const auto& E = sys.energy().potential.stored;
  EXPECT_NEAR(E[static_cast<int>(EnergyTerm::Vdw)], e_vdw, 1e-10 * std::abs(e_vdw));
  EXPECT_NEAR(E[static_cast<int>(EnergyTerm::NpCnt)], e_np, 1e-10 * std::abs(e_np));
  ASSERT_LT(e_np, -0.1);
  double fs = 0;
  for (std::size_t i = 0; i < n; ++i) fs = std::max(fs, f[i].norm());
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_LT((el.f[i] - f[i]).norm(), 1e-10 * fs) << "element " << i;
    EXPECT_LT((el.t[i] - t[i]).norm(), 1e-10 * fs) << "element " << i;
    EXPECT_LT((sys.damping_forces()[i] - fd[i]).norm(), 1e-12 * (1 + fd[i].norm()))
        << "element " << i;
    if (el.kind[i] == ElementKind::Nanoparticle) {
      EXPECT_EQ(sys.damping_forces()[i].norm(), 0.0) << "CNT dashpot on nanoparticle " << i;
      EXPECT_GT(el.f[i].norm(), 0.0);  // while the NP contact does act on it
    }
  }
}

TEST(PairTable, ADashpotReachingBeyondItsContactIsRefused) {
  ContactDampingParams d;
  d.cutoff = 6.0;  // the vdW contact ends at 5.424 nm
  try {
    make(false, d);
    FAIL() << "accepted a dashpot longer than its contact";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("viscous_contact_damping"), std::string::npos) << m;
    EXPECT_NE(m.find("anisotropic_vdw"), std::string::npos) << m;
  }
}

TEST(PairTable, ADashpotWithoutItsContactListsItsOwnPairs) {
  IntegratorSettings s;
  s.dt = 0.002;
  System sys(scene(), s);
  sys.add(std::make_unique<ViscousContactDamping>(ContactDampingParams{}));
  sys.initialize();
  ASSERT_EQ(sys.pair_table().entries().size(), 1u);
  const Elements& el = sys.elements();
  EXPECT_EQ(sys.neighbors()->pair_count(),
            count_pairs(el, ElementKind::CntSegment, ElementKind::CntSegment,
                        ContactDampingParams{}.cutoff + s.skin, [&](std::size_t i, std::size_t j) {
                          return el.cnt_pair_excluded(i, j, 20);
                        }));
  for (std::size_t i = 0; i < el.size(); ++i)
    if (el.kind[i] == ElementKind::Nanoparticle) {
      EXPECT_EQ(sys.damping_forces()[i].norm(), 0.0);
    }
}

// A dashpot added before its contact still shares the contact's list (one entry, one build per
// update), as one added after it does.
TEST(PairTable, ADashpotAddedBeforeItsContactSharesItsList) {
  for (const bool dashpot_first : {true, false}) {
    System sys(scene(), IntegratorSettings{});
    if (dashpot_first) sys.add(std::make_unique<ViscousContactDamping>(ContactDampingParams{}));
    const auto* vdw = sys.add(std::make_unique<AnisotropicVdw>());
    if (!dashpot_first) sys.add(std::make_unique<ViscousContactDamping>(ContactDampingParams{}));
    sys.initialize();
    const auto* dashpot = sys.find<ViscousContactDamping>();
    EXPECT_EQ(sys.pair_table().entries().size(), 1u) << "dashpot first: " << dashpot_first;
    EXPECT_EQ(sys.neighbors(*dashpot), sys.neighbors(*vdw)) << "dashpot first: " << dashpot_first;
  }
}
