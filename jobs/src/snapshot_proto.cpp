#include "mdem/snapshot_proto.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace mdem {

v1::SnapshotData snapshot_to_proto(const Snapshot& s) {
  v1::SnapshotData d;
  d.set_step(s.step);
  d.set_time_ps(s.time_ps);
  const std::size_t n = s.size();
  d.mutable_x()->Reserve(static_cast<int>(3 * n));
  d.mutable_q()->Reserve(static_cast<int>(4 * n));
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) d.add_x(s.x[i][k]);
    for (double c : {s.q[i].w(), s.q[i].x(), s.q[i].y(), s.q[i].z()}) d.add_q(c);
  }
  for (const Vec3& v : s.v)
    for (int k = 0; k < 3; ++k) d.add_v(v[k]);
  for (const SnapshotBond& b : s.bonds) {
    v1::Bond* pb = d.add_bonds();
    pb->set_i(b.i);
    pb->set_j(b.j);
    pb->set_state(static_cast<v1::Bond::State>(b.state));
  }
  d.mutable_radius()->Add(s.radius.begin(), s.radius.end());
  d.mutable_kind()->Add(s.kind.begin(), s.kind.end());
  d.mutable_tube()->Add(s.tube.begin(), s.tube.end());
  d.mutable_index()->Add(s.index.begin(), s.index.end());
  for (const auto& [name, values] : s.scalars) {
    v1::NamedValues* nv = d.add_scalars();
    nv->set_name(name);
    nv->mutable_values()->Add(values.begin(), values.end());
  }
  return d;
}

Snapshot snapshot_from_proto(const v1::SnapshotData& d) {
  const std::size_t n = static_cast<std::size_t>(d.radius_size());
  auto check = [&](const char* field, std::size_t got, std::size_t want) {
    if (got != want)
      throw std::invalid_argument("snapshot at step " + std::to_string(d.step()) + ": " + field +
                                  " holds " + std::to_string(got) + " values, expected " +
                                  std::to_string(want) + " for " + std::to_string(n) + " elements");
  };
  check("x", d.x_size(), 3 * n);
  check("q", d.q_size(), 4 * n);
  check("kind", d.kind_size(), n);
  check("tube", d.tube_size(), n);
  check("index", d.index_size(), n);
  if (d.v_size() != 0) check("v", d.v_size(), 3 * n);
  Snapshot s;
  s.step = d.step();
  s.time_ps = d.time_ps();
  s.x.resize(n);
  s.q.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    s.x[i] = Vec3(d.x(3 * i), d.x(3 * i + 1), d.x(3 * i + 2));
    s.q[i] = Quat(d.q(4 * i), d.q(4 * i + 1), d.q(4 * i + 2), d.q(4 * i + 3));
  }
  if (d.v_size() != 0) {
    s.v.resize(n);
    for (std::size_t i = 0; i < n; ++i) s.v[i] = Vec3(d.v(3 * i), d.v(3 * i + 1), d.v(3 * i + 2));
  }
  for (const v1::Bond& b : d.bonds()) {
    if (b.i() < 0 || b.j() < 0 || static_cast<std::size_t>(std::max(b.i(), b.j())) >= n ||
        !v1::Bond::State_IsValid(b.state()))
      throw std::invalid_argument("snapshot at step " + std::to_string(d.step()) + ": bond " +
                                  std::to_string(b.i()) + "-" + std::to_string(b.j()) +
                                  " names no element of " + std::to_string(n) +
                                  " or has an unknown state");
    s.bonds.push_back({b.i(), b.j(), static_cast<BondState>(b.state())});
  }
  s.radius.assign(d.radius().begin(), d.radius().end());
  s.kind.assign(d.kind().begin(), d.kind().end());
  s.tube.assign(d.tube().begin(), d.tube().end());
  s.index.assign(d.index().begin(), d.index().end());
  for (const v1::NamedValues& nv : d.scalars()) {
    check(("scalar " + nv.name()).c_str(), nv.values_size(), n);
    s.scalars.emplace_back(nv.name(), std::vector<double>(nv.values().begin(), nv.values().end()));
  }
  return s;
}

}  // namespace mdem
