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
//   hertz: --radius R --grains MIN,MAX --porosity P --realisations N --cube-half A
//          --strain S (peak approach over R) --seed K
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

#include "mdem/compression_job.h"
#include "mdem/units.h"

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
  fs::path out = ".";
  // hertz
  double radius = 50, gmin = 1, gmax = 2, porosity = 0.4, cube_half = 12, strain = 0.1;
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
  std::fprintf(stderr,
               "usage: validate_compression hertz|au|cds [--threads N] [--speed V] [--quick] "
               "[--out DIR]\n  hertz: [--radius R] [--grains MIN,MAX] [--porosity P] "
               "[--realisations N] [--cube-half A] [--cube-only] [--carve] [--strain S] [--seed "
               "K]\n  au: [--sigmas "
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
  std::vector<Vec3> x0, x_half, x_peak;  // grain positions: start, half the peak, the peak
  double f_half = 0, h_half = 0;         // force and displacement at x_half
};

IntegratorSettings settings(const Options& o) {
  IntegratorSettings s;
  s.local_damping = 0.7;  // thesis §6.2
  s.threads = o.threads;
  return s;
}

// Builds the job (packing included), runs it, records the curve every `every_ps`.
RunResult run(CompressionJob& job, double every_ps, const Options& o, bool keep_peak,
              double peak = 0) {
  RunResult r;
  System& sys = job.system();
  sys.initialize();
  r.grains = static_cast<long>(job.packing().grains.size());
  r.bonds = static_cast<long>(job.bonds().bonds().size());
  r.porosity = job.packing().porosity;
  r.dt = sys.dt();
  for (std::size_t i = 0; i < job.packing().grains.size(); ++i) r.x0.push_back(sys.elements().x[i]);
  JobObserver obs;
  double h_max = -1;
  obs.frame = [&](const SeriesFrame& f) {
    const double h = job.displacement();
    r.curve.push_back({f.time_ps, h, job.platen_force_nN(), (long)job.bonds().broken_count(),
                       (long)job.bonds().yielded_count()});
    if (keep_peak && r.x_half.empty() && h >= 0.5 * peak) {
      r.x_half.assign(sys.elements().x.begin(), sys.elements().x.begin() + r.grains);
      r.f_half = job.platen_force_nN();
      r.h_half = h;
    }
    if (keep_peak && h > h_max) {
      h_max = h;
      r.x_peak.assign(sys.elements().x.begin(), sys.elements().x.begin() + r.grains);
    }
  };
  const auto t0 = Clock::now();
  JobCadence c;
  c.frame_every_ps = every_ps;
  const JobRunResult res = run_job(job, c, obs);
  r.run_s = seconds_since(t0);
  r.steps = res.steps;
  (void)o;
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
  return out;
}

// ---- hertz ------------------------------------------------------------------------------------

int hertz(const Options& o) {
  const GrainMaterial au = gold();
  const double E_bond_GPa = units::to_GPa(au.youngs);
  // 1. The bonded cube: E_eff from the stress-strain slope, ν_eff from the lateral strain.
  CompressionJobSpec cs =
      base_spec(PackingShape::Cube, o.cube_half, 0, o.gmin, o.gmax, o.porosity, au, o.seed, o);
  cs.loading.peak_displacement = 0.01 * 2 * o.cube_half;  // 1 % strain
  cs.loading.unload = false;
  cs.loading.speed = o.speed / 5;  // a smaller body, as slow in units of its crossing time
  auto t0 = Clock::now();
  CompressionJob cube(cs, settings(o));
  const double cube_pack_s = seconds_since(t0);
  RunResult rc = run(cube, cs.loading.peak_displacement / (2 * cs.loading.speed) / 100, o, true,
                     cs.loading.peak_displacement);
  const double edge = 2 * o.cube_half, area = edge * edge;
  std::vector<double> eps, sig;
  for (const auto& p : rc.curve)
    if (p.h >= 0.5 * cs.loading.peak_displacement) {  // past the seating of the platens
      eps.push_back(p.h / edge);
      sig.push_back(units::to_GPa(units::nN(p.f)) / area);  // nN/nm² in GPa
    }
  const double E_platen_GPa = fit_line(eps, sig).first;
  // The strain inside the cube, free of the platens' seating: slopes of the displacement from
  // half the peak to the peak against the position, in z (axial) and in x, y (lateral).
  std::vector<double> X, dX, Y, dY, Z, dZ;
  // Interior grains only (within 60 % of the half-edge of the centre in every direction): the
  // layers the packing walls ordered at the faces are looser and would soften the average.
  Vec3 centre = Vec3::Zero();
  for (const Vec3& x : rc.x0) centre += x;
  centre /= static_cast<double>(rc.x0.size());
  for (std::size_t i = 0; i < rc.x0.size(); ++i) {
    if ((rc.x0[i] - centre).cwiseAbs().maxCoeff() > 0.6 * o.cube_half) continue;
    X.push_back(rc.x0[i].x());
    dX.push_back(rc.x_peak[i].x() - rc.x_half[i].x());
    Y.push_back(rc.x0[i].y());
    dY.push_back(rc.x_peak[i].y() - rc.x_half[i].y());
    Z.push_back(rc.x0[i].z());
    dZ.push_back(rc.x_peak[i].z() - rc.x_half[i].z());
  }
  const double d_eps_z = -fit_line(Z, dZ).first;  // compression positive
  const double d_eps_lat = 0.5 * (fit_line(X, dX).first + fit_line(Y, dY).first);
  const double d_sigma = units::to_GPa(units::nN(rc.curve.back().f - rc.f_half)) / area;  // GPa
  // The platens' figure is the modulus used below: the internal one rests on displacements of
  // a few grains' thermal-like jitter and scatters by ±15 % between packings.
  const double E_internal_GPa = d_sigma / d_eps_z;
  const double E_eff_GPa = E_platen_GPa;
  const double nu_eff = d_eps_lat / d_eps_z;
  std::printf(
      "bonded cube: edge %.1f nm, %ld grains, %ld bonds, porosity %.3f, packed in %.1f s, "
      "loaded in %.1f s (%ld steps, dt %.3f ps)\n",
      edge, rc.grains, rc.bonds, rc.porosity, cube_pack_s, rc.run_s, rc.steps, rc.dt);
  std::printf(
      "  E_eff = %.2f GPa from the platen displacement (%.2f GPa from the interior "
      "strain; bond material E = %.0f GPa), nu_eff = %.3f\n",
      E_eff_GPa, E_internal_GPa, E_bond_GPa, nu_eff);
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
  std::printf("%4s %7s %7s %9s %8s %8s %9s %9s\n", "seed", "grains", "poros", "exponent",
              "C(n=1.5)", "C/rigid", "pack [s]", "run [s]");
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
      made = std::make_unique<CompressionJob>(carve_sphere(pack_grains(bulk), o.radius), ss,
                                              settings(o));
    } else {
      made = std::make_unique<CompressionJob>(ss, settings(o));
    }
    CompressionJob& sphere = *made;
    const double pack_s = seconds_since(t0);
    RunResult r = run(sphere, ss.loading.peak_displacement / (2 * o.speed) / 200, o, false);
    std::vector<double> lx, ly, c;
    for (const auto& p : r.curve) {
      const double hr = p.h / o.radius;
      if (hr < lo || hr > hi || p.f <= 0) continue;
      const double fn = units::to_GPa(units::nN(p.f)) / (o.radius * o.radius * E_eff_GPa);
      lx.push_back(std::log(hr));
      ly.push_back(std::log(fn));
      c.push_back(fn / std::pow(hr, 1.5));
    }
    const double n = fit_line(lx, ly).first;
    const double C = std::accumulate(c.begin(), c.end(), 0.0) / c.size();
    exps.push_back(n);
    Cs.push_back(C);
    std::printf("%4lu %7ld %7.3f %9.3f %8.4f %8.3f %9.1f %9.1f\n",
                static_cast<unsigned long>(ss.particle.seed), r.grains, r.porosity, n, C,
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
    RunResult r = run(job, s.loading.peak_displacement / (2 * o.speed) / 200, o, false);
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
