#include <stdexcept>

#include "mdem/core/capacity_bytes.h"
#include "mdem/force/force_model.h"

namespace mdem {

void ForceSink::resize(std::size_t n, int n_threads, bool with_damping, bool with_damping_torque) {
  force_.assign(n_threads, std::vector<Vec3>(n, Vec3::Zero()));
  torque_.assign(n_threads, std::vector<Vec3>(n, Vec3::Zero()));
  if (with_damping)
    damp_force_.assign(n_threads, std::vector<Vec3>(n, Vec3::Zero()));
  else
    damp_force_.clear();
  if (with_damping && with_damping_torque)
    damp_torque_.assign(n_threads, std::vector<Vec3>(n, Vec3::Zero()));
  else
    damp_torque_.clear();
  energy_.assign(n_threads, EnergyTally{});
  zeroed_ = true;
}

Vec3* ForceSink::damping_torque(int thread) {
  if (damp_torque_.empty())
    throw std::logic_error(
        "ForceSink: no damping torque buffers (a dissipative model that writes torques must "
        "return true from damping_torques())");
  return damp_torque_[thread].data();
}

void ForceSink::clear() {
  for (auto& e : energy_) e = EnergyTally{};
  if (zeroed_) {
    zeroed_ = false;  // the models write next
    return;
  }
  const int nt = threads();
  const std::size_t n = nt ? force_[0].size() : 0;
  const bool damp = has_damping(), damp_t = has_damping_torque();
#pragma omp parallel for schedule(static) if (static_cast <long>(n) >= kParallelMinItems)
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < nt; ++k) {
      force_[k][i].setZero();
      torque_[k][i].setZero();
      if (damp) damp_force_[k][i].setZero();
      if (damp_t) damp_torque_[k][i].setZero();
    }
  }
}

EnergyTally ForceSink::reduce(std::vector<Vec3>& f, std::vector<Vec3>& t, std::vector<Vec3>& fd,
                              std::vector<Vec3>& td) {
  const int nt = threads();
  const std::size_t n = nt ? force_[0].size() : 0;
  const bool damp = has_damping(), damp_t = has_damping_torque();
#pragma omp parallel for schedule(static) if (static_cast <long>(n) >= kParallelMinItems)
  for (std::size_t i = 0; i < n; ++i) {
    take_one(force_, i, nt, f[i]);
    take_one(torque_, i, nt, t[i]);
    if (damp) {
      take_one(damp_force_, i, nt, fd[i]);
      if (damp_t)
        take_one(damp_torque_, i, nt, td[i]);
      else
        td[i].setZero();
    }
  }
  zeroed_ = true;
  return energy_total();
}

EnergyTally ForceSink::energy_total() const {
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
