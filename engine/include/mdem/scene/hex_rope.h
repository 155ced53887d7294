#pragma once
// The twisted-rope scene's geometry (scenes.md "twist", thesis Ch. 4): parallel (10,10) tubes on
// a triangular lattice with N hexagonal layers, 3N²−3N+1 sites, optional packing defects (missing
// tubes: points, or rows along a radius over all or part of the length, §4.6), and the grips (the
// end segments of every tube at each end). The rope axis is z, centred on the origin.
#include <Eigen/Core>
#include <cstddef>
#include <string_view>
#include <vector>

#include "mdem/core/elements.h"
#include "mdem/force/contact/anisotropic_vdw.h"

namespace mdem {

using Vec2 = Eigen::Vector2d;

// Sites of a hexagonal cross-section: site 0 is the centre, then ring k = 1..N−1 (6k sites each)
// counter-clockwise from the corner at (k·d, 0).
struct HexLattice {
  int layers = 0;
  double spacing = 0;                       // nm, centre to centre
  std::vector<Vec2> sites;                  // nm
  std::vector<int> ring;                    // 0 = centre
  std::vector<std::vector<int>> neighbors;  // sites at distance d
  std::size_t size() const { return sites.size(); }
};

// 3N² − 3N + 1.
int hex_site_count(int layers);
// Throws std::invalid_argument for layers < 1 or > 50, or a spacing that is not finite and > 0.
HexLattice make_hex_lattice(int layers, double spacing);

// Centre-to-centre spacing at which an infinite triangular lattice of infinite straight parallel
// tubes has its lowest vdW energy (model.md §4 pair law summed over all segment pairs within the
// cutoff; golden-section search to 1e-6 nm).
double lattice_equilibrium_spacing(const VdwParams& p = {});

// A row of missing tubes from the centre outward along `angle_deg`, `width` rows wide, over the
// central `length_fraction` of the rope (1 = the whole length).
struct LineDefect {
  double angle_deg = 0;
  int width = 1;
  double length_fraction = 1;
};
// Sites of a line defect: perpendicular offset from the ray in [−√3/4·d, (width − ½)·√3/2·d),
// projection along the ray ≥ 0 (the centre site included).
std::vector<int> line_defect_sites(const HexLattice& lattice, const LineDefect& defect);

struct RopeSpec {
  int layers = 6;
  int segments = 50;         // per tube; length = segments · T
  double spacing = 0;        // nm; 0 = lattice_equilibrium_spacing()
  std::vector<int> missing;  // point defects: sites without a tube
  std::vector<LineDefect> lines;
  int grip_segments = 1;  // end segments of every tube held by each grip
};

// One tube of the rope (a site whose tube is cut by a partial line defect holds two tubes).
struct RopeTube {
  int site = 0;
  int id = 0;                         // Elements::tube
  std::vector<std::size_t> elements;  // in index order
};

struct Rope {
  HexLattice lattice;
  int segments = 0;
  double length = 0;  // nm, segments · T
  std::vector<RopeTube> tubes;
  // Per site, the elements at each segment index (−1 where a defect removed it).
  std::vector<std::vector<long>> site_elements;
  // Sites that hold a tube at mid-length and have all six lattice neighbours there, as built: the
  // "internal" tubes of the topological charge (thesis §4.2).
  std::vector<bool> internal;
  // Outermost-ring sites that hold a tube over the central half: whose tilt is the twist angle.
  std::vector<int> outer_sites;
  double initial_radius = 0;  // largest distance of a tube centre from the axis (nm)
};

// The rope's grips, declared as element groups (Elements::groups): the grip_segments end
// segments of every tube at the z < 0 end (a) and at the z > 0 end (b).
inline constexpr std::string_view kRopeGripA = "rope.grip_a";
inline constexpr std::string_view kRopeGripB = "rope.grip_b";

// Appends the rope's elements to el, records its tubes and intra-tube bonds in el.topology (one
// open chain per RopeTube, tube ids from 0), and declares the groups kRopeGripA and kRopeGripB.
// Throws std::invalid_argument naming the field for layers outside [1, 50], segments < 2, a
// missing or defect site that does not exist, grip_segments outside [1, segments/2], or a spec
// that leaves no tube.
Rope build_hex_rope(Elements& el, const RopeSpec& spec);

}  // namespace mdem
