#include "mdem/job/prerelax_criterion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/contact/np_cnt_contact.h"
#include "mdem/force/contact/np_np_contact.h"
#include "mdem/io/state_io.h"

namespace mdem {

namespace {

void check(const char* field, double v, bool positive) {
  if (!std::isfinite(v) || (positive ? !(v > 0) : false)) {
    std::ostringstream m;
    m << "pre-relaxation: " << field << " must be finite" << (positive ? " and > 0" : "")
      << ", got " << v;
    throw std::invalid_argument(m.str());
  }
}

// Smallest D over the pairs of `model`'s neighbour sub-list; d(i, j, r) with r = x_j − x_i
// (minimum image). +inf when the system holds no such model.
template <class Model, class D>
double smallest(const System& sys, const Model* model, D&& d) {
  double lo = std::numeric_limits<double>::infinity();
  if (!model) return lo;
  const NeighborList* list = sys.neighbors(*model);
  if (!list) return lo;
  const Elements& el = sys.elements();
  const auto& off = list->offsets();
  const auto& nb = list->neighbors();
  for (std::size_t i = 0; i + 1 < off.size(); ++i)
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
      const std::size_t j = nb[k];
      lo = std::min(lo, d(i, j, sys.domain().delta(el.x[i], el.x[j])));
    }
  return lo;
}

}  // namespace

PrerelaxCriterion::PrerelaxCriterion(PrerelaxLimits l) : limits_(l) {
  check("cnt_cnt D limit", l.cnt_cnt, false);
  check("np_cnt D limit", l.np_cnt, false);
  check("np_np D limit", l.np_np, false);
  check("max_speed (nm/ps)", l.max_speed, true);
  check("max_time (ps)", l.max_time, true);
  if (l.check_every < 1)
    throw std::invalid_argument("pre-relaxation: check_every must be >= 1 step, got " +
                                std::to_string(l.check_every));
}

PrerelaxStatus PrerelaxCriterion::measure(const System& sys) const {
  const Elements& el = sys.elements();
  PrerelaxStatus s;
  s.checked = true;
  if (const auto* m = sys.find<PairModel<VdwKernel>>()) {
    const VdwConstants k(m->kernel().params());
    s.min_cnt_cnt = smallest(sys, m, [&](std::size_t i, std::size_t j, const Vec3& r) {
      return vdw_separation(k, r, el.axis(i), el.axis(j));
    });
  } else {
    s.min_cnt_cnt = std::numeric_limits<double>::infinity();
  }
  const auto* nc = sys.find<PairModel<NpCntKernel>>();
  s.min_np_cnt = smallest(sys, nc, [&](std::size_t i, std::size_t j, const Vec3& r) {
    const NpCntKernel& k = nc->kernel();
    // r = x_j − x_i; the law takes the NP's and the segment's centres.
    return el.kind[i] == ElementKind::Nanoparticle ? k.separation(Vec3::Zero(), r, el.axis(j))
                                                   : k.separation(r, Vec3::Zero(), el.axis(i));
  });
  const auto* nn = sys.find<PairModel<NpNpKernel>>();
  s.min_np_np = smallest(sys, nn, [&](std::size_t, std::size_t, const Vec3& r) {
    return nn->kernel().separation(r.norm());
  });
  for (std::size_t i = 0; i < el.size(); ++i) s.max_speed = std::max(s.max_speed, el.v[i].norm());
  s.overlap_free = s.min_cnt_cnt >= limits_.cnt_cnt && s.min_np_cnt >= limits_.np_cnt &&
                   s.min_np_np >= limits_.np_np;
  s.slow = s.max_speed < limits_.max_speed;
  return s;
}

bool PrerelaxCriterion::met(const System& sys) {
  last_ = measure(sys);
  return last_.overlap_free && last_.slow;
}

void PrerelaxCriterion::save_state(StateWriter& w) const {
  w.begin("prerelax criterion");
  for (double d : {last_.min_cnt_cnt, last_.min_np_cnt, last_.min_np_np, last_.max_speed}) w.put(d);
  for (bool b : {last_.overlap_free, last_.slow, last_.checked}) w.put(b);
}

void PrerelaxCriterion::load_state(StateReader& r) {
  r.begin("prerelax criterion");
  for (double* d : {&last_.min_cnt_cnt, &last_.min_np_cnt, &last_.min_np_np, &last_.max_speed})
    *d = r.get<double>("last check");
  for (bool* b : {&last_.overlap_free, &last_.slow, &last_.checked}) *b = r.get_bool("last check");
}

std::string PrerelaxCriterion::reason() const {
  std::ostringstream m;
  const PrerelaxStatus& s = last_;
  if (!s.checked) return "not checked yet";
  auto figures = [&] {
    // A kind of pair the film does not have (no NPs: its smallest D is infinite) is not named.
    auto pair = [&](const char* name, double d, double limit, bool first) {
      if (!std::isfinite(d)) return;
      m << (first ? "" : ", ") << name << " " << d << " (limit " << limit << ")";
    };
    m << "smallest D: ";
    pair("CNT-CNT", s.min_cnt_cnt, limits_.cnt_cnt, true);
    pair("NP-CNT", s.min_np_cnt, limits_.np_cnt, !std::isfinite(s.min_cnt_cnt));
    pair("NP-NP", s.min_np_np, limits_.np_np,
         !std::isfinite(s.min_cnt_cnt) && !std::isfinite(s.min_np_cnt));
    if (!std::isfinite(s.min_cnt_cnt) && !std::isfinite(s.min_np_cnt) &&
        !std::isfinite(s.min_np_np))
      m << "no pair in reach";
    m << "; largest speed " << s.max_speed << " nm/ps (limit " << limits_.max_speed << ")";
  };
  if (s.overlap_free && s.slow) {
    m << "settled: no pair on an overlap branch and nothing fast; ";
  } else {
    m << "cap of " << limits_.max_time << " ps reached with "
      << (!s.overlap_free && !s.slow ? "overlaps left and elements still fast"
          : !s.overlap_free          ? "overlaps left"
                                     : "elements still fast")
      << "; ";
  }
  figures();
  return m.str();
}

StopCondition PrerelaxCriterion::stop(std::shared_ptr<PrerelaxCriterion> c, double dt) {
  check("dt (ps)", dt, true);
  const PrerelaxLimits l = c->limits();
  return StopCondition::when(std::move(c), l.check_every,
                             static_cast<long>(std::ceil(l.max_time / dt - 1e-9)));
}

void zero_motion(Elements& el) {
  for (std::size_t i = 0; i < el.size(); ++i) {
    el.v[i].setZero();
    el.w[i].setZero();
  }
}

}  // namespace mdem
