#include "mdem/observe/snapshot.h"

#include "mdem/core/units.h"

namespace mdem {

Snapshot capture_snapshot(const Elements& el, long step, double time_ps) {
  Snapshot s;
  s.step = step;
  s.time_ps = time_ps;
  s.x = el.x;
  s.q = el.q;
  s.v = el.v;
  s.radius = el.radius;
  const std::size_t n = el.size();
  s.kind.resize(n);
  std::vector<double> force(n), torque(n);
  for (std::size_t i = 0; i < n; ++i) {
    s.kind[i] = static_cast<std::int32_t>(el.kind[i]);
    force[i] = units::to_nN(el.f[i].norm());
    torque[i] = units::to_nNnm(el.t[i].norm());
  }
  s.tube = el.tube;
  s.index = el.index;
  s.scalars.emplace_back("force_nN", std::move(force));
  s.scalars.emplace_back("torque_nNnm", std::move(torque));
  return s;
}

}  // namespace mdem
