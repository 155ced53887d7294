#pragma once
// A packed nanocrystalline particle (thesis §6.2, scenes.md compression): grains with radii drawn
// uniformly in [r_min, r_max] placed at random, seeded, in a spherical shell (outer radius
// r_outer, inner r_inner; 0 for a full sphere) or a cube, packed by linear repulsion with local
// damping 0.7 inside walls (two spherical walls, or six platens for the cube) until equilibrated,
// then returned with the list of touching pairs to bond. The radii grow from half size while the
// packing relaxes (radius expansion); grains too few to jam at the container's size are jammed
// by closing the walls in until the mean overlap is 3 % of a radius (see grain_packing.cpp). The
// caller removes the walls by not adding them again. Same seed and thread count: bit-identical
// grains on every machine.
#include <cstdint>
#include <memory>
#include <vector>

#include "mdem/core/elements.h"
#include "mdem/io/state_io.h"
#include "mdem/scene/grain.h"

namespace mdem {

class System;

enum class PackingShape : std::uint8_t { Shell = 0, Cube = 1 };

struct PackingSpec {
  PackingShape shape = PackingShape::Shell;
  double r_outer = 0;                       // shell: outer radius (nm); cube: half the edge
  double r_inner = 0;                       // shell only: inner radius (0: a full sphere)
  double grain_r_min = 0, grain_r_max = 0;  // nm, 0 < min ≤ max
  // The grain count is the one whose grain volume fills (1 − porosity) of the container; the
  // porosity reached after packing (overlaps counted once) is measured and reported.
  double target_porosity = 0.4;
  GrainMaterial material;
  std::uint64_t seed = 1;
  int threads = 0;
  // Equilibrium: the mean unbalanced force over the mean contact force below this.
  double tolerance = 1e-3;
  long max_steps = 200000;
};

struct PackedParticle {
  Elements grains;                                                // at rest, no walls
  std::vector<std::pair<std::uint32_t, std::uint32_t>> touching;  // i < j, centres < R_i + R_j
  double porosity = 0;          // measured: 1 − (volume inside grains)/(container volume)
  double porosity_error = 0;    // its standard error (Monte Carlo over seeded points)
  long rattlers = 0;            // grains that touch nothing (left unbonded)
  long steps = 0;               // packing steps
  double unbalanced_ratio = 0;  // at the end
  // How far the walls moved in (nm; the inner wall of a shell moved out as far) to jam grains
  // that were loose at the container's size (see pack_grains). 0 when they jammed by themselves.
  double wall_shift = 0;
};

// Packs to the end: GrainPacker advanced until done. Throws std::invalid_argument naming the
// field for an impossible spec (radii, porosity outside (0.2, 0.95), a grain larger than the
// shell's thickness, more than 5 million grains), and std::runtime_error when max_steps pass
// without equilibrium.
PackedParticle pack_grains(const PackingSpec& spec);

// The packing as a process a run loop advances a little at a time (a job's packing stage): the
// same operations in the same order as one pack_grains call, so the same spec and thread count
// give the same particle bit for bit however the work is split, cancelled or checkpointed.
class GrainPacker {
 public:
  // Validates the spec, draws and places the grains, builds the packing system (grains, walls,
  // local damping 0.7); the relaxation has not started. Throws as pack_grains.
  explicit GrainPacker(const PackingSpec& spec);
  ~GrainPacker();
  GrainPacker(const GrainPacker&) = delete;
  GrainPacker& operator=(const GrainPacker&) = delete;

  // Puts the packing system back as built when nothing has run yet (a caller may have
  // initialized it in between, e.g. to read its step, which recomputes dt at the shrunk radii);
  // does nothing once the packing has started.
  void begin();
  bool done() const;
  // Advances by whole units of the packing (10 steps, or a check of the equilibrium) until at
  // least `steps` more steps are done or the packing is done; a unit may overrun the request by
  // up to 9 steps. Throws std::runtime_error when max_steps pass without equilibrium.
  void advance(long steps);
  long steps() const;  // packing steps so far
  const PackingSpec& spec() const;
  // The packing's own system (grains and walls), for progress and inspection.
  System& system();
  const PackedParticle& result() const;  // once done()

  // Between units: the packing's progress and, while it runs, its system; once done, the packed
  // particle. load_state throws CheckpointError for a checkpoint of another spec.
  void save_state(StateWriter& w) const;
  void load_state(StateReader& r);

  struct Impl;  // defined in grain_packing.cpp

 private:
  std::unique_ptr<Impl> impl_;
};

// Connected components of a graph of n vertices with the given edges (union–find): used for the
// fragment count of a bonded particle.
long connected_components(std::size_t n,
                          const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges);

}  // namespace mdem
