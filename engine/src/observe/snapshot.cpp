#include "mdem/observe/snapshot.h"

#include "mdem/core/units.h"

namespace mdem {

Snapshot capture_snapshot(const Elements& el, long step, double time_ps) {
  Snapshot s;
  s.step = step;
  s.time_ps = time_ps;
  // In tag order, whatever the elements' memory order (IntegratorSettings::memory_order).
  const std::vector<std::uint32_t> order = el.tag_order();
  const std::size_t n = el.size();
  s.x.resize(n);
  s.q.resize(n);
  s.v.resize(n);
  s.radius.resize(n);
  s.kind.resize(n);
  s.tube.resize(n);
  s.index.resize(n);
  std::vector<double> force(n), torque(n);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = order[k];
    s.x[k] = el.x[i];
    s.q[k] = el.q[i];
    s.v[k] = el.v[i];
    s.radius[k] = el.radius[i];
    s.kind[k] = static_cast<std::int32_t>(el.kind[i]);
    s.tube[k] = el.tube[i];
    s.index[k] = el.index[i];
    force[k] = units::to_nN(el.f[i].norm());
    torque[k] = units::to_nNnm(el.t[i].norm());
  }
  s.scalars.emplace_back("force_nN", std::move(force));
  s.scalars.emplace_back("torque_nNnm", std::move(torque));
  return s;
}

}  // namespace mdem
