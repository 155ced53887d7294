// Conformance of every registered pair kernel (pair_driver.h), one typed suite over all of them.
// Conservative kernels: forces and torques are the gradient of the energy (central finite
// differences; torques by small rotations), Newton's third law, no net angular momentum change
// (Σ x×f + t = 0 about the origin), objectivity under a rigid rotation, the energy continuous
// where the interaction ends. Dampers: they never put energy in, and conserve linear and angular
// momentum. Every kernel: it excludes every kind pair it does not declare.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "mdem/core/cnt.h"
#include "mdem/force/bond/grain_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/contact/linear_contact.h"
#include "mdem/force/contact/np_cnt_contact.h"
#include "mdem/force/contact/np_np_contact.h"
#include "mdem/force/damping/np_contact_damping.h"
#include "mdem/force/damping/viscous_contact_damping.h"
#include "mdem/scene/grain.h"
#include "mdem/scene/nanoparticle.h"
#include "mdem/scene/tube_builder.h"

using namespace mdem;

namespace {

Vec3 random_unit(std::mt19937_64& g) {
  std::normal_distribution<double> n;
  return Vec3(n(g), n(g), n(g)).normalized();
}

Quat random_rotation(std::mt19937_64& g) {
  std::normal_distribution<double> n;
  return Quat(n(g), n(g), n(g), n(g)).normalized();
}

// Evaluates kernel k on the pair (0, 1) of el, as the driver does (per-step caches first).
template <class K>
PairForces evaluate(const K& k, const Elements& el) {
  if constexpr (requires { k.begin(el); }) k.begin(el);
  if constexpr (requires { k.prepare(el, 0L); })
    for (long i = 0; i < static_cast<long>(el.size()); ++i) k.prepare(el, i);
  PairForces r;
  if (!k.pair(el, 0, 1, el.x[1] - el.x[0], r)) r = PairForces{};
  return r;
}

// Per kernel: how to make it, and a random pair configuration where it acts.
template <class K>
struct Traits;

template <>
struct Traits<VdwKernel> {
  static VdwKernel make() { return VdwKernel(VdwParams{}); }
  static Elements pair(std::mt19937_64& g) {
    std::uniform_real_distribution<double> r(1.3, 5.3);
    Elements el;
    el.add(cnt_segment(Vec3(0.3, -0.2, 0.1), quat_from_axis(random_unit(g)), 0, 0));
    el.add(cnt_segment(Vec3(0.3, -0.2, 0.1) + r(g) * random_unit(g), quat_from_axis(random_unit(g)),
                       1, 0));
    return el;
  }
  // Where the interaction ends along the centre line.
  static double reach(const VdwKernel& k, const Elements&) { return k.cutoff(); }
};

GrainMaterial material() { return gold(); }

Elements grain_pair(std::mt19937_64& g, double gap_lo, double gap_hi) {
  std::uniform_real_distribution<double> rad(1.0, 2.5), gap(gap_lo, gap_hi), vel(-0.5, 0.5);
  const double r1 = rad(g), r2 = rad(g);
  Elements el;
  el.add(grain_element(Vec3(1.0, 2.0, -0.5), r1, material()));
  el.add(grain_element(Vec3(1.0, 2.0, -0.5) + (r1 + r2) * gap(g) * random_unit(g), r2, material()));
  el.q[0] = random_rotation(g);
  el.q[1] = random_rotation(g);
  for (std::size_t i = 0; i < 2; ++i) {
    el.v[i] = Vec3(vel(g), vel(g), vel(g));
    el.w[i] = Vec3(vel(g), vel(g), vel(g));
  }
  return el;
}

template <>
struct Traits<LinearContactKernel> {
  static LinearContactKernel make() { return LinearContactKernel(material().youngs, 2.5); }
  static Elements pair(std::mt19937_64& g) { return grain_pair(g, 0.7, 0.99); }
  static double reach(const LinearContactKernel&, const Elements& el) {
    return el.radius[0] + el.radius[1];
  }
};

template <>
struct Traits<ContactDampingKernel> {
  static ContactDampingKernel make() { return ContactDampingKernel(ContactDampingParams{}); }
  static Elements pair(std::mt19937_64& g) {
    Elements el = Traits<VdwKernel>::pair(g);
    std::normal_distribution<double> vel(0.0, 0.5);
    for (std::size_t i = 0; i < 2; ++i) {
      el.v[i] = Vec3(vel(g), vel(g), vel(g));
      el.w[i] = Vec3(vel(g), vel(g), vel(g));
    }
    return el;
  }
};

template <>
struct Traits<GrainContactDashpotKernel> {
  static GrainContactDashpotKernel make() {
    return GrainContactDashpotKernel(0.5, nullptr, material().youngs, 2.5);
  }
  static Elements pair(std::mt19937_64& g) { return grain_pair(g, 0.7, 0.99); }
};

// A nanoparticle and a CNT segment 1.5–5.3 nm apart (the linear branch, the well and the f_c
// ramp), in either order, both moving.
Elements np_segment_pair(std::mt19937_64& g) {
  std::uniform_real_distribution<double> r(1.5, 5.3);
  std::normal_distribution<double> vel(0.0, 0.5);
  const Vec3 xs(0.3, -0.2, 0.1), xn = xs + r(g) * random_unit(g);
  const ElementInit seg = cnt_segment(xs, quat_from_axis(random_unit(g)), 0, 0);
  ElementInit np = nanoparticle(xn);
  np.q = random_rotation(g);
  Elements el;
  const bool np_first = std::uniform_int_distribution<int>(0, 1)(g) == 1;
  el.add(np_first ? np : seg);
  el.add(np_first ? seg : np);
  for (std::size_t i = 0; i < 2; ++i) {
    el.v[i] = Vec3(vel(g), vel(g), vel(g));
    el.w[i] = Vec3(vel(g), vel(g), vel(g));
  }
  return el;
}

template <>
struct Traits<NpCntKernel> {
  static NpCntKernel make() { return NpCntKernel(NpCntParams{}); }
  static Elements pair(std::mt19937_64& g) { return np_segment_pair(g); }
  static double reach(const NpCntKernel& k, const Elements&) { return k.cutoff(); }
};

template <>
struct Traits<NpNpKernel> {
  static NpNpKernel make() { return NpNpKernel(NpNpParams{}); }
  // 4.5–7.9 nm apart: the linear branch (below 5.25), the well and the f_c ramp (7–8).
  static Elements pair(std::mt19937_64& g) {
    std::uniform_real_distribution<double> r(4.5, 7.9);
    Elements el;
    el.add(nanoparticle(Vec3(-1.0, 0.5, 2.0)));
    el.add(nanoparticle(Vec3(-1.0, 0.5, 2.0) + r(g) * random_unit(g)));
    el.q[0] = random_rotation(g);
    el.q[1] = random_rotation(g);
    return el;
  }
  static double reach(const NpNpKernel& k, const Elements&) { return k.cutoff(); }
};

template <>
struct Traits<NpDashpotKernel> {
  static NpDashpotKernel make() { return np_cnt_dashpot(0.03); }
  static Elements pair(std::mt19937_64& g) { return np_segment_pair(g); }
};

// Every pair kernel; the conservative ones; the dampers.
template <class K>
class AnyPairKernel : public ::testing::Test {};
template <class K>
class ConservativeKernel : public ::testing::Test {};
template <class K>
class DampingKernel : public ::testing::Test {};

using AllKernels =
    ::testing::Types<VdwKernel, LinearContactKernel, ContactDampingKernel,
                     GrainContactDashpotKernel, NpCntKernel, NpNpKernel, NpDashpotKernel>;
using ConservativeKernels =
    ::testing::Types<VdwKernel, LinearContactKernel, NpCntKernel, NpNpKernel>;
using DampingKernels =
    ::testing::Types<ContactDampingKernel, GrainContactDashpotKernel, NpDashpotKernel>;
TYPED_TEST_SUITE(AnyPairKernel, AllKernels);
TYPED_TEST_SUITE(ConservativeKernel, ConservativeKernels);
TYPED_TEST_SUITE(DampingKernel, DampingKernels);

constexpr int kSamples = 60;

// Rotates the whole configuration rigidly about the origin.
Elements rotated(const Elements& el, const Quat& R) {
  Elements out = el;
  for (std::size_t i = 0; i < el.size(); ++i) {
    out.x[i] = R * el.x[i];
    out.q[i] = (R * el.q[i]).normalized();
    out.v[i] = R * el.v[i];
    out.w[i] = R * el.w[i];
  }
  return out;
}

}  // namespace

TYPED_TEST(AnyPairKernel, ExcludesEveryUndeclaredKindPair) {
  using K = TypeParam;
  const K k = Traits<K>::make();
  std::mt19937_64 g(1);
  Elements el = Traits<K>::pair(g);
  int declared = 0;
  for (int a = 0; a < kElementKinds; ++a)
    for (int b = 0; b < kElementKinds; ++b) {
      el.kind[0] = static_cast<ElementKind>(a);
      el.kind[1] = static_cast<ElementKind>(b);
      if (k.kinds().has(el.kind[0], el.kind[1])) {
        ++declared;
        continue;
      }
      EXPECT_TRUE(k.excludes(el, 0, 1)) << k.name() << " acts on kinds " << a << "-" << b;
    }
  EXPECT_GT(declared, 0);
  EXPECT_GT(k.cutoff(), 0.0);
}

TYPED_TEST(ConservativeKernel, ForcesAndTorquesAreTheEnergyGradient) {
  using K = TypeParam;
  {
    const K k = Traits<K>::make();
    std::mt19937_64 g(2);
    const double h = 1e-6;
    int interacting = 0;
    for (int s = 0; s < kSamples; ++s) {
      const Elements el = Traits<K>::pair(g);
      const PairForces r = evaluate(k, el);
      if (r.energy == 0) continue;
      ++interacting;
      const double scale = std::max({r.f1.norm(), r.t1.norm(), r.t2.norm(), 1e-3});
      for (std::size_t i = 0; i < 2; ++i)
        for (int a = 0; a < 3; ++a) {
          Elements p = el, m = el;
          p.x[i][a] += h;
          m.x[i][a] -= h;
          const double fd = -(evaluate(k, p).energy - evaluate(k, m).energy) / (2 * h);
          const double f = (i == 0 ? r.f1 : r.f2)[a];
          EXPECT_NEAR(f, fd, 2e-5 * scale) << k.name() << " force on " << i << " axis " << a;
          // A small rotation δφ about world axis a: q → exp(δφ e_a) q.
          Vec3 e = Vec3::Zero();
          e[a] = h;
          p = el;
          m = el;
          p.q[i] = (quat_exp(e) * el.q[i]).normalized();
          m.q[i] = (quat_exp(-e) * el.q[i]).normalized();
          const double td = -(evaluate(k, p).energy - evaluate(k, m).energy) / (2 * h);
          const double t = (i == 0 ? r.t1 : r.t2)[a];
          EXPECT_NEAR(t, td, 2e-5 * scale) << k.name() << " torque on " << i << " axis " << a;
        }
    }
    EXPECT_GT(interacting, kSamples / 2);
  }
}

TYPED_TEST(AnyPairKernel, ConservesMomentumAndAngularMomentum) {
  using K = TypeParam;
  const K k = Traits<K>::make();
  std::mt19937_64 g(3);
  int interacting = 0;
  for (int s = 0; s < kSamples; ++s) {
    const Elements el = Traits<K>::pair(g);
    const PairForces r = evaluate(k, el);
    if (r.f1.norm() == 0 && r.t1.norm() == 0) continue;
    ++interacting;
    const double scale = std::max({r.f1.norm(), r.t1.norm(), r.t2.norm()});
    EXPECT_LT((r.f1 + r.f2).norm(), 1e-12 * scale) << k.name();
    const Vec3 L = el.x[0].cross(r.f1) + el.x[1].cross(r.f2) + r.t1 + r.t2;
    const double arm = std::max(el.x[0].norm(), el.x[1].norm()) + 1.0;
    EXPECT_LT(L.norm(), 1e-12 * scale * arm) << k.name();
  }
  EXPECT_GT(interacting, kSamples / 2);
}

TYPED_TEST(AnyPairKernel, ObjectiveUnderARigidRotation) {
  using K = TypeParam;
  const K k = Traits<K>::make();
  std::mt19937_64 g(4);
  for (int s = 0; s < kSamples; ++s) {
    const Elements el = Traits<K>::pair(g);
    const Quat R = random_rotation(g);
    const PairForces a = evaluate(k, el), b = evaluate(k, rotated(el, R));
    const double scale = std::max({a.f1.norm(), a.t1.norm(), a.t2.norm(), 1e-12});
    EXPECT_NEAR(b.energy, a.energy, 1e-11 * std::max(std::abs(a.energy), 1e-12)) << k.name();
    EXPECT_LT((b.f1 - R * a.f1).norm(), 1e-10 * scale) << k.name();
    EXPECT_LT((b.f2 - R * a.f2).norm(), 1e-10 * scale) << k.name();
    EXPECT_LT((b.t1 - R * a.t1).norm(), 1e-10 * scale) << k.name();
    EXPECT_LT((b.t2 - R * a.t2).norm(), 1e-10 * scale) << k.name();
  }
}

TYPED_TEST(ConservativeKernel, EnergyIsContinuousWhereTheInteractionEnds) {
  using K = TypeParam;
  {
    const K k = Traits<K>::make();
    std::mt19937_64 g(5);
    for (int s = 0; s < kSamples; ++s) {
      Elements el = Traits<K>::pair(g);
      const Vec3 n = (el.x[1] - el.x[0]).normalized();
      const double reach = Traits<K>::reach(k, el);
      // The energy scale of this pair well inside its reach.
      el.x[1] = el.x[0] + 0.5 * reach * n;
      const double inside = std::abs(evaluate(k, el).energy);
      ASSERT_GT(inside, 0.0) << k.name();
      el.x[1] = el.x[0] + reach * (1 - 1e-6) * n;
      const double just_inside = evaluate(k, el).energy;
      el.x[1] = el.x[0] + reach * (1 + 1e-9) * n;
      const PairForces beyond = evaluate(k, el);
      EXPECT_LT(std::abs(just_inside), 1e-9 * inside) << k.name();
      EXPECT_EQ(beyond.energy, 0.0) << k.name();
      EXPECT_EQ(beyond.f1.norm(), 0.0) << k.name();
    }
  }
}

TYPED_TEST(DampingKernel, DampersNeverPutEnergyIn) {
  using K = TypeParam;
  {
    const K k = Traits<K>::make();
    std::mt19937_64 g(6);
    int damping = 0;
    for (int s = 0; s < kSamples; ++s) {
      Elements el = Traits<K>::pair(g);
      const PairForces r = evaluate(k, el);
      EXPECT_EQ(r.energy, 0.0) << k.name();
      // Power of the damping forces and torques: never positive.
      const double power =
          r.f1.dot(el.v[0]) + r.f2.dot(el.v[1]) + r.t1.dot(el.w[0]) + r.t2.dot(el.w[1]);
      const double scale = r.f1.norm() * (el.v[0].norm() + el.v[1].norm()) + 1e-300;
      EXPECT_LE(power, 1e-12 * scale) << k.name();
      if (power < 0) ++damping;
      // A rigid motion (translation plus rotation about any point) is not damped.
      const Vec3 u(0.3, -0.7, 0.2), omega = 0.4 * random_unit(g), c(1, -2, 0.5);
      for (std::size_t i = 0; i < 2; ++i) {
        el.v[i] = u + omega.cross(el.x[i] - c);
        el.w[i] = omega;
      }
      const PairForces rigid = evaluate(k, el);
      EXPECT_LT(rigid.f1.norm(), 1e-12 * std::max(1.0, r.f1.norm())) << k.name();
    }
    EXPECT_GT(damping, kSamples / 2);
  }
}
