#include "mdem/integrate/respa.h"

namespace mdem {

void RespaSplit::setup(int k, std::size_t n) {
  k_ = k;
  const std::size_t m = on() ? n : 0;  // no buffers when off
  for (auto* a : {&f, &t, &fd, &td}) a->assign(m, Vec3::Zero());
  tally = EnergyTally{};
  tags.clear();
}

void RespaSplit::follow(const Elements& el) {
  if (!on() || tags == el.tag) return;
  std::vector<Vec3> nf(f.size()), nt(f.size()), nfd(f.size()), ntd(f.size());
  for (std::size_t i = 0; i < tags.size(); ++i) {
    const std::size_t j = el.index_of(tags[i]);
    nf[j] = f[i];
    nt[j] = t[i];
    nfd[j] = fd[i];
    ntd[j] = td[i];
  }
  f.swap(nf);
  t.swap(nt);
  fd.swap(nfd);
  td.swap(ntd);
  tags = el.tag;
}

void RespaSplit::add_impulse(std::vector<Vec3>& ef, std::vector<Vec3>& et, std::vector<Vec3>& efd,
                             std::vector<Vec3>& etd, bool damping) const {
  const double k = k_;
  const long n = static_cast<long>(f.size());
#pragma omp parallel for schedule(static) if (n >= kParallelMinItems)
  for (long i = 0; i < n; ++i) {
    ef[i] += k * f[i];
    et[i] += k * t[i];
    if (damping) {
      efd[i] += k * fd[i];
      etd[i] += k * td[i];
    }
  }
}

}  // namespace mdem
