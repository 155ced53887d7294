#pragma once
// What a twisted rope reports (scenes.md "twist", thesis §4.2–4.3): twist angle of the outer
// tubes, end shift angle, radius and length, the topological charge Q of the mid cross-section and
// a morphology label. Every rule here is documented in docs/twist.md.
#include <string_view>
#include <vector>

#include "mdem/core/elements.h"
#include "mdem/integrate/system.h"
#include "mdem/scene/hex_rope.h"

namespace mdem {

class StateWriter;
class StateReader;

// The rope's axis: through the mass centroids of the two grips (el's groups kRopeGripA and
// kRopeGripB), from grip a to grip b.
struct RopeAxis {
  Vec3 origin = Vec3::Zero();  // midpoint of the two grip centroids
  Vec3 dir = Vec3::UnitZ();
  double length = 0;  // distance between the grip centroids (nm)
};
RopeAxis rope_axis(const Elements& el, const Rope& rope);

// Topological charge Q = Σ (6 − m) over internal tubes (thesis Eq. 24). `centres[i]` is where
// tube i crosses the section; `tubes[j]` a polyline along tube j near the section. m counts the
// tubes whose polyline comes closer to centre i than `neighbor_distance` (the thesis takes the
// smallest distance between elements of two helical tubes). Only `internal[i]` tubes contribute.
struct SectionCharge {
  int charge = 0;
  std::vector<int> coordination;  // per tube (all tubes, internal or not)
};
SectionCharge topological_charge(const std::vector<Vec3>& centres,
                                 const std::vector<std::vector<Vec3>>& tubes,
                                 const std::vector<bool>& internal, double neighbor_distance);
// The neighbour distance for a lattice spacing d: halfway between the first (d) and second
// (√3·d) neighbour shells.
double charge_neighbor_distance(double spacing);
// Q of the rope's mid cross-section (the plane through RopeAxis::origin normal to its dir).
SectionCharge rope_topological_charge(const Elements& el, const Rope& rope, const RopeAxis& axis);

enum class Morphology { Straight, Spindle, BirdCage, Helix, Separated };
std::string_view morphology_name(Morphology m);

struct RopeShape {
  double twist_angle_deg = 0;   // mean tilt of the outer tubes from the axis, central half
  double radius = 0;            // largest distance of a segment centre from the axis, central half
  double core_void_radius = 0;  // largest empty circle about the local axis, central half (nm)
  double axis_deviation = 0;    // largest distance of a cross-section centroid from the axis
  int clusters = 0;             // groups of tubes in vdW contact
};
RopeShape rope_shape(const Elements& el, const Rope& rope, const RopeAxis& axis);

// The label, by the first rule that holds: separated (tubes fall into more than one group in
// contact), helix (a cross-section centroid strays from the axis by more than half the initial
// radius, and at least 2 spacings), bird cage (an empty core wider than 1.2 spacings, which no
// as-built single vacancy reaches), spindle (outer tubes tilted by 5° or more), else straight.
Morphology classify_morphology(const RopeShape& shape, const Rope& rope);

// The end-to-end shift angle: rotation of grip b relative to grip a about the axis since the
// reference state, continuous past ±180° when sampled often enough (less than a half turn between
// samples).
class ShiftAngle {
 public:
  ShiftAngle(const Elements& reference, const Rope& rope);
  double update(const Elements& el, const RopeAxis& axis);  // radians
  double angle() const { return angle_; }
  // The unwrapped angle (the reference offsets come from the job's build), for checkpoints.
  void save_state(StateWriter& w) const;
  void load_state(StateReader& r);

 private:
  double grip_rotation(const Elements& el, const std::vector<std::size_t>& grip,
                       const std::vector<Vec3>& ref, const RopeAxis& axis) const;
  std::vector<Vec3> ref_a_, ref_b_;  // offsets from each grip's centroid, as built
  double angle_ = 0;
};

// The shift angle sampled every `every` steps before the force evaluation (counted by the
// system, so a job restored from a checkpoint samples at the same steps): unwrapping needs
// samples less than a half turn apart. An observer of a job's stage.
class ShiftAngleSampler final : public Updater {
 public:
  ShiftAngleSampler(const Elements& reference, const Rope& rope, long every = 10);
  void apply(System& sys, double t) override;
  bool reads_forces() const override { return false; }   // positions and orientations only
  bool applies_loads() const override { return false; }  // an observer
  // Samples now (a report between samples); the angle in radians.
  double sample(const Elements& el);
  double angle() const { return value_; }
  void save_state(StateWriter& w) const override;
  void load_state(StateReader& r) override;

 private:
  ShiftAngle shift_;
  const Rope* rope_;
  long every_;
  double value_ = 0;  // the last sample (radians)
};

}  // namespace mdem
