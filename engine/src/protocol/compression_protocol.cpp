// Platen compression at constant speed (compression_protocol.h).
#include "mdem/protocol/compression_protocol.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace mdem {

CompressionProtocol::CompressionProtocol(CompressionLoading loading, std::size_t top,
                                         std::size_t bottom)
    : l_(loading), top_(top), bottom_(bottom) {
  if (!std::isfinite(l_.speed) || l_.speed <= 0)
    throw std::invalid_argument("compression loading speed must be finite and > 0 nm/ps, got " +
                                std::to_string(l_.speed));
  if (!std::isfinite(l_.peak_displacement) || l_.peak_displacement <= 0)
    throw std::invalid_argument(
        "compression loading peak_displacement must be finite and > 0 nm, got " +
        std::to_string(l_.peak_displacement));
  set_platens(top, bottom);
}

void CompressionProtocol::set_platens(std::size_t top, std::size_t bottom) {
  if (top == bottom) throw std::invalid_argument("compression platens: top and bottom coincide");
  top_ = top;
  bottom_ = bottom;
}

double CompressionProtocol::peak_time() const { return l_.peak_displacement / (2.0 * l_.speed); }

double CompressionProtocol::duration() const { return l_.unload ? 2.0 * peak_time() : peak_time(); }

double CompressionProtocol::displacement(double t) const {
  const double tp = peak_time();
  if (!(t > 0)) return 0.0;
  if (t < tp) return 2.0 * l_.speed * t;
  if (!l_.unload) return l_.peak_displacement;
  if (t < 2.0 * tp) return std::max(0.0, l_.peak_displacement - 2.0 * l_.speed * (t - tp));
  return 0.0;
}

bool CompressionProtocol::loading(double t) const { return t < peak_time(); }

std::string CompressionProtocol::phase(double t) const {
  if (loading(t)) return "loading";
  if (l_.unload && t < duration()) return "unloading";
  return "done";
}

void CompressionProtocol::apply(System& sys, double t) {
  Elements& el = sys.elements();
  if (top_ >= el.size() || bottom_ >= el.size())
    throw std::logic_error("compression protocol: platen index out of range");
  // The velocity set now is used over the coming step [t, t + dt]: take the mean velocity of the
  // motion law over it, so the platens sit exactly on the law at every step (also across the
  // turn at the peak). Before the step is known (dt = 0, at initialisation) the law's own.
  const double dt = sys.dt();
  double v;  // each platen's speed towards the other
  if (dt > 0) {
    v = 0.5 * (displacement(t + dt) - displacement(t)) / dt;
  } else {
    const double tp = peak_time();
    v = t < tp ? l_.speed : (l_.unload && t < 2.0 * tp) ? -l_.speed : 0.0;
  }
  for (std::size_t p : {top_, bottom_}) {
    auto& dof = el.dof[p];
    for (int k = 0; k < 3; ++k) {
      dof[k] = DofMode::Prescribed;
      dof[k + 3] = DofMode::Fixed;
    }
  }
  el.v_prescribed[top_] = Vec3(0, 0, -v);
  el.v_prescribed[bottom_] = Vec3(0, 0, v);
}

}  // namespace mdem
