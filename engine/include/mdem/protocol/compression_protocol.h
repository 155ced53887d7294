#pragma once
// Platen compression (thesis §6.2, scenes.md compression): two flat platens, above and below the
// particle along z, move towards each other at a constant speed until their total approach
// reaches the peak displacement h, then return at the same speed to where they started.
#include <memory>
#include <string>

#include "mdem/protocol/protocol.h"

namespace mdem {

struct CompressionLoading {
  double speed = 0;              // each platen's speed (nm/ps); the approach rate is twice it
  double peak_displacement = 0;  // h, total approach of the two platens (nm)
  bool unload = true;            // return to the start after the peak
};

class CompressionProtocol final : public Protocol {
 public:
  // top, bottom: platen element indices (normals −z and +z). Throws std::invalid_argument for a
  // non-positive or non-finite speed or peak.
  CompressionProtocol(CompressionLoading loading, std::size_t top, std::size_t bottom);
  // Sets the platens' prescribed velocities for time t (translation prescribed, rotation fixed).
  // With the system's step dt known, the velocity is the motion law's mean over [t, t + dt], so
  // the platens follow the law exactly at every step. Stateless: nothing to checkpoint.
  void apply(System& sys, double t) override;
  bool reads_forces() const override { return false; }   // platen motion from the time alone
  bool applies_loads() const override { return false; }  // prescribed motion, no loads
  // The platens' element indices, when they are known only once the scene is built.
  void set_platens(std::size_t top, std::size_t bottom);
  double duration() const;   // h/(2·speed) loading, as long again unloading
  double peak_time() const;  // h/(2·speed)
  // Total approach (nm) at time t (exact, from the motion law).
  double displacement(double t) const;
  bool loading(double t) const;                // true before the peak
  std::string phase(double t) const override;  // "loading", "unloading", or "done" after duration()
  const CompressionLoading& params() const { return l_; }

 private:
  CompressionLoading l_;
  std::size_t top_, bottom_;
};

}  // namespace mdem
