#include "mdem/core/capacity_bytes.h"
#include "mdem/force/force_model.h"

namespace mdem {

void ForceSink::resize(std::size_t n, int n_threads, bool with_damping) {
  force_.assign(n_threads, std::vector<Vec3>(n, Vec3::Zero()));
  torque_.assign(n_threads, std::vector<Vec3>(n, Vec3::Zero()));
  if (with_damping) {
    damp_force_.assign(n_threads, std::vector<Vec3>(n, Vec3::Zero()));
    damp_torque_.assign(n_threads, std::vector<Vec3>(n, Vec3::Zero()));
  } else {
    damp_force_.clear();
    damp_torque_.clear();
  }
  energy_.assign(n_threads, EnergyTally{});
}

void ForceSink::clear() {
  const int nt = threads();
  const std::size_t n = nt ? force_[0].size() : 0;
  const bool damp = has_damping();
#pragma omp parallel for schedule(static) if (static_cast <long>(n) >= kParallelMinItems)
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < nt; ++k) {
      force_[k][i].setZero();
      torque_[k][i].setZero();
      if (damp) {
        damp_force_[k][i].setZero();
        damp_torque_[k][i].setZero();
      }
    }
  }
  for (auto& e : energy_) e = EnergyTally{};
}

EnergyTally ForceSink::reduce(std::vector<Vec3>& f, std::vector<Vec3>& t, std::vector<Vec3>& fd,
                              std::vector<Vec3>& td) const {
  const int nt = threads();
  const std::size_t n = nt ? force_[0].size() : 0;
  const bool damp = has_damping();
#pragma omp parallel for schedule(static) if (static_cast <long>(n) >= kParallelMinItems)
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 fi = force_[0][i], ti = torque_[0][i];
    for (int k = 1; k < nt; ++k) {
      fi += force_[k][i];
      ti += torque_[k][i];
    }
    f[i] = fi;
    t[i] = ti;
    if (damp) {
      Vec3 a = damp_force_[0][i], b = damp_torque_[0][i];
      for (int k = 1; k < nt; ++k) {
        a += damp_force_[k][i];
        b += damp_torque_[k][i];
      }
      fd[i] = a;
      td[i] = b;
    }
  }
  EnergyTally total;
  for (const auto& e : energy_) total += e;
  return total;
}

}  // namespace mdem

namespace mdem {

std::size_t ForceSink::memory_bytes() const {
  return capacity_bytes(force_) + capacity_bytes(torque_) + capacity_bytes(damp_force_) +
         capacity_bytes(damp_torque_) + capacity_bytes(energy_);
}

}  // namespace mdem
