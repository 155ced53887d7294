#pragma once
// The pore-size distribution of a film from its 2D projection on xy (tensile.md §3.4, thesis
// L752): a window, a raster of material and void pixels, and the pores as 4-connected void
// components that do not touch the window's edge. Definitions and tests: docs/tensile.md.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "mdem/core/cnt.h"
#include "mdem/core/elements.h"

namespace mdem {

struct Window2D {
  double x_lo = 0, x_hi = 0, y_lo = 0, y_hi = 0;  // nm
};

// The window between the lo_pct-th and hi_pct-th percentiles (observe/percentile.h) of the
// centres' x and of their y, shrunk by `shrink` of its side on each edge (tensile.md: 2, 98, 5 %).
// Throws std::invalid_argument for no centres, a non-finite centre, or a window without area.
Window2D percentile_window(std::span<const Vec3> centres, double lo_pct = 2, double hi_pct = 98,
                           double shrink = 0.05);

// What is projected: CNT segments (centre and unit axis) and NPs (centre and radius).
struct ProjectedFrame {
  std::vector<Vec3> segment_centre, segment_axis;
  std::vector<Vec3> np_centre;
  std::vector<double> np_radius;
};
// The CNT segments and NPs of el (other kinds are left out).
ProjectedFrame projected_frame(const Elements& el);

struct RasterSettings {
  double pixel = 0.5;                              // p (nm)
  double footprint = cnt::kRadius;                 // r_d (nm): material reach of a segment's axis
  double half_length = 0.5 * cnt::kSegmentLength;  // a segment's axis is c ± half_length·b
};

// Pixels of side p from the window's lower corner: nx = ⌊(x_hi − x_lo)/p⌋ columns and likewise
// ny rows (a remainder strip narrower than p is left out). Pixel (ix, iy) has its centre at
// (x_lo + (ix + ½)p, y_lo + (iy + ½)p) and is material when that centre lies within r_d of the
// xy projection of a segment's axis line segment, or within r_NP of an NP centre's projection.
struct Raster {
  Window2D window;
  double pixel = 0;
  int nx = 0, ny = 0;
  std::vector<std::uint8_t> material;  // row-major: index iy·nx + ix; 1 = material
  bool is_material(int ix, int iy) const { return material[iy * nx + ix] != 0; }
};

// Throws std::invalid_argument for non-finite input, a non-positive pixel, footprint or half
// length, a window narrower than one pixel, or unequal segment or NP arrays.
Raster rasterize(const ProjectedFrame& frame, const Window2D& window, const RasterSettings& s = {});

// Histogram bins of pore area (nm²): [0.25, 10), [10, 50), [50, 100), [100, 200), [200, 300),
// [300, ∞).
inline constexpr std::array<double, 6> kPoreBinLower = {0.25, 10, 50, 100, 200, 300};

struct PoreStats {
  std::vector<double> areas;        // each kept pore's area (nm²), largest first
  std::array<long, 6> histogram{};  // pores per bin of kPoreBinLower
  long below_first_bin = 0;         // kept pores under 0.25 nm² (only with pixels under 0.5 nm)
  long large = 0;                   // pores > large_area
  long edge_discarded = 0;          // void components touching the window's edge
  double void_fraction = 0;         // void pixels / all pixels (edge components included)
  double weighted_mean_area = 0;    // Σ a² / Σ a over kept pores (0 without pores)
};

// Pores: the 4-connected components of void pixels (material connects diagonally, void does
// not); components touching the raster's edge are discarded. Area = pixel count × p².
PoreStats pore_stats(const Raster& raster, double large_area = 200.0);

}  // namespace mdem
