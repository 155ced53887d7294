// Packing a nanocrystalline particle (grain_packing.h).
//
// Reproducibility: one std::mt19937_64 seeded with spec.seed, and our own uniform deviates from
// its raw 64-bit output (the top 53 bits), so radii and positions are the same on every standard
// library; positions are drawn by rejection in a cube (no transcendental functions). The
// relaxation sums forces per thread in a fixed order: the same seed and thread count give
// bit-identical grains.
//
// Method: radius expansion. Grains are placed at random with half their radius (1/8 of their
// volume, so overlaps are rare and shallow), their radii then grow linearly to full size over
// kGrowSteps steps while the packing relaxes under linear repulsion, grain–wall contacts and
// local damping 0.7, and the packing then relaxes at full size until the mean unbalanced force is
// below tolerance × the mean contact force. Placing full-size grains at random instead starts
// from overlaps as deep as a diameter, with huge forces and a long, violent relaxation.
//
// Confinement: a solid fraction below random close packing (about 0.64 for frictionless
// spheres; 40 % porosity is 0.60) does not jam in a container of its nominal size unless walls
// crowd it (small particles do jam): the grains settle into a loose assembly without a
// connected contact network, nothing to bond into one body. The walls then close in (outer in,
// inner out) at kShiftRate·r_max per step until the mean overlap reaches kTargetOverlap of the
// smaller radius; the measured porosity stays that of the nominal container (the grains' volume
// is fixed), and PackedParticle::wall_shift says how far the walls moved. A target of 3 % keeps
// the packing far enough from the jamming point that it settles in a few 10⁴ steps (at 1 % a 50 nm
// sphere took 7·10⁴, at 0.5 % a 25 nm one did not settle in 2·10⁵).
//
// The step is the system's automatic one, from the full-size grains' contacts.
#include "mdem/scene/grain_packing.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

#include "mdem/force/contact/linear_contact.h"
#include "mdem/force/wall/planar_wall.h"
#include "mdem/force/wall/spherical_wall.h"
#include "mdem/integrate/system.h"
#include "mdem/io/state_io.h"

namespace mdem {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kStartScale = 0.5;  // radii start at half size
constexpr long kGrowSteps = 3000;    // steps over which they grow to full size
constexpr long kGrowChunk = 10;      // radii are updated every this many steps
constexpr long kCheckEvery = 100;    // steps between equilibrium checks
// Confinement of loose packings: the mean overlap (over the smaller radius) the walls press the
// grains to, and the walls' speed (fraction of the largest grain radius per step).
constexpr double kTargetOverlap = 0.03;
constexpr double kShiftRate = 2e-4;
constexpr long kMaxGrains = 5000000;
constexpr long kPorosityPoints = 1L << 19;  // Monte Carlo points for the porosity

// Uniform deviates in [0, 1) from the raw 64-bit output: the top 53 bits, exact in a double.
class Uniform {
 public:
  explicit Uniform(std::uint64_t seed) : g_(seed) {}
  double operator()() { return static_cast<double>(g_() >> 11) * 0x1.0p-53; }
  double in(double a, double b) { return a + (b - a) * (*this)(); }

 private:
  std::mt19937_64 g_;
};

[[noreturn]] void bad(const std::string& field, const std::string& what) {
  throw std::invalid_argument("packing " + field + ": " + what);
}

bool finite_positive(double v) { return std::isfinite(v) && v > 0; }

double container_volume(const PackingSpec& s) {
  if (s.shape == PackingShape::Cube) return 8.0 * s.r_outer * s.r_outer * s.r_outer;
  return 4.0 / 3.0 * kPi * (std::pow(s.r_outer, 3) - std::pow(s.r_inner, 3));
}

void validate(const PackingSpec& s) {
  if (s.shape != PackingShape::Shell && s.shape != PackingShape::Cube)
    bad("shape", "must be shell or cube");
  if (!finite_positive(s.r_outer))
    bad("r_outer", "must be finite and > 0 nm, got " + std::to_string(s.r_outer));
  if (s.shape == PackingShape::Shell &&
      (!std::isfinite(s.r_inner) || s.r_inner < 0 || s.r_inner >= s.r_outer))
    bad("r_inner",
        "must be in [0, r_outer) nm (0: a full sphere), got " + std::to_string(s.r_inner));
  if (!finite_positive(s.grain_r_min))
    bad("grain_r_min", "must be finite and > 0 nm, got " + std::to_string(s.grain_r_min));
  if (!std::isfinite(s.grain_r_max) || s.grain_r_max < s.grain_r_min)
    bad("grain_r_max", "must be finite and >= grain_r_min, got " + std::to_string(s.grain_r_max));
  const double thickness = s.shape == PackingShape::Cube ? 2.0 * s.r_outer : s.r_outer - s.r_inner;
  if (2.0 * s.grain_r_max > thickness)
    bad("grain_r_max", "a grain of diameter " + std::to_string(2.0 * s.grain_r_max) +
                           " nm does not fit in the container's thickness " +
                           std::to_string(thickness) + " nm");
  if (!std::isfinite(s.target_porosity) || s.target_porosity <= 0.2 || s.target_porosity >= 0.95)
    bad("target_porosity", "must be in (0.2, 0.95), got " + std::to_string(s.target_porosity));
  if (!finite_positive(s.material.youngs)) bad("material.youngs", "must be finite and > 0");
  if (!finite_positive(s.material.density)) bad("material.density", "must be finite and > 0");
  if (!finite_positive(s.tolerance) || s.tolerance >= 1)
    bad("tolerance", "must be in (0, 1), got " + std::to_string(s.tolerance));
  if (s.max_steps < 1) bad("max_steps", "must be >= 1");
  if (s.threads < 0) bad("threads", "must be >= 0 (0: OpenMP's default)");
  // Mean grain volume for radii uniform in [a, b]: (4/3)π E[R³], E[R³] = (b⁴ − a⁴)/(4(b − a)).
  const double a = s.grain_r_min, b = s.grain_r_max;
  const double mean_r3 = b > a ? (b * b * b * b - a * a * a * a) / (4.0 * (b - a)) : a * a * a;
  const double estimate =
      container_volume(s) * (1.0 - s.target_porosity) / (4.0 / 3.0 * kPi * mean_r3);
  if (estimate > static_cast<double>(kMaxGrains))
    bad("target_porosity", "r_outer and grain radii ask for about " +
                               std::to_string(static_cast<long>(estimate)) +
                               " grains, more than the limit of 5 million");
}

// A uniform point in the region where a grain centre of radius R keeps the grain inside the
// container (rejection in the bounding cube).
Vec3 place(const PackingSpec& s, double R, Uniform& u) {
  if (s.shape == PackingShape::Cube) {
    const double h = s.r_outer - R;
    return Vec3(u.in(-h, h), u.in(-h, h), u.in(-h, h));
  }
  const double hi = s.r_outer - R, lo = s.r_inner > 0 ? s.r_inner + R : 0.0;
  for (;;) {
    const Vec3 p(u.in(-hi, hi), u.in(-hi, hi), u.in(-hi, hi));
    const double r2 = p.squaredNorm();
    if (r2 <= hi * hi && r2 >= lo * lo) return p;
  }
}

// Cell grid over the grains, for the porosity estimate.
class Grid {
 public:
  Grid(const std::vector<Vec3>& x, double half_extent, double cell)
      : lo_(-half_extent),
        cell_(cell),
        n_(std::max(1, static_cast<int>(std::ceil(2.0 * half_extent / cell)))) {
    std::vector<std::uint32_t> count(static_cast<std::size_t>(n_) * n_ * n_ + 1, 0);
    for (const Vec3& p : x) ++count[index(p) + 1];
    std::partial_sum(count.begin(), count.end(), count.begin());
    start_ = count;
    items_.resize(x.size());
    std::vector<std::uint32_t> fill(count.begin(), count.end() - 1);
    for (std::size_t i = 0; i < x.size(); ++i) items_[fill[index(x[i])]++] = i;
  }
  int coord(double v) const { return std::clamp(static_cast<int>((v - lo_) / cell_), 0, n_ - 1); }
  std::size_t index(const Vec3& p) const {
    return (static_cast<std::size_t>(coord(p.z())) * n_ + coord(p.y())) * n_ + coord(p.x());
  }
  // Calls fn(i) for the grains in the cells around p.
  template <class Fn>
  bool any_near(const Vec3& p, Fn fn) const {
    const int cx = coord(p.x()), cy = coord(p.y()), cz = coord(p.z());
    for (int z = std::max(0, cz - 1); z <= std::min(n_ - 1, cz + 1); ++z)
      for (int y = std::max(0, cy - 1); y <= std::min(n_ - 1, cy + 1); ++y)
        for (int x = std::max(0, cx - 1); x <= std::min(n_ - 1, cx + 1); ++x) {
          const std::size_t c = (static_cast<std::size_t>(z) * n_ + y) * n_ + x;
          for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k)
            if (fn(items_[k])) return true;
        }
    return false;
  }

 private:
  double lo_, cell_;
  int n_;
  std::vector<std::uint32_t> start_, items_;
};

// Contact statistics of the packing: grain pairs and grain–wall contacts.
struct ContactStats {
  double force = 0;    // sum of contact force magnitudes (eV/nm)
  double overlap = 0;  // sum of overlaps over the smaller radius
  long count = 0;
  double unbalanced = 0;  // sum of |f| over the grains
  long grains = 0;
  // Mean unbalanced force over the mean contact force (0 when nothing touches: at rest).
  double ratio() const {
    return count && force > 0
               ? (unbalanced / static_cast<double>(grains)) / (force / static_cast<double>(count))
               : 0.0;
  }
  double mean_overlap() const { return count ? overlap / static_cast<double>(count) : 0.0; }
};

// Where the walls are: the spherical walls' radii, or the cube's half edge.
struct WallPlaces {
  double outer = 0, inner = 0;
};

ContactStats contact_stats(const System& sys, const LinearContact& contact, const PackingSpec& s,
                           const WallPlaces& w, std::size_t n_grains) {
  ContactStats st;
  st.grains = static_cast<long>(n_grains);
  const Elements& el = sys.elements();
  const NeighborList* nl = sys.neighbors();
  const auto& off = nl->offsets();
  const auto& nb = nl->neighbors();
  for (std::size_t i = 0; i < n_grains; ++i) {
    st.unbalanced += el.f[i].norm();
    for (std::uint32_t m = off[i]; m < off[i + 1]; ++m) {
      const std::uint32_t j = nb[m];
      if (j >= n_grains) continue;
      const double ri = el.radius[i], rj = el.radius[j];
      const double fc = contact.force(ri, rj, (el.x[j] - el.x[i]).norm());
      if (fc > 0) {
        st.force += fc;
        st.overlap += fc / contact.stiffness(ri, rj) / std::min(ri, rj);
        ++st.count;
      }
    }
  }
  for (std::size_t i = 0; i < n_grains; ++i) {
    const double R = el.radius[i];
    const double k = wall_contact_stiffness(s.material.youngs, R);
    auto wall = [&](double u) {
      if (u > 0) {
        st.force += k * u;
        st.overlap += u / R;
        ++st.count;
      }
    };
    if (s.shape == PackingShape::Cube) {
      for (int a = 0; a < 3; ++a) {
        wall(el.x[i][a] + R - w.outer);
        wall(-el.x[i][a] + R - w.outer);
      }
    } else {
      const double r = el.x[i].norm();
      wall(r + R - w.outer);
      if (w.inner > 0) wall(w.inner - (r - R));
    }
  }
  return st;
}

}  // namespace

long connected_components(std::size_t n,
                          const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges) {
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t a) {
    while (parent[a] != a) {
      parent[a] = parent[parent[a]];  // path halving
      a = parent[a];
    }
    return a;
  };
  long components = static_cast<long>(n);
  for (const auto& [a, b] : edges) {
    if (a >= n || b >= n)
      throw std::invalid_argument("connected_components: edge (" + std::to_string(a) + ", " +
                                  std::to_string(b) + ") names a vertex >= " + std::to_string(n));
    const std::uint32_t ra = find(a), rb = find(b);
    if (ra == rb) continue;
    parent[std::max(ra, rb)] = std::min(ra, rb);
    --components;
  }
  return components;
}

// The packing's state between units. Growth: chunk k of kGrowChunk steps grows the radii to
// scale(k); relaxation: blocks of kCheckEvery steps (run in kGrowChunk-step units; chunks of a
// run do not change its result), each after a check of the equilibrium.
struct GrainPacker::Impl {
  enum class Phase : std::uint8_t { Grow = 0, Relax = 1, Done = 2 };

  PackingSpec s;
  std::vector<double> radius;  // full radii
  std::size_t n = 0;
  System sys;
  LinearContact* contact = nullptr;
  SphericalWallContact* sphere = nullptr;
  double max_shift = 0, shift_per_step = 0;

  Phase phase = Phase::Grow;
  long k = 1;  // next growth chunk
  long steps = 0;
  double scale = kStartScale;
  WallPlaces w;
  bool confining = false;
  long block_len = 0, block_done = 0;  // the relaxation block under way (0: at a check)
  ContactStats st;
  PackedParticle out;

  Impl(const PackingSpec& spec, std::vector<double> radii, Elements el, IntegratorSettings cfg)
      : s(spec), radius(std::move(radii)), n(radius.size()), sys(std::move(el), cfg) {
    contact = sys.add(std::make_unique<LinearContact>(s.material.youngs, s.grain_r_max));
    if (s.shape == PackingShape::Cube)
      sys.add(std::make_unique<PlanarWallContact>(s.material.youngs));
    else
      sphere = sys.add(std::make_unique<SphericalWallContact>(Vec3::Zero(), s.r_outer, s.r_inner,
                                                              s.material.youngs));
    w = WallPlaces{s.r_outer, s.r_inner};
    max_shift = s.shape == PackingShape::Cube ? s.r_outer - s.grain_r_max
                : s.r_inner > 0               ? 0.5 * (s.r_outer - s.r_inner) - s.grain_r_max
                                              : s.r_outer - s.grain_r_max;
    shift_per_step = kShiftRate * s.grain_r_max;
    // The step comes from the full-size grains (the stiffest contacts the packing meets), then
    // the radii shrink for the start.
    sys.initialize();
    set_scale(kStartScale);
    sys.refresh();
  }

  void set_scale(double f) {
    scale = f;
    Elements& e = sys.elements();
    for (std::size_t i = 0; i < n; ++i) e.radius[i] = f * radius[i];
  }

  // Grains too few to jam in the container (a solid fraction below random close packing, ~0.64
  // for frictionless spheres, less near walls) settle into a loose assembly with hardly any
  // contacts: no bonded particle, and an unbalanced-force ratio that converges very slowly. Then
  // the walls move in (the inner one out) at a slow, constant rate until the mean overlap reaches
  // kTargetOverlap of the grain radius, and stop while the packing relaxes; a loss of confinement
  // below half of it starts them again.
  void move_walls(double shift) {
    if (shift > max_shift)
      throw std::runtime_error(
          "packing: the walls moved in by " + std::to_string(shift) +
          " nm without jamming the grains (target_porosity too high for this container?)");
    out.wall_shift = shift;
    w.outer = s.r_outer - shift;
    w.inner = s.r_inner > 0 ? s.r_inner + shift : 0.0;
    if (sphere) {
      sphere->set_radii(w.outer, w.inner);
    } else {
      Elements& e = sys.elements();
      for (std::size_t m = n; m < e.size(); ++m)
        e.x[m] = -e.q[m].toRotationMatrix().col(2) * w.outer;
    }
  }

  bool growing() const { return k * kGrowChunk <= kGrowSteps && steps < s.max_steps; }

  // One unit; returns the steps it ran.
  long unit() {
    if (phase == Phase::Grow) {
      const long chunk = std::min(kGrowChunk, s.max_steps - steps);
      sys.run(chunk);
      steps += chunk;
      const double f = std::min(1.0, static_cast<double>(k * kGrowChunk) / kGrowSteps);
      set_scale(kStartScale + (1.0 - kStartScale) * f);
      sys.refresh();
      ++k;
      if (!growing()) {
        set_scale(1.0);
        sys.refresh();
        confining = false;
        st = contact_stats(sys, *contact, s, w, n);
        phase = Phase::Relax;
      }
      return chunk;
    }
    if (block_len == 0) {  // a check of the equilibrium
      if (st.mean_overlap() < 0.5 * kTargetOverlap) confining = true;
      if (st.mean_overlap() >= kTargetOverlap) confining = false;
      if (!confining && st.ratio() < s.tolerance) {
        finish();
        return 0;
      }
      if (steps >= s.max_steps)
        throw std::runtime_error(
            "packing did not reach equilibrium in max_steps = " + std::to_string(s.max_steps) +
            " steps: unbalanced-force ratio " + std::to_string(st.ratio()) + " (tolerance " +
            std::to_string(s.tolerance) + "), mean overlap " + std::to_string(st.mean_overlap()) +
            " of a radius (raise max_steps or tolerance)");
      block_len = std::min(kCheckEvery, s.max_steps - steps);
      block_done = 0;
    }
    const long c = std::min(kGrowChunk, block_len - block_done);
    if (confining) {
      move_walls(out.wall_shift + shift_per_step * static_cast<double>(c));
      sys.refresh();
    }
    sys.run(c);
    block_done += c;
    if (block_done == block_len) {
      steps += block_len;
      block_len = block_done = 0;
      st = contact_stats(sys, *contact, s, w, n);
    }
    return c;
  }

  void finish() {
    out.steps = steps;
    out.unbalanced_ratio = st.ratio();

    // Touching pairs from the neighbour list (fresh for the final positions).
    const Elements& fin = sys.elements();
    const NeighborList* nl = sys.neighbors();
    std::vector<long> touches(n, 0);
    for (std::size_t i = 0; i < n; ++i)
      for (std::uint32_t m = nl->offsets()[i]; m < nl->offsets()[i + 1]; ++m) {
        const std::uint32_t j = nl->neighbors()[m];
        if (j >= n) continue;
        const double reach = radius[i] + radius[j];
        if ((fin.x[j] - fin.x[i]).squaredNorm() < reach * reach) {
          out.touching.emplace_back(static_cast<std::uint32_t>(std::min<std::size_t>(i, j)),
                                    static_cast<std::uint32_t>(std::max<std::size_t>(i, j)));
          ++touches[i];
          ++touches[j];
        }
      }
    std::sort(out.touching.begin(), out.touching.end());
    out.rattlers = std::count(touches.begin(), touches.end(), 0L);
    for (std::size_t i = 0; i < n; ++i)
      out.grains.add(grain_element(fin.x[i], radius[i], s.material));
    measure_porosity();
    phase = Phase::Done;
  }

  // Porosity by seeded Monte Carlo points in the container (overlaps counted once).
  void measure_porosity() {
    Uniform pu(s.seed ^ 0x9e3779b97f4a7c15ULL);
    const Grid grid(out.grains.x, s.r_outer + s.grain_r_max, s.grain_r_max);
    long inside = 0;
    for (long m = 0; m < kPorosityPoints; ++m) {
      Vec3 p;
      if (s.shape == PackingShape::Cube) {
        p = Vec3(pu.in(-s.r_outer, s.r_outer), pu.in(-s.r_outer, s.r_outer),
                 pu.in(-s.r_outer, s.r_outer));
      } else {
        for (;;) {
          p = Vec3(pu.in(-s.r_outer, s.r_outer), pu.in(-s.r_outer, s.r_outer),
                   pu.in(-s.r_outer, s.r_outer));
          const double r2 = p.squaredNorm();
          if (r2 <= s.r_outer * s.r_outer && r2 >= s.r_inner * s.r_inner) break;
        }
      }
      if (grid.any_near(p, [&](std::uint32_t i) {
            return (out.grains.x[i] - p).squaredNorm() < radius[i] * radius[i];
          }))
        ++inside;
    }
    const double solid = static_cast<double>(inside) / kPorosityPoints;
    out.porosity = 1.0 - solid;
    out.porosity_error = std::sqrt(solid * (1.0 - solid) / kPorosityPoints);
  }
};

namespace {

// Draws the radii and places the grains (one seeded stream), in cell order; then the elements:
// grains, and for a cube its six platens.
GrainPacker::Impl* new_packing(const PackingSpec& s) {
  validate(s);
  Uniform u(s.seed);

  // Radii until the grain volume fills (1 − porosity) of the container: a drawn grain is kept
  // while it brings the total closer to the target.
  const double target = container_volume(s) * (1.0 - s.target_porosity);
  std::vector<double> radius;
  double volume = 0;
  for (;;) {
    const double R = u.in(s.grain_r_min, s.grain_r_max);
    const double v = 4.0 / 3.0 * kPi * R * R * R;
    if (volume + 0.5 * v > target) break;
    radius.push_back(R);
    volume += v;
  }
  if (radius.empty()) bad("r_outer", "the container holds no grain at this porosity");
  const std::size_t n = radius.size();
  std::vector<Vec3> x(n);
  for (std::size_t i = 0; i < n; ++i) x[i] = place(s, radius[i], u);

  // Cell order (z, y, x on a grid of the cutoff): neighbours sit close in memory.
  {
    const double cell = 2.0 * s.grain_r_max;
    const double lo = -s.r_outer;
    auto key = [&](const Vec3& p) {
      const long m = static_cast<long>(std::ceil(2.0 * s.r_outer / cell)) + 1;
      auto c = [&](double v) { return std::clamp(static_cast<long>((v - lo) / cell), 0L, m - 1); };
      return (c(p.z()) * m + c(p.y())) * m + c(p.x());
    };
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), std::size_t{0});
    std::vector<long> keys(n);
    for (std::size_t i = 0; i < n; ++i) keys[i] = key(x[i]);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return keys[a] < keys[b]; });
    std::vector<Vec3> xs(n);
    std::vector<double> rs(n);
    for (std::size_t k = 0; k < n; ++k) {
      xs[k] = x[order[k]];
      rs[k] = radius[order[k]];
    }
    x.swap(xs);
    radius.swap(rs);
  }

  Elements el;
  for (std::size_t i = 0; i < n; ++i) el.add(grain_element(x[i], radius[i], s.material));
  const double grain_mass = el.mass[0];
  if (s.shape == PackingShape::Cube) {
    for (int a = 0; a < 3; ++a)
      for (double side : {-1.0, 1.0}) {
        Vec3 p = Vec3::Zero();
        p[a] = side * s.r_outer;
        add_platen(el, p, -p / s.r_outer, grain_mass, s.r_outer);
      }
  }

  IntegratorSettings cfg;
  cfg.local_damping = 0.7;
  cfg.threads = s.threads;
  cfg.skin = std::max(0.2, 0.3 * s.grain_r_max);
  // Growing radii put in energy no load accounts for: the energy guard would read it as an
  // instability. Finiteness and the per-step motion guard stay on.
  cfg.guard_energy_tolerance = 1e100;
  return new GrainPacker::Impl(s, std::move(radius), std::move(el), cfg);
}

// The spec's fields, so that a checkpoint of another packing is refused.
void put_spec(StateWriter& w, const PackingSpec& s) {
  w.begin("packing spec");
  w.put(s.shape);
  for (double v : {s.r_outer, s.r_inner, s.grain_r_min, s.grain_r_max, s.target_porosity,
                   s.material.youngs, s.material.poisson, s.material.density, s.tolerance})
    w.put(v);
  w.put(s.seed);
  w.put(s.max_steps);
}

void check_spec(StateReader& r, const PackingSpec& s) {
  r.begin("packing spec");
  bool same = r.get<PackingShape>("shape") == s.shape;
  for (double v : {s.r_outer, s.r_inner, s.grain_r_min, s.grain_r_max, s.target_porosity,
                   s.material.youngs, s.material.poisson, s.material.density, s.tolerance})
    same = r.get<double>("sizes, material, tolerance") == v && same;
  same = r.get<std::uint64_t>("seed") == s.seed && same;
  same = r.get<long>("max_steps") == s.max_steps && same;
  if (!same)
    r.fail({},
           "the checkpoint's packing (shape, radii, porosity, material, seed or limits) differs "
           "from this job's");
}

}  // namespace

GrainPacker::GrainPacker(const PackingSpec& spec) : impl_(new_packing(spec)) {}
GrainPacker::~GrainPacker() = default;

bool GrainPacker::done() const { return impl_->phase == Impl::Phase::Done; }

void GrainPacker::advance(long steps) {
  long ran = 0;
  while (!done() && ran < std::max(1L, steps)) ran += impl_->unit();
}

long GrainPacker::steps() const { return impl_->steps + impl_->block_done; }
const PackingSpec& GrainPacker::spec() const { return impl_->s; }
System& GrainPacker::system() { return impl_->sys; }

const PackedParticle& GrainPacker::result() const {
  if (!done()) throw std::logic_error("GrainPacker::result: the packing has not finished");
  return impl_->out;
}

void GrainPacker::save_state(StateWriter& w) const {
  const Impl& p = *impl_;
  put_spec(w, p.s);
  w.begin("packing");
  w.put(p.phase);
  if (p.phase == Impl::Phase::Done) {
    const PackedParticle& o = p.out;
    w.put(o.grains.x);
    std::vector<std::uint32_t> pairs;  // i, j of each touching pair
    for (const auto& [i, j] : o.touching) pairs.insert(pairs.end(), {i, j});
    w.put(pairs);
    for (double v : {o.porosity, o.porosity_error, o.unbalanced_ratio, o.wall_shift}) w.put(v);
    w.put(o.rattlers);
    w.put(o.steps);
    return;
  }
  w.put(p.k);
  w.put(p.steps);
  w.put(p.scale);
  w.put(p.out.wall_shift);
  w.put(p.confining);
  w.put(p.block_len);
  w.put(p.block_done);
  for (double v : {p.st.force, p.st.overlap, p.st.unbalanced}) w.put(v);
  w.put(p.st.count);
  w.put(p.st.grains);
  p.sys.save_state(w);
}

void GrainPacker::load_state(StateReader& r) {
  Impl& p = *impl_;
  check_spec(r, p.s);
  r.begin("packing");
  const auto phase = r.get<Impl::Phase>("phase");
  if (phase > Impl::Phase::Done)
    r.fail("phase", "holds an unknown phase " + std::to_string(static_cast<int>(phase)));
  if (phase == Impl::Phase::Done) {
    PackedParticle o;
    std::vector<Vec3> x;
    r.get(x, "grain positions", p.n);
    std::vector<std::uint32_t> pairs;
    r.get(pairs, "touching");
    if (pairs.size() % 2) r.fail("touching", "holds an odd count of grain indices");
    for (std::size_t m = 0; m < pairs.size(); m += 2) {
      if (!(pairs[m] < pairs[m + 1] && pairs[m + 1] < p.n))
        r.fail("touching", "names a grain pair out of range");
      o.touching.emplace_back(pairs[m], pairs[m + 1]);
    }
    for (double* v : {&o.porosity, &o.porosity_error, &o.unbalanced_ratio, &o.wall_shift})
      *v = r.get<double>("packing figures");
    o.rattlers = r.get<long>("rattlers");
    o.steps = r.get<long>("steps");
    for (std::size_t i = 0; i < p.n; ++i)
      o.grains.add(grain_element(x[i], p.radius[i], p.s.material));
    p.out = std::move(o);
    p.steps = p.out.steps;
    p.phase = phase;
    return;
  }
  p.phase = phase;
  p.k = r.get<long>("growth chunk");
  p.steps = r.get<long>("steps");
  p.scale = r.get<double>("radius scale");
  const double shift = r.get<double>("wall shift");
  p.confining = r.get_bool("confining");
  p.block_len = r.get<long>("block length");
  p.block_done = r.get<long>("block done");
  p.st.force = r.get<double>("contact force");
  p.st.overlap = r.get<double>("overlap");
  p.st.unbalanced = r.get<double>("unbalanced force");
  p.st.count = r.get<long>("contacts");
  p.st.grains = r.get<long>("grains");
  if (p.k < 1 || p.steps < 0 || p.block_len < 0 || p.block_done < 0 || p.block_done > p.block_len ||
      !(shift >= 0 && shift <= p.max_shift))
    r.fail({}, "holds an impossible packing state");
  // The radii and walls as they were, before the system checks its elements against them.
  p.set_scale(p.scale);
  if (shift > 0) p.move_walls(shift);
  p.sys.load_state(r);
}

PackedParticle pack_grains(const PackingSpec& spec) {
  GrainPacker packer(spec);
  while (!packer.done()) packer.advance(std::numeric_limits<long>::max());
  return packer.result();
}

}  // namespace mdem
