// Compression of a nanocrystalline particle (scenes.md compression, thesis Ch. 6): the seeded
// packing, the bond graph's components, the platen protocol, and the job itself — elastic,
// plastic and brittle particles, its energy balance, its inputs and its checkpoints.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <string>

#include "mdem/core/units.h"
#include "mdem/io/state_io.h"
#include "mdem/job/compression_job.h"
#include "mdem/scene/grain_packing.h"

namespace mdem {
namespace {

using Edges = std::vector<std::pair<std::uint32_t, std::uint32_t>>;

PackingSpec sphere(double r_outer, std::uint64_t seed = 1) {
  PackingSpec s;
  s.r_outer = r_outer;
  s.grain_r_min = 1.0;
  s.grain_r_max = 2.0;
  s.target_porosity = 0.4;
  s.material = gold();
  s.seed = seed;
  return s;
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

// Deepest overlap of touching grains over the smaller radius, and the mean.
std::pair<double, double> overlaps(const PackedParticle& p) {
  const Elements& g = p.grains;
  double worst = 0, mean = 0;
  for (const auto& [i, j] : p.touching) {
    const double u =
        (g.radius[i] + g.radius[j] - (g.x[j] - g.x[i]).norm()) / std::min(g.radius[i], g.radius[j]);
    worst = std::max(worst, u);
    mean += u / static_cast<double>(p.touching.size());
  }
  return {worst, mean};
}

TEST(GrainPacking, SameSeedSameGrainsOtherSeedOthers) {
  const PackedParticle a = pack_grains(sphere(8.0, 7));
  const PackedParticle b = pack_grains(sphere(8.0, 7));
  const PackedParticle c = pack_grains(sphere(8.0, 8));
  ASSERT_GT(a.grains.size(), 50u);
  EXPECT_TRUE(same_bits(a.grains.x, b.grains.x));
  EXPECT_TRUE(same_bits(a.grains.radius, b.grains.radius));
  EXPECT_EQ(a.touching, b.touching);
  EXPECT_EQ(a.porosity, b.porosity);
  EXPECT_FALSE(same_bits(a.grains.x, c.grains.x));
}

TEST(GrainPacking, FullSphereMeetsItsSpec) {
  const PackingSpec s = sphere(10.0, 3);
  const PackedParticle p = pack_grains(s);
  const Elements& g = p.grains;
  const std::size_t n = g.size();
  // The grain count fills 60 % of the sphere: (1 − 0.4)·(4/3)π10³ / ((4/3)π·E[R³] = 3.75) ≈ 160.
  EXPECT_NEAR(static_cast<double>(n), 0.6 * 1000.0 / 3.75, 25.0);
  // Measured porosity (overlaps counted once), within a few % of the target.
  EXPECT_NEAR(p.porosity, s.target_porosity, 0.02);
  EXPECT_LT(p.porosity_error, 0.002);
  EXPECT_GT(p.porosity_error, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(g.kind[i], ElementKind::Grain);
    EXPECT_GE(g.radius[i], s.grain_r_min);
    EXPECT_LE(g.radius[i], s.grain_r_max);
    // Inside the container, up to the small overlap with its wall at equilibrium.
    EXPECT_LE(g.x[i].norm() + g.radius[i], s.r_outer + 0.05 * g.radius[i]) << "grain " << i;
    EXPECT_EQ(g.v[i].norm(), 0.0);
  }
  const auto [worst, mean] = overlaps(p);
  EXPECT_LT(worst, 0.25);
  EXPECT_LT(mean, 0.05);
  EXPECT_LT(p.unbalanced_ratio, s.tolerance);
  // Touching pairs: sorted, i < j, each really touching.
  EXPECT_TRUE(std::is_sorted(p.touching.begin(), p.touching.end()));
  for (const auto& [i, j] : p.touching) {
    EXPECT_LT(i, j);
    EXPECT_LT((g.x[j] - g.x[i]).norm(), g.radius[i] + g.radius[j]);
  }
  // A dense packing bonds into one body, apart from its few rattlers.
  EXPECT_LT(p.rattlers, static_cast<long>(n / 20) + 1);
  EXPECT_EQ(connected_components(n, p.touching), 1 + p.rattlers);
  std::printf(
      "[ packing  ] R = 10 nm: %zu grains, %zu touching pairs, porosity %.4f +- %.4f, "
      "%ld rattlers, overlap mean %.4f max %.3f of R_min, %ld steps, wall shift %.3f nm\n",
      n, p.touching.size(), p.porosity, p.porosity_error, p.rattlers, mean, worst, p.steps,
      p.wall_shift);
}

TEST(GrainPacking, ShellAndCubeStayInTheirContainers) {
  PackingSpec shell = sphere(12.0, 5);
  shell.r_inner = 7.0;
  shell.grain_r_max = 1.5;
  const PackedParticle p = pack_grains(shell);
  for (std::size_t i = 0; i < p.grains.size(); ++i) {
    const double r = p.grains.x[i].norm(), R = p.grains.radius[i];
    EXPECT_LE(r + R, shell.r_outer + 0.05 * R);
    EXPECT_GE(r - R, shell.r_inner - 0.05 * R);
  }
  EXPECT_NEAR(p.porosity, shell.target_porosity, 0.03);
  EXPECT_EQ(connected_components(p.grains.size(), p.touching), 1 + p.rattlers);

  PackingSpec cube = sphere(6.0, 9);
  cube.shape = PackingShape::Cube;
  const PackedParticle c = pack_grains(cube);
  for (std::size_t i = 0; i < c.grains.size(); ++i)
    EXPECT_LE(c.grains.x[i].cwiseAbs().maxCoeff() + c.grains.radius[i],
              cube.r_outer + 0.05 * c.grains.radius[i]);
  EXPECT_NEAR(c.porosity, cube.target_porosity, 0.03);
}

void expect_invalid(const PackingSpec& s, const std::string& field) {
  try {
    pack_grains(s);
    ADD_FAILURE() << "accepted a bad " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

TEST(GrainPacking, RejectsImpossibleSpecs) {
  PackingSpec s = sphere(10.0);
  s.grain_r_min = 0;
  expect_invalid(s, "grain_r_min");
  s = sphere(10.0);
  s.grain_r_max = 0.5;  // below the minimum
  expect_invalid(s, "grain_r_max");
  s = sphere(10.0);
  s.grain_r_max = 6.0;  // wider than the sphere's radius
  s.grain_r_min = 5.5;
  expect_invalid(s, "grain_r_max");
  s = sphere(10.0);
  s.r_inner = 9.0;  // a shell 1 nm thick for grains of 2-4 nm
  expect_invalid(s, "grain_r_max");
  s = sphere(10.0);
  s.r_inner = 10.0;
  expect_invalid(s, "r_inner");
  s = sphere(10.0);
  s.r_outer = std::nan("");
  expect_invalid(s, "r_outer");
  for (double p : {0.2, 0.1, 0.95, std::nan("")}) {
    s = sphere(10.0);
    s.target_porosity = p;
    expect_invalid(s, "target_porosity");
  }
  s = sphere(1000.0);  // ~64 million grains
  expect_invalid(s, "5 million");
  s = sphere(10.0);
  s.material.youngs = 0;
  expect_invalid(s, "youngs");
}

TEST(ConnectedComponents, HandMadeGraphs) {
  EXPECT_EQ(connected_components(0, {}), 0);
  EXPECT_EQ(connected_components(5, {}), 5);
  EXPECT_EQ(connected_components(4, Edges{{0, 1}, {1, 2}, {2, 3}}), 1);  // a chain
  // Two triangles and an isolated vertex; repeated edges and a self loop change nothing.
  const Edges two = {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {1, 0}, {4, 4}};
  EXPECT_EQ(connected_components(7, two), 3);
  Edges joined = two;
  joined.emplace_back(2, 5);
  EXPECT_EQ(connected_components(7, joined), 2);
  // A star whose edges come in every order.
  EXPECT_EQ(connected_components(6, Edges{{5, 0}, {3, 0}, {0, 1}, {4, 0}, {2, 0}}), 1);
  EXPECT_THROW(connected_components(3, Edges{{0, 3}}), std::invalid_argument);
}

// ---- protocol ----

TEST(CompressionProtocol, MotionLawVelocitiesAndDuration) {
  CompressionLoading l;
  l.speed = 0.05;
  l.peak_displacement = 2.0;
  const CompressionProtocol p(l, 0, 1);
  // Loading h/(2v) = 20 ps, as long again unloading.
  EXPECT_DOUBLE_EQ(p.peak_time(), 20.0);
  EXPECT_DOUBLE_EQ(p.duration(), 40.0);
  EXPECT_DOUBLE_EQ(p.displacement(0.0), 0.0);
  EXPECT_DOUBLE_EQ(p.displacement(5.0), 0.5);  // both platens at 0.05 nm/ps
  EXPECT_DOUBLE_EQ(p.displacement(20.0), 2.0);
  EXPECT_DOUBLE_EQ(p.displacement(30.0), 1.0);
  EXPECT_DOUBLE_EQ(p.displacement(40.0), 0.0);
  EXPECT_DOUBLE_EQ(p.displacement(55.0), 0.0);
  EXPECT_TRUE(p.loading(19.9));
  EXPECT_FALSE(p.loading(20.1));
  EXPECT_EQ(p.phase(1.0), "loading");
  EXPECT_EQ(p.phase(25.0), "unloading");
  EXPECT_EQ(p.phase(41.0), "done");
  CompressionLoading once = l;
  once.unload = false;
  const CompressionProtocol q(once, 0, 1);
  EXPECT_DOUBLE_EQ(q.duration(), 20.0);
  EXPECT_DOUBLE_EQ(q.displacement(30.0), 2.0);

  // Two platens alone, stepped at 0.7 ps (the peak falls inside a step): the updater prescribes
  // the platens' velocities (mean of the law over each step), so their approach follows the law
  // exactly at every step, down to rounding, and they end where they started.
  Elements el;
  const std::size_t top = add_platen(el, Vec3(0, 0, 5), Vec3(0, 0, -1), 1.0, 5.0);
  const std::size_t bottom = add_platen(el, Vec3(0, 0, -5), Vec3(0, 0, 1), 1.0, 5.0);
  IntegratorSettings st;
  st.dt = 0.7;
  st.threads = 1;
  System sys(std::move(el), st);
  auto proto = std::make_shared<CompressionProtocol>(l, top, bottom);
  sys.add_updater(proto);
  sys.initialize();
  const Elements& e = sys.elements();
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(e.dof[top][k], DofMode::Prescribed);
    EXPECT_EQ(e.dof[top][k + 3], DofMode::Fixed);
  }
  EXPECT_DOUBLE_EQ(e.v_prescribed[top].z(), -0.05);
  EXPECT_DOUBLE_EQ(e.v_prescribed[bottom].z(), 0.05);
  double max_h = 0;
  while (sys.time() < p.duration() + 2.0) {
    sys.step();
    const double h = (5.0 - e.x[top].z()) + (e.x[bottom].z() + 5.0);
    max_h = std::max(max_h, h);
    ASSERT_NEAR(h, p.displacement(sys.time()), 1e-12) << "t = " << sys.time();
    EXPECT_EQ(e.x[top].x(), 0.0);
    EXPECT_NEAR(e.x[top].z() - 5.0, -(e.x[bottom].z() + 5.0), 1e-12);  // symmetric
    if (sys.time() < 19.0) {
      EXPECT_NEAR(e.v[top].z(), -0.05, 1e-15);
    }
    if (sys.time() > 21.0 && sys.time() < 39.0) {
      EXPECT_NEAR(e.v[top].z(), 0.05, 1e-15);
    }
  }
  EXPECT_NEAR(max_h, 2.0, 2 * 0.7 * 0.05);
  EXPECT_NEAR(e.x[top].z(), 5.0, 1e-12);
  EXPECT_EQ(e.v[top].z(), 0.0);

  CompressionLoading bad = l;
  bad.speed = 0;
  EXPECT_THROW(CompressionProtocol(bad, 0, 1), std::invalid_argument);
  bad = l;
  bad.peak_displacement = -1;
  EXPECT_THROW(CompressionProtocol(bad, 0, 1), std::invalid_argument);
}

// ---- the job ----

// A small full sphere (R = 8 nm, grains of 1–2 nm, ~90 grains) between platens at 0.02 nm/ps,
// loaded to h and unloaded, under local damping 0.7 (the thesis's) and dashpots β = 0.5.
CompressionJobSpec job_spec(BondBehaviour b, double strength_gpa, double h,
                            const GrainMaterial& m = gold()) {
  CompressionJobSpec s;
  s.particle = sphere(8.0, 11);
  s.particle.material = m;
  s.bond.behaviour = b;
  s.bond.strength = units::GPa(strength_gpa);
  s.loading.speed = 0.02;
  s.loading.peak_displacement = h;
  s.viscous_ratio = 0.5;
  return s;
}

IntegratorSettings job_settings(int threads = 2) {
  IntegratorSettings st;
  st.local_damping = 0.7;
  st.threads = threads;
  return st;
}

struct Curve {
  std::vector<SeriesFrame> frames;
  JobObserver observer() {
    JobObserver o;
    o.frame = [this](const SeriesFrame& f) { frames.push_back(f); };
    return o;
  }
};

template <class T>
T summary_value(const Summary& s, const std::string& name) {
  for (const auto& [k, v] : s)
    if (k == name) return std::get<T>(v);
  ADD_FAILURE() << "no summary value " << name;
  return T{};
}

std::size_t column(const CompressionJob& job, const std::string& name) {
  const auto c = job.columns();
  const auto it = std::find(c.begin(), c.end(), name);
  EXPECT_NE(it, c.end()) << name;
  return static_cast<std::size_t>(it - c.begin());
}

// Largest displacement of the bonded grains from their start once the best rigid motion is
// taken out (Kabsch: centroids, then the rotation from the SVD of the covariance). Rattlers are
// left out: nothing holds them in place.
double non_rigid_residual(const std::vector<Vec3>& X0, const std::vector<Vec3>& x0,
                          const PackedParticle& p) {
  std::vector<bool> bonded(p.grains.size(), false);
  for (const auto& [i, j] : p.touching) bonded[i] = bonded[j] = true;
  std::vector<Vec3> X, x;
  for (std::size_t i = 0; i < bonded.size(); ++i)
    if (bonded[i]) {
      X.push_back(X0[i]);
      x.push_back(x0[i]);
    }
  const std::size_t n = X.size();
  Vec3 cX = Vec3::Zero(), cx = Vec3::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    cX += X[i] / static_cast<double>(n);
    cx += x[i] / static_cast<double>(n);
  }
  Mat3 H = Mat3::Zero();
  for (std::size_t i = 0; i < n; ++i) H += (X[i] - cX) * (x[i] - cx).transpose();
  Eigen::JacobiSVD<Mat3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 d = Mat3::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() > 0 ? 1.0 : -1.0;
  const Mat3 R = svd.matrixV() * d * svd.matrixU().transpose();
  double worst = 0;
  for (std::size_t i = 0; i < n; ++i)
    worst = std::max(worst, ((x[i] - cx) - R * (X[i] - cX)).norm());
  return worst;
}

TEST(CompressionJob, ElasticParticleRecovers) {
  CompressionJob job(job_spec(BondBehaviour::Elastic, 0, 1.2), job_settings());
  prepare_job(job);  // packs the particle
  const std::size_t n = job.packing().grains.size();
  EXPECT_EQ(job.bonds().bonds().size(), job.packing().touching.size());
  EXPECT_EQ(job.fragments(), 1);  // rattlers, never bonded, are no fragments
  Curve c;
  run_job(job, {1.0, 0.0}, c.observer());
  const Summary at_end = job.summary();
  const double peak = summary_value<double>(at_end, "peak_force_nN");
  EXPECT_GT(peak, 10.0);  // nN
  EXPECT_NEAR(job.displacement(), 0.0, 1e-9);
  EXPECT_EQ(job.bonds().broken_count(), 0u);
  EXPECT_EQ(job.bonds().yielded_count(), 0u);
  // The curve: compression positive, largest at the peak displacement, and the energy balance
  // holds throughout.
  const std::size_t iF = column(job, "force_nN"), islip = column(job, "slip_max_nm");
  const std::size_t ir = column(job, "balance_residual_eV"), iw = column(job, "external_work_eV");
  double max_work = 0, max_residual = 0, slip_peak = 0;
  for (const SeriesFrame& f : c.frames) {
    EXPECT_GT(f.values[iF], -0.02 * peak);
    max_work = std::max(max_work, std::abs(f.values[iw]));
    max_residual = std::max(max_residual, std::abs(f.values[ir]));
    slip_peak = std::max(slip_peak, f.values[islip]);
  }
  EXPECT_NEAR(summary_value<double>(at_end, "peak_force_displacement_nm"), 1.2, 0.1);
  EXPECT_LT(summary_value<double>(at_end, "energy_balance_error"), 0.01);
  EXPECT_LT(max_residual, 0.01 * max_work);
  EXPECT_GT(summary_value<double>(at_end, "loading_stiffness_nN_per_nm"), 0.0);

  // Let the platens rest at their start a little longer (the particle was still ringing): the
  // force returns to zero and the grains to their places.
  job.system().run(2000);
  const Summary s = job.summary();
  EXPECT_LT(std::abs(job.platen_force_nN()), 0.01 * peak);
  EXPECT_LT(std::abs(summary_value<double>(s, "residual_height_loss_nm")), 0.01);
  // Eq. 40's slip also counts a rigid turn of the whole particle (the frictionless platens let
  // it turn a little): small next to the peak's and to a grain; without the rigid motion, the
  // grains are back where they started.
  const double slip_max = summary_value<double>(s, "slip_max_nm");
  EXPECT_LT(slip_max, 0.05);
  EXPECT_LT(slip_max, 0.25 * slip_peak);
  const double residual =
      non_rigid_residual(job.packing().grains.x, job.system().elements().x, job.packing());
  EXPECT_LT(residual, 2e-3);
  std::printf(
      "[ elastic  ] %zu grains, %zu bonds: peak %.2f nN at %.3f nm, %.3f nN at the end of "
      "unloading, %.1e after rest; slip max %.3f nm (%.3f at peak), non-rigid residual "
      "%.1e nm; balance error %.1e; dt %.3f ps (critical %.3f)\n",
      n, job.bonds().bonds().size(), peak,
      summary_value<double>(at_end, "peak_force_displacement_nm"),
      summary_value<double>(at_end, "final_force_nN"), job.platen_force_nN(), slip_max, slip_peak,
      residual, summary_value<double>(at_end, "energy_balance_error"),
      summary_value<double>(s, "dt_ps"), summary_value<double>(s, "critical_dt_ps"));
}

TEST(CompressionJob, BrittleParticleBreaksBondsAndBalancesEnergy) {
  // CdS with a low strength (σ_f = 1 GPa), crushed by a fifth of its diameter.
  CompressionJob job(job_spec(BondBehaviour::Brittle, 1.0, 3.2, cadmium_sulfide()), job_settings());
  Curve c;
  run_job(job, {1.0, 0.0}, c.observer());
  const Summary s = job.summary();
  const long broken = summary_value<long>(s, "bonds_broken");
  EXPECT_GT(broken, 0);
  EXPECT_EQ(summary_value<long>(s, "bonds_yielded"), 0);
  const double err = summary_value<double>(s, "energy_balance_error");
  EXPECT_LT(err, 0.02);
  const std::size_t ir = column(job, "balance_residual_eV"), iw = column(job, "external_work_eV");
  double max_work = 0, max_residual = 0;
  for (const SeriesFrame& f : c.frames) {
    max_work = std::max(max_work, std::abs(f.values[iw]));
    max_residual = std::max(max_residual, std::abs(f.values[ir]));
  }
  EXPECT_LT(max_residual, 0.02 * max_work);
  std::printf(
      "[ brittle  ] %ld of %ld bonds broken, %ld fragments, peak %.2f nN, work %.1f eV, "
      "balance error %.2e (max residual %.2e of the work)\n",
      broken, summary_value<long>(s, "bonds"), summary_value<long>(s, "fragments"),
      summary_value<double>(s, "peak_force_nN"), max_work, err, max_residual / max_work);
}

TEST(CompressionJob, PlasticParticleKeepsItsDeformation) {
  CompressionJob job(job_spec(BondBehaviour::Plastic, 1.0, 3.0), job_settings());
  run_job(job, {1.0, 0.0}, {});
  const Summary s = job.summary();
  EXPECT_GT(summary_value<long>(s, "bonds_yielded"), 0);
  EXPECT_EQ(summary_value<long>(s, "bonds_broken"), 0);
  // Flattened for good, and the grains slid past each other.
  const double loss = summary_value<double>(s, "residual_height_loss_nm");
  EXPECT_GT(loss, 0.1);
  EXPECT_GT(summary_value<double>(s, "slip_mean_nm"), 0.01);
  EXPECT_LT(summary_value<double>(s, "energy_balance_error"), 0.02);
  std::printf(
      "[ plastic  ] %ld bonds yielded, residual height loss %.3f nm, slip mean %.3f max "
      "%.3f nm, peak %.2f nN, balance error %.2e\n",
      summary_value<long>(s, "bonds_yielded"), loss, summary_value<double>(s, "slip_mean_nm"),
      summary_value<double>(s, "slip_max_nm"), summary_value<double>(s, "peak_force_nN"),
      summary_value<double>(s, "energy_balance_error"));
}

void expect_job_invalid(CompressionJobSpec s, const std::string& field) {
  try {
    CompressionJob job(s, job_settings());
    ADD_FAILURE() << "accepted a bad " << field;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
  }
}

TEST(CompressionJob, RejectsBadInputsNamingTheField) {
  const CompressionJobSpec good = job_spec(BondBehaviour::Elastic, 0, 1.0);
  CompressionJobSpec s = good;
  s.particle.grain_r_min = -1;
  expect_job_invalid(s, "grain_r_min");
  s = good;
  s.particle.grain_r_max = 100;
  expect_job_invalid(s, "grain_r_max");
  s = good;
  s.particle.target_porosity = 0.99;
  expect_job_invalid(s, "target_porosity");
  s = good;
  s.loading.speed = 0;
  expect_job_invalid(s, "speed");
  s = good;
  s.loading.speed = std::nan("");
  expect_job_invalid(s, "speed");
  s = good;
  s.loading.peak_displacement = 0;
  expect_job_invalid(s, "peak_displacement");
  s = good;
  s.loading.peak_displacement = 16.0;  // the particle's diameter
  expect_job_invalid(s, "peak_displacement");
  s = good;
  s.viscous_ratio = -0.1;
  expect_job_invalid(s, "viscous_ratio");
}

TEST(CompressionJob, SlipSnapshotsAndFragmentsOfAFreshParticle) {
  CompressionJob job(job_spec(BondBehaviour::Elastic, 0, 1.0), job_settings());
  prepare_job(job);  // packs the particle
  const std::vector<double> slip = job.slip();
  ASSERT_EQ(slip.size(), job.system().elements().size());
  for (double v : slip) EXPECT_NEAR(v, 0.0, 1e-12);  // the rigid fit's round-off
  EXPECT_EQ(job.platen_force_nN(), 0.0);             // the platens just touch
  EXPECT_EQ(job.displacement(), 0.0);
  std::vector<Snapshot> snaps;
  JobObserver o;
  o.snapshot = [&](const Snapshot& s) { snaps.push_back(s); };
  run_job(job, {1.0, 10.0}, o);
  ASSERT_FALSE(snaps.empty());
  const auto& sc = snaps.back().scalars;
  const auto it =
      std::find_if(sc.begin(), sc.end(), [](const auto& p) { return p.first == "slip_nm"; });
  ASSERT_NE(it, sc.end());
  EXPECT_EQ(it->second, job.slip());
}

// A brittle run saved mid-loading and resumed in a job built anew reports the same frames, bit
// for bit, as the run that never stopped (bond breakage, the tracked peak and the stiffness fit
// included).
TEST(CompressionJob, CheckpointResumesBitIdentically) {
  const CompressionJobSpec spec = job_spec(BondBehaviour::Brittle, 0.5, 3.0, cadmium_sulfide());
  const JobCadence cadence{2.0, 20.0};
  CompressionJob full(spec, job_settings());
  Curve whole;
  const JobRunResult rf = run_job(full, cadence, whole.observer());
  const Summary full_summary = full.summary();

  std::string bytes;
  long saved_at = -1;
  {
    CompressionJob first(spec, job_settings());
    JobObserver obs;
    const long stop_at = rf.steps * 2 / 3;  // in the unloading, after bonds broke
    obs.checkpoint = [&](long step) {
      if (bytes.empty() && step >= stop_at) {
        bytes = save_checkpoint(first);
        saved_at = step;
      }
    };
    obs.cancelled = [&] { return !bytes.empty(); };
    ASSERT_TRUE(run_job(first, cadence, obs).cancelled);
  }
  CompressionJob resumed(spec, job_settings());
  load_checkpoint(resumed, bytes);
  EXPECT_EQ(resumed.system().steps(), saved_at);
  EXPECT_EQ(save_checkpoint(resumed), bytes);
  Curve after;
  EXPECT_EQ(run_job(resumed, cadence, after.observer()).steps, rf.steps);
  std::vector<const SeriesFrame*> expected;
  for (const SeriesFrame& f : whole.frames)
    if (f.step > saved_at) expected.push_back(&f);
  ASSERT_EQ(after.frames.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) {
    EXPECT_EQ(after.frames[k].step, expected[k]->step);
    EXPECT_TRUE(same_bits(after.frames[k].values, expected[k]->values))
        << "frame at step " << expected[k]->step;
  }
  EXPECT_TRUE(same_bits(full.system().elements().x, resumed.system().elements().x));
  EXPECT_EQ(resumed.summary(), full_summary);
  EXPECT_GT(full.bonds().broken_count(), 0u);

  // A checkpoint of another particle is refused.
  CompressionJobSpec other = spec;
  other.particle.seed = 12;
  CompressionJob different(other, job_settings());
  if (different.system().elements().size() != resumed.system().elements().size()) {
    EXPECT_THROW(load_checkpoint(different, bytes), CheckpointError);
  }
}

}  // namespace
}  // namespace mdem
