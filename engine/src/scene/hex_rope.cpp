#include "mdem/scene/hex_rope.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "mdem/core/cnt.h"
#include "mdem/scene/tube_builder.h"

namespace mdem {
namespace {

// Unit vector of lattice direction k (60° apart).
Vec2 lattice_dir(int k) {
  const double a = k * std::numbers::pi / 3.0;
  return {std::cos(a), std::sin(a)};
}

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

// Energy per segment of a tube in an infinite lattice of infinite parallel tubes at spacing d.
double lattice_energy_per_segment(const VdwConstants& k, double d) {
  const double T = k.p.segment_length, rc = k.p.cutoff();
  const Vec3 b = Vec3::UnitZ();
  const int m = static_cast<int>(std::ceil(rc / (0.8 * d))) + 1;
  const int kmax = static_cast<int>(std::ceil(rc / T)) + 1;
  double e = 0;
  for (int i = -m; i <= m; ++i)
    for (int j = -m; j <= m; ++j) {
      if (i == 0 && j == 0) continue;
      const Vec2 p = d * (i * lattice_dir(0) + j * lattice_dir(1));
      if (p.norm() > rc) continue;
      for (int s = -kmax; s <= kmax; ++s)
        e += vdw_pair(k, Vec3::Zero(), b, Vec3(p.x(), p.y(), s * T), b).energy;
    }
  return 0.5 * e;  // each pair shared by two segments
}

}  // namespace

int hex_site_count(int layers) { return 3 * layers * layers - 3 * layers + 1; }

HexLattice make_hex_lattice(int layers, double spacing) {
  require(layers >= 1 && layers <= 50, "layers must be in [1, 50], got " + std::to_string(layers));
  require(std::isfinite(spacing) && spacing > 0, "lattice spacing must be finite and > 0 nm");
  HexLattice L;
  L.layers = layers;
  L.spacing = spacing;
  L.sites.push_back(Vec2::Zero());
  L.ring.push_back(0);
  for (int k = 1; k < layers; ++k)
    for (int side = 0; side < 6; ++side)
      for (int j = 0; j < k; ++j) {
        L.sites.push_back(spacing * (k * lattice_dir(side) + j * lattice_dir(side + 2)));
        L.ring.push_back(k);
      }
  L.neighbors.resize(L.size());
  for (std::size_t a = 0; a < L.size(); ++a)
    for (std::size_t b = 0; b < L.size(); ++b)
      if (a != b && std::abs((L.sites[a] - L.sites[b]).norm() - spacing) < 1e-6 * spacing)
        L.neighbors[a].push_back(static_cast<int>(b));
  return L;
}

double lattice_equilibrium_spacing(const VdwParams& p) {
  const VdwConstants k(p);
  double a = 1.5, b = 2.0;
  const double g = (std::sqrt(5.0) - 1) / 2;
  double x1 = b - g * (b - a), x2 = a + g * (b - a);
  double f1 = lattice_energy_per_segment(k, x1), f2 = lattice_energy_per_segment(k, x2);
  while (b - a > 1e-6) {
    if (f1 < f2) {
      b = x2, x2 = x1, f2 = f1;
      x1 = b - g * (b - a);
      f1 = lattice_energy_per_segment(k, x1);
    } else {
      a = x1, x1 = x2, f1 = f2;
      x2 = a + g * (b - a);
      f2 = lattice_energy_per_segment(k, x2);
    }
  }
  return 0.5 * (a + b);
}

std::vector<int> line_defect_sites(const HexLattice& L, const LineDefect& d) {
  require(std::isfinite(d.angle_deg), "line defect angle must be finite");
  require(d.width >= 1, "line defect width must be >= 1 row");
  const double a = d.angle_deg * std::numbers::pi / 180.0;
  const Vec2 along(std::cos(a), std::sin(a)), across(-std::sin(a), std::cos(a));
  const double row = std::sqrt(3.0) / 2.0 * L.spacing, eps = 1e-9 * L.spacing;
  std::vector<int> out;
  for (std::size_t s = 0; s < L.size(); ++s) {
    const double u = L.sites[s].dot(along), v = L.sites[s].dot(across);
    if (u >= -eps && v >= -0.5 * row - eps && v < (d.width - 0.5) * row - eps)
      out.push_back(static_cast<int>(s));
  }
  return out;
}

Rope build_hex_rope(Elements& el, const RopeSpec& spec) {
  require(spec.segments >= 2, "segments must be >= 2, got " + std::to_string(spec.segments));
  require(spec.grip_segments >= 1 && spec.grip_segments <= spec.segments / 2,
          "grip_segments must be in [1, " + std::to_string(spec.segments / 2) + "], got " +
              std::to_string(spec.grip_segments));
  const double d = spec.spacing > 0 ? spec.spacing : lattice_equilibrium_spacing();
  Rope rope;
  rope.lattice = make_hex_lattice(spec.layers, d);
  rope.segments = spec.segments;
  rope.length = spec.segments * cnt::kSegmentLength;
  const int n = static_cast<int>(rope.lattice.size()), S = spec.segments;

  // Which segments of each site are missing.
  std::vector<std::vector<bool>> gone(n, std::vector<bool>(S, false));
  for (int s : spec.missing) {
    require(s >= 0 && s < n, "missing tube site " + std::to_string(s) +
                                 " does not exist (allowed: 0.." + std::to_string(n - 1) + ")");
    gone[s].assign(S, true);
  }
  for (const LineDefect& line : spec.lines) {
    require(line.length_fraction > 0 && line.length_fraction <= 1,
            "line defect length_fraction must be in (0, 1]");
    const int gap = std::max(1, static_cast<int>(std::lround(line.length_fraction * S)));
    const int first = (S - gap) / 2;
    for (int s : line_defect_sites(rope.lattice, line))
      for (int k = first; k < first + gap; ++k) gone[s][k] = true;
  }

  const Quat q = quat_from_axis(Vec3::UnitZ());
  const double z0 = -0.5 * (S - 1) * cnt::kSegmentLength;
  rope.site_elements.assign(n, std::vector<long>(S, -1));
  int tube_id = 0;
  std::vector<std::uint64_t> grip_a, grip_b;  // tags
  for (int s = 0; s < n; ++s) {
    const Vec2 p = rope.lattice.sites[s];
    RopeTube* tube = nullptr;
    for (int i = 0; i < S; ++i) {
      if (gone[s][i]) {
        tube = nullptr;
        continue;
      }
      if (!tube) {
        rope.tubes.push_back({s, tube_id++, {}});
        tube = &rope.tubes.back();
      }
      const Vec3 x(p.x(), p.y(), z0 + i * cnt::kSegmentLength);
      const std::size_t e = el.add(cnt_segment(x, q, tube->id, i));
      tube->elements.push_back(e);
      rope.site_elements[s][i] = static_cast<long>(e);
      if (i < spec.grip_segments) grip_a.push_back(el.tag[e]);
      if (i >= S - spec.grip_segments) grip_b.push_back(el.tag[e]);
    }
  }
  require(!rope.tubes.empty(), "the defects leave no tube in the rope");
  require(!grip_a.empty() && !grip_b.empty(), "the defects leave a grip without tubes");
  for (const RopeTube& t : rope.tubes) record_cnt_tube(el, t.elements, t.id, false);
  el.groups.add(std::string(kRopeGripA), std::move(grip_a));
  el.groups.add(std::string(kRopeGripB), std::move(grip_b));

  // Internal sites: a tube at mid-length and six lattice neighbours with tubes there too.
  const int mid = S / 2;
  auto present_mid = [&](int s) { return rope.site_elements[s][mid] >= 0; };
  rope.internal.assign(n, false);
  for (int s = 0; s < n; ++s) {
    if (!present_mid(s) || rope.lattice.neighbors[s].size() != 6) continue;
    rope.internal[s] = std::all_of(rope.lattice.neighbors[s].begin(),
                                   rope.lattice.neighbors[s].end(), present_mid);
  }
  for (int s = 0; s < n; ++s) {
    if (rope.lattice.ring[s] != spec.layers - 1) continue;
    bool central = true;
    for (int i = S / 4; i < S - S / 4; ++i) central = central && !gone[s][i];
    if (central) rope.outer_sites.push_back(s);
  }
  for (const RopeTube& t : rope.tubes)
    rope.initial_radius = std::max(rope.initial_radius, rope.lattice.sites[t.site].norm());
  return rope;
}

}  // namespace mdem
