// The compression job's validation runs (docs/compression.md), a plain timed program:
//
//   validate_compression hertz  elastic full spheres against rigid-platen Hertz, with the
//                               effective modulus and Poisson ratio measured on a bonded cube of
//                               the same packing;
//   validate_compression au     the thesis's Au shell (52/95 nm, grains 3-6 nm), plastic bonds
//                               σ_y = 2, 4, 6, 8 GPa: force-displacement curves and peak forces;
//   validate_compression cds    the thesis's CdS shell (75/105 nm), brittle bonds σ_f = 4 GPa,
//                               peak displacements 40, 60, 80 nm: outcome, fragments, stiffness.
//
// Each case prints a table and writes its curves as CSV into --out (default .). Options:
//   --threads N --speed V (nm/ps per platen) --quick (smaller particles, for a smoke run)
//   hertz: --radius R --grains MIN,MAX --porosity P --realisations N --strain S (peak approach
//          over R) --seed K; the cube: --cube-half A (default R) --cube-speed V --cube-only;
//          other surfaces: --carve (cut out of a bulk packing) [--press P (cut P·r_max wider,
//          then pressed into a spherical wall at R before bonding)]
//   au: --sigmas LIST --peak H;  cds: --peaks LIST --grains MIN,MAX
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/core/units.h"
#include "mdem/force/contact/linear_contact.h"
#include "mdem/force/wall/spherical_wall.h"
#include "mdem/job/compression_job.h"

namespace {

namespace fs = std::filesystem;
using namespace mdem;
using Clock = std::chrono::steady_clock;

struct Options {
  std::string mode;
  int threads = 0;
  double speed = 0.02;  // nm/ps per platen
  bool quick = false, cube_only = false;
  bool carve = false;  // hertz: spheres carved out of a bulk cube packing, not packed in a sphere
  double press = 0;    // hertz --carve: carve this many r_max wider, then press to R (0: no press)
  fs::path out = ".";
  // hertz
  double radius = 50, gmin = 1, gmax = 2, porosity = 0.4, strain = 0.1;
  double cube_half = 0;        // 0: the sphere's radius (the same surface-to-volume ratio, 3/R)
  double cube_speed = 0.0004;  // nm/ps per platen: quasi-static (see docs/compression.md)
  int realisations = 10;
  unsigned seed = 1;
  // au / cds
  std::vector<double> sigmas = {2, 4, 6, 8};
  double peak = 40;
  std::vector<double> peaks = {40, 60, 80};
  bool grains_given = false;
};

[[noreturn]] void usage(const std::string& msg) {
  std::fprintf(stderr, "validate_compression: %s\n", msg.c_str());
  std::fprintf(
      stderr,
      "usage: validate_compression hertz|au|cds [--threads N] [--speed V] [--quick] "
      "[--out DIR]\n  hertz: [--radius R] [--grains MIN,MAX] [--porosity P] "
      "[--realisations N] [--cube-half A] [--cube-speed V] [--cube-only] [--carve [--press "
      "P]] [--strain S] [--seed K]\n  au: [--sigmas "
      "LIST] [--peak H]   cds: [--peaks LIST] [--grains MIN,MAX]\n");
  std::exit(2);
}

double number(const std::string& flag, const std::string& s) {
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end || !std::isfinite(v) || v <= 0)
    usage(flag + ": '" + s + "' is not a positive number");
  return v;
}

std::vector<double> list(const std::string& flag, const std::string& s) {
  std::vector<double> v;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) v.push_back(number(flag, item));
  if (v.empty()) usage(flag + ": empty list");
  return v;
}

Options parse(int argc, char** argv) {
  if (argc < 2) usage("which validation? hertz, au or cds");
  Options o;
  o.mode = argv[1];
  if (o.mode != "hertz" && o.mode != "au" && o.mode != "cds")
    usage("unknown validation '" + o.mode + "' (allowed: hertz, au, cds)");
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    auto val = [&]() -> std::string {
      if (i + 1 >= argc) usage(a + " needs a value");
      return argv[++i];
    };
    if (a == "--threads")
      o.threads = static_cast<int>(number(a, val()));
    else if (a == "--speed")
      o.speed = number(a, val());
    else if (a == "--quick")
      o.quick = true;
    else if (a == "--cube-only")
      o.cube_only = true;
    else if (a == "--carve")
      o.carve = true;
    else if (a == "--press")
      o.press = number(a, val());
    else if (a == "--out")
      o.out = val();
    else if (a == "--radius")
      o.radius = number(a, val());
    else if (a == "--grains") {
      const auto g = list(a, val());
      if (g.size() != 2 || g[0] > g[1]) usage("--grains: MIN,MAX with MIN <= MAX");
      o.gmin = g[0];
      o.gmax = g[1];
      o.grains_given = true;
    } else if (a == "--porosity")
      o.porosity = number(a, val());
    else if (a == "--realisations")
      o.realisations = static_cast<int>(number(a, val()));
    else if (a == "--cube-half")
      o.cube_half = number(a, val());
    else if (a == "--cube-speed")
      o.cube_speed = number(a, val());
    else if (a == "--strain")
      o.strain = number(a, val());
    else if (a == "--seed")
      o.seed = static_cast<unsigned>(number(a, val()));
    else if (a == "--sigmas")
      o.sigmas = list(a, val());
    else if (a == "--peak")
      o.peak = number(a, val());
    else if (a == "--peaks")
      o.peaks = list(a, val());
    else
      usage("unknown flag '" + a + "'");
  }
  return o;
}

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// One recorded point of a run.
struct Point {
  double t, h, f;  // ps, nm, nN
  long broken, yielded;
};

struct RunResult {
  std::vector<Point> curve;
  double pack_s = 0, run_s = 0;
  long grains = 0, bonds = 0, steps = 0;
  double porosity = 0, dt = 0;
  double wall_shift = 0;  // how far the packing walls closed in (nm): the body is that much smaller
  std::vector<Vec3> x0;   // grain positions at the start (bonded, force-free)
};

IntegratorSettings settings(const Options& o) {
  IntegratorSettings s;
  s.local_damping = 0.7;  // thesis §6.2
  s.threads = o.threads;
  return s;
}

// Builds the job (packing included), runs it, records the curve every `every_ps`.
RunResult run(CompressionJob& job, double every_ps) {
  RunResult r;
  prepare_job(job);  // the packing stage, when the job packs its particle
  System& sys = job.system();
  sys.initialize();
  r.grains = static_cast<long>(job.packing().grains.size());
  r.bonds = static_cast<long>(job.bonds().bonds().size());
  r.porosity = job.packing().porosity;
  r.wall_shift = job.packing().wall_shift;
  r.dt = sys.dt();
  for (std::size_t i = 0; i < job.packing().grains.size(); ++i) r.x0.push_back(sys.elements().x[i]);
  JobObserver obs;
  obs.frame = [&](const SeriesFrame& f) {
    r.curve.push_back({f.time_ps, job.displacement(), job.platen_force_nN(),
                       (long)job.bonds().broken_count(), (long)job.bonds().yielded_count()});
  };
  const auto t0 = Clock::now();
  JobCadence c;
  c.frame_every_ps = every_ps;
  const JobRunResult res = run_job(job, c, obs);
  r.run_s = seconds_since(t0);
  r.steps = res.steps;
  return r;
}

void write_curve(const fs::path& p, const std::vector<Point>& c) {
  std::ofstream out(p);
  out << "time_ps,displacement_nm,force_nN,bonds_broken,bonds_yielded\n";
  for (const auto& q : c)
    out << q.t << ',' << q.h << ',' << q.f << ',' << q.broken << ',' << q.yielded << '\n';
}

// Least-squares slope and intercept of y on x.
std::pair<double, double> fit_line(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / n;
  const double my = std::accumulate(y.begin(), y.end(), 0.0) / n;
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sxy += (x[k] - mx) * (y[k] - my);
    sxx += (x[k] - mx) * (x[k] - mx);
  }
  const double slope = sxy / sxx;
  return {slope, my - slope * mx};
}

CompressionJobSpec base_spec(PackingShape shape, double r_outer, double r_inner, double gmin,
                             double gmax, double porosity, const GrainMaterial& m, unsigned seed,
                             const Options& o) {
  CompressionJobSpec s;
  s.particle.shape = shape;
  s.particle.r_outer = r_outer;
  s.particle.r_inner = r_inner;
  s.particle.grain_r_min = gmin;
  s.particle.grain_r_max = gmax;
  s.particle.target_porosity = porosity;
  s.particle.material = m;
  s.particle.seed = seed;
  s.particle.threads = o.threads;
  s.bond.material = m;
  s.loading.speed = o.speed;
  return s;
}

// The grains of a cube packing whose centres lie within R − r of its centre, with the touching
// pairs among them: a sphere with no wall-ordered skin.
PackedParticle carve_sphere(const PackedParticle& cube, double R) {
  const Elements& g = cube.grains;
  Vec3 c = Vec3::Zero();
  for (const Vec3& x : g.x) c += x;
  c /= static_cast<double>(g.size());
  PackedParticle out = cube;
  out.grains = Elements();
  std::vector<long> index(g.size(), -1);
  for (std::size_t i = 0; i < g.size(); ++i) {
    if ((g.x[i] - c).norm() + g.radius[i] > R) continue;
    ElementInit e;
    e.kind = g.kind[i];
    e.x = g.x[i] - c;
    e.q = g.q[i];
    e.mass = g.mass[i];
    e.inertia = g.inertia[i];
    e.radius = g.radius[i];
    index[i] = static_cast<long>(out.grains.add(e));
  }
  out.touching.clear();
  std::vector<int> degree(out.grains.size(), 0);
  for (const auto& [i, j] : cube.touching)
    if (index[i] >= 0 && index[j] >= 0) {
      out.touching.emplace_back(index[i], index[j]);
      ++degree[index[i]];
      ++degree[index[j]];
    }
  out.rattlers = std::count(degree.begin(), degree.end(), 0);
  out.wall_shift = 0;  // the cut is at R itself
  return out;
}

// A carved sphere pressed into a spherical wall of radius R before it is bonded: the grains that
// stick out are pushed in and the surface settles smooth at the wall, while the grains beneath
// keep the bulk packing's arrangement. Relaxes with local damping 0.7 until the mean unbalanced
// force is 1e-3 of the mean contact force; the touching pairs are found afresh.
PackedParticle press_into_sphere(PackedParticle p, double R, const GrainMaterial& m, double r_max,
                                 int threads) {
  const std::size_t n = p.grains.size();
  double start = 0;
  for (std::size_t i = 0; i < n; ++i)
    start = std::max(start, p.grains.x[i].norm() + p.grains.radius[i]);
  IntegratorSettings cfg;
  cfg.local_damping = 0.7;
  cfg.threads = threads;
  cfg.skin = std::max(0.2, 0.3 * r_max);
  cfg.guard_energy_tolerance = 1e100;  // the moving wall puts in energy no load accounts for
  System sys(std::move(p.grains), cfg);
  auto* contact = sys.add(std::make_unique<LinearContact>(m.youngs, r_max));
  auto* wall = sys.add(std::make_unique<SphericalWallContact>(Vec3::Zero(), start, 0.0, m.youngs));
  sys.initialize();
  const double rate = 2e-4 * r_max;  // nm per step, as the packing's walls
  for (double w = start; w > R;) {
    w = std::max(R, w - 10 * rate);
    wall->set_radii(w, 0.0);
    sys.refresh();
    sys.run(10);
  }
  for (long steps = 0;; steps += 100) {
    const Elements& el = sys.elements();
    const NeighborList* nl = sys.neighbors();
    double fsum = 0, unbalanced = 0;
    long contacts = 0;
    for (std::size_t i = 0; i < n; ++i) {
      unbalanced += el.f[i].norm();
      for (std::uint32_t k = nl->offsets()[i]; k < nl->offsets()[i + 1]; ++k) {
        const std::uint32_t j = nl->neighbors()[k];
        const double fc = contact->force(el.radius[i], el.radius[j], (el.x[j] - el.x[i]).norm());
        if (fc > 0) {
          fsum += fc;
          ++contacts;
        }
      }
    }
    const double ratio = contacts ? (unbalanced / n) / (fsum / contacts) : 0.0;
    if (steps > 200000)
      throw std::runtime_error("press_into_sphere: no equilibrium in 200000 steps (ratio " +
                               std::to_string(ratio) + ")");
    if (ratio < 1e-3) {
      std::printf("  pressed from %.2f to %.2f nm, relaxed in %ld steps (ratio %.2g)\n", start, R,
                  steps, ratio);
      break;
    }
    sys.run(100);
  }
  PackedParticle out = p;
  out.grains = Elements();
  out.touching.clear();
  const Elements& fin = sys.elements();
  const NeighborList* nl = sys.neighbors();  // current: it holds every touching pair
  std::vector<int> degree(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    out.grains.add(grain_element(fin.x[i], fin.radius[i], m));
    for (std::uint32_t k = nl->offsets()[i]; k < nl->offsets()[i + 1]; ++k) {
      const std::uint32_t j = nl->neighbors()[k];
      const double reach = fin.radius[i] + fin.radius[j];
      if ((fin.x[j] - fin.x[i]).squaredNorm() < reach * reach) {
        out.touching.emplace_back(i, j);  // a half list: i < j
        ++degree[i];
        ++degree[j];
      }
    }
  }
  std::sort(out.touching.begin(), out.touching.end());
  out.rattlers = std::count(degree.begin(), degree.end(), 0);
  return out;
}

// ---- hertz ------------------------------------------------------------------------------------

int hertz(const Options& o) {
  const GrainMaterial au = gold();
  const double E_bond_GPa = units::to_GPa(au.youngs);
  // 1. The bonded cube: E_eff from the stress-strain slope, ν_eff from the lateral strain. Its
  // edge is by default the sphere's diameter: the same surface-to-volume ratio (3/R), so the same
  // share of grains in the looser layers the packing walls leave at the surface.
  const double cube_half = o.cube_half > 0 ? o.cube_half : o.radius;
  CompressionJobSpec cs =
      base_spec(PackingShape::Cube, cube_half, 0, o.gmin, o.gmax, o.porosity, au, o.seed, o);
  cs.loading.peak_displacement = 0.01 * 2 * cube_half;  // 1 % strain
  cs.loading.unload = false;
  // Quasi-static: at the default 0.0004 nm/ps a 30 nm cube reaches 1 % strain in ~20 crossing
  // times of a sound wave; 2x slower changes E_eff by < 0.1 %, 5x faster lowers it by 4 %.
  cs.loading.speed = o.cube_speed;
  auto t0 = Clock::now();
  CompressionJob cube(cs, settings(o));
  const double cube_pack_s = seconds_since(t0);
  RunResult rc = run(cube, cs.loading.peak_displacement / (2 * cs.loading.speed) / 100);
  // The body is the container less the walls' closing-in: its edge, and the loaded area.
  const double edge = 2 * (cube_half - rc.wall_shift), area = edge * edge;
  std::vector<double> eps, sig;
  for (const auto& p : rc.curve)
    if (p.h >= 0.5 * cs.loading.peak_displacement) {  // past the seating of the platens
      eps.push_back(p.h / edge);
      sig.push_back(units::to_GPa(units::nN(p.f)) / area);  // nN/nm² in GPa
    }
  const double E_platen_GPa = fit_line(eps, sig).first;
  // 2. The same cube held at the peak until it is static: the strain inside it, from the
  // interior grains' displacements since the (force-free) bonded start, checks E_eff free of the
  // platens' seating and of any lag of the interior behind the platens, and gives ν_eff.
  System& sys = cube.system();
  const auto t_hold = Clock::now();
  long held = 0;
  for (double f_prev = cube.platen_force_nN();; f_prev = cube.platen_force_nN()) {
    sys.run(500);
    held += 500;
    if (std::abs(cube.platen_force_nN() - f_prev) < 1e-5 * std::abs(f_prev) || held >= 400000)
      break;
  }
  const double hold_s = seconds_since(t_hold);
  const double f_static = cube.platen_force_nN();
  // Interior grains only (within 60 % of the half-edge of the centre in every direction), clear
  // of the looser layers the packing walls leave at the faces.
  Vec3 centre = Vec3::Zero();
  for (const Vec3& x : rc.x0) centre += x;
  centre /= static_cast<double>(rc.x0.size());
  std::vector<double> pos[3], disp[3];
  for (std::size_t i = 0; i < rc.x0.size(); ++i) {
    if ((rc.x0[i] - centre).cwiseAbs().maxCoeff() > 0.6 * cube_half) continue;
    for (int a = 0; a < 3; ++a) {
      pos[a].push_back(rc.x0[i][a]);
      disp[a].push_back(sys.elements().x[i][a] - rc.x0[i][a]);
    }
  }
  const double eps_z = -fit_line(pos[2], disp[2]).first;  // compression positive
  const double eps_lat = 0.5 * (fit_line(pos[0], disp[0]).first + fit_line(pos[1], disp[1]).first);
  const double E_interior_GPa = units::to_GPa(units::nN(f_static)) / area / eps_z;
  const double E_eff_GPa = E_platen_GPa;
  const double nu_eff = eps_lat / eps_z;
  std::printf(
      "bonded cube: edge %.2f nm (walls closed in %.2f nm), %ld grains, %ld bonds, porosity "
      "%.3f, packed in %.1f s, loaded in %.1f s (%ld steps, dt %.3f ps), held %ld steps "
      "(%.1f s)\n",
      edge, rc.wall_shift, rc.grains, rc.bonds, rc.porosity, cube_pack_s, rc.run_s, rc.steps, rc.dt,
      held, hold_s);
  std::printf(
      "  E_eff = %.2f GPa from the platens' stress-strain slope; %.2f GPa from the static "
      "interior strain %.5f (platens' %.5f); bond material E = %.0f GPa; nu_eff = %.3f\n",
      E_eff_GPa, E_interior_GPa, eps_z, cs.loading.peak_displacement / edge, E_bond_GPa, nu_eff);
  write_curve(o.out / "hertz-cube.csv", rc.curve);
  if (o.cube_only) return 0;

  // 2. Spheres: exponent and prefactor of F/(R²E) = C (h/R)^n on h/R in [lo, hi].
  const double lo = 0.25 * o.strain, hi = o.strain;
  const double C_rigid = std::sqrt(2.0) / (3 * (1 - nu_eff * nu_eff));
  const double C_eq39 = 1 / (3 * std::sqrt(2.0) * (1 - nu_eff * nu_eff));
  std::printf(
      "\nsphere R = %.1f nm, grains %.2g-%.2g nm, target porosity %.2f; fit on h/R in "
      "[%.3f, %.3f]\n",
      o.radius, o.gmin, o.gmax, o.porosity, lo, hi);
  std::printf("%4s %7s %7s %7s %9s %8s %8s %9s %9s\n", "seed", "grains", "poros", "R [nm]",
              "exponent", "C(n=1.5)", "C/rigid", "pack [s]", "run [s]");
  std::vector<double> exps, Cs;
  for (int k = 0; k < o.realisations; ++k) {
    CompressionJobSpec ss = base_spec(PackingShape::Shell, o.radius, 0, o.gmin, o.gmax, o.porosity,
                                      au, o.seed + 100 + k, o);
    ss.loading.peak_displacement = o.strain * o.radius;
    ss.loading.unload = false;
    t0 = Clock::now();
    std::unique_ptr<CompressionJob> made;
    if (o.carve) {
      PackingSpec bulk = ss.particle;
      bulk.shape = PackingShape::Cube;
      bulk.r_outer = o.radius + 2 * o.gmax;  // the carved sphere stays clear of the cube's faces
      PackedParticle carved = carve_sphere(pack_grains(bulk), o.radius + o.press * o.gmax);
      if (o.press > 0)
        carved = press_into_sphere(std::move(carved), o.radius, au, o.gmax, o.threads);
      made = std::make_unique<CompressionJob>(carved, ss, settings(o));
    } else {
      made = std::make_unique<CompressionJob>(ss, settings(o));
    }
    CompressionJob& sphere = *made;
    const double pack_s = seconds_since(t0);
    RunResult r = run(sphere, ss.loading.peak_displacement / (2 * o.speed) / 200);
    // The sphere's radius is the container's less the walls' closing-in.
    const double R = o.radius - r.wall_shift;
    std::vector<double> lx, ly, c;
    for (const auto& p : r.curve) {
      const double hr = p.h / R;
      if (hr < lo || hr > hi || p.f <= 0) continue;
      const double fn = units::to_GPa(units::nN(p.f)) / (R * R * E_eff_GPa);
      lx.push_back(std::log(hr));
      ly.push_back(std::log(fn));
      c.push_back(fn / std::pow(hr, 1.5));
    }
    const double n = fit_line(lx, ly).first;
    const double C = std::accumulate(c.begin(), c.end(), 0.0) / c.size();
    exps.push_back(n);
    Cs.push_back(C);
    std::printf("%4lu %7ld %7.3f %7.2f %9.3f %8.4f %8.3f %9.1f %9.1f\n",
                static_cast<unsigned long>(ss.particle.seed), r.grains, r.porosity, R, n, C,
                C / C_rigid, pack_s, r.run_s);
    write_curve(o.out / ("hertz-sphere-" + std::to_string(k) + ".csv"), r.curve);
  }
  auto mean = [](const std::vector<double>& v) {
    return std::accumulate(v.begin(), v.end(), 0.0) / v.size();
  };
  auto sd = [&](const std::vector<double>& v) {
    const double m = mean(v);
    double s = 0;
    for (double x : v) s += (x - m) * (x - m);
    return v.size() > 1 ? std::sqrt(s / (v.size() - 1)) : 0.0;
  };
  std::printf("mean exponent %.3f ± %.3f (sd); mean prefactor C = %.4f ± %.4f\n", mean(exps),
              sd(exps), mean(Cs), sd(Cs));
  std::printf(
      "rigid-platen Hertz sqrt(2)/(3(1-nu^2)) = %.4f -> ratio %.3f; Eq. 39 "
      "1/(3 sqrt(2)(1-nu^2)) = %.4f -> ratio %.3f\n",
      C_rigid, mean(Cs) / C_rigid, C_eq39, mean(Cs) / C_eq39);
  return 0;
}

// ---- au / cds ---------------------------------------------------------------------------------

struct ShellOutcome {
  double peak_f = 0, h_at_peak = 0, k_load = 0, k_unload = 0, residual_h = 0;
  long broken = 0, yielded = 0;
};

ShellOutcome outcome(const RunResult& r, double peak) {
  ShellOutcome s;
  for (const auto& p : r.curve)
    if (p.f > s.peak_f) {
      s.peak_f = p.f;
      s.h_at_peak = p.h;
    }
  // Stiffness (least-squares slope) on loading between 10 % and 30 % of the peak displacement,
  // and on unloading between 90 % and 50 % of it.
  std::vector<double> hl, fl, hu, fu;
  bool returning = false;
  double h_prev = -1;
  for (const auto& p : r.curve) {
    if (p.h < h_prev - 1e-9) returning = true;
    h_prev = p.h;
    if (!returning && p.h >= 0.1 * peak && p.h <= 0.3 * peak) {
      hl.push_back(p.h);
      fl.push_back(p.f);
    }
    if (returning && p.h >= 0.5 * peak && p.h <= 0.9 * peak) {
      hu.push_back(p.h);
      fu.push_back(p.f);
    }
    if (returning && p.f > 1e-6 * s.peak_f) s.residual_h = p.h;
  }
  if (hl.size() > 2) s.k_load = fit_line(hl, fl).first;
  if (hu.size() > 2) s.k_unload = fit_line(hu, fu).first;
  s.broken = r.curve.back().broken;
  s.yielded = r.curve.back().yielded;
  return s;
}

// Components of the intact bond graph with at least `min_size` grains.
long big_fragments(const CompressionJob& job, long min_size) {
  const std::size_t n = job.packing().grains.size();
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (const auto& b : job.bonds().bonds())
    if (!b.broken) parent[find(b.bond.i)] = find(b.bond.j);
  std::map<std::uint32_t, long> size;
  for (std::uint32_t i = 0; i < n; ++i) ++size[find(i)];
  long count = 0;
  for (const auto& [root, s] : size) count += s >= min_size;
  return count;
}

int shells(const Options& o) {
  const bool au = o.mode == "au";
  const GrainMaterial m = au ? gold() : cadmium_sulfide();
  double r_out = au ? 95 : 105, r_in = au ? 52 : 75, gmin = 3, gmax = 6;
  if (o.grains_given) {
    gmin = o.gmin;
    gmax = o.gmax;
  }
  double scale = 1;
  if (o.quick) {  // a third of the size, same shape
    scale = 1.0 / 3;
    r_out *= scale;
    r_in *= scale;
    gmin *= scale * 1.5;
    gmax *= scale * 1.5;
  }
  const std::vector<double> cases = au ? o.sigmas : o.peaks;
  std::printf("%s shell %.0f/%.0f nm, grains %.2g-%.2g nm, platen speed %.3g nm/ps\n",
              au ? "Au" : "CdS", r_in, r_out, gmin, gmax, o.speed);
  std::printf("%8s %7s %7s %7s %10s %8s %9s %9s %8s %8s %8s %9s %8s %8s\n",
              au ? "sigma_y" : "h [nm]", "grains", "bonds", "poros", "peak [uN]", "at [nm]",
              "k_l[nN/nm]", "k_u[nN/nm]", "resid", "yielded", "broken", "frag>=10", "pack[s]",
              "run[s]");
  for (double c : cases) {
    CompressionJobSpec s =
        base_spec(PackingShape::Shell, r_out, r_in, gmin, gmax, 0.4, m, o.seed, o);
    s.bond.behaviour = au ? BondBehaviour::Plastic : BondBehaviour::Brittle;
    s.bond.strength = units::GPa(au ? c : 4.0);
    s.loading.peak_displacement = (au ? o.peak : c) * scale;
    s.viscous_ratio = 0.5;
    const auto t0 = Clock::now();
    CompressionJob job(s, settings(o));
    const double pack_s = seconds_since(t0);
    RunResult r = run(job, s.loading.peak_displacement / (2 * o.speed) / 200);
    const ShellOutcome oc = outcome(r, s.loading.peak_displacement);
    std::printf("%8.3g %7ld %7ld %7.3f %10.4f %8.2f %9.2f %9.2f %8.2f %8ld %8ld %9ld %8.1f %8.1f\n",
                c, r.grains, r.bonds, r.porosity, oc.peak_f / 1000, oc.h_at_peak, oc.k_load,
                oc.k_unload, oc.residual_h, oc.yielded, oc.broken, big_fragments(job, 10), pack_s,
                r.run_s);
    std::ostringstream name;
    name << (au ? "au-sigma" : "cds-h") << c << ".csv";
    write_curve(o.out / name.str(), r.curve);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  fs::create_directories(o.out);
  try {
    std::printf("threads %d (OMP max %d)\n", o.threads, omp_get_max_threads());
    return o.mode == "hertz" ? hertz(o) : shells(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "validate_compression: %s\n", e.what());
    return 1;
  }
}
