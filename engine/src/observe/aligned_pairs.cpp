#include "mdem/observe/aligned_pairs.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "mdem/neighbor/kind_pairs.h"
#include "mdem/neighbor/neighbor_list.h"
#include "mdem/observe/series_checks.h"

namespace mdem {

namespace {

void check_criteria(const AlignedPairCriteria& c) {
  if (!(c.max_angle_deg > 0 && c.max_angle_deg <= 90))
    throw std::invalid_argument("count_aligned_pairs: max_angle_deg must lie in (0, 90]");
  require_positive(c.max_distance, "count_aligned_pairs", "max_distance");
  require_positive(c.half_length, "count_aligned_pairs", "half_length");
  if (c.exclusion < 0)
    throw std::invalid_argument("count_aligned_pairs: exclusion must not be negative");
}

// Both counts lie within |R| < √(d² + (T/2)²) of segment 1's centre.
double reach(const AlignedPairCriteria& c) { return std::hypot(c.max_distance, c.half_length); }

// The counts over the listed pairs (i < j) of a list that holds every CNT pair within reach(c);
// pairs the criteria exclude are skipped here, whatever the list's own exclusion.
AlignedPairCounts count_listed(const Elements& el, const NeighborList& list,
                               const AlignedPairCriteria& c) {
  AlignedPairCounts n;
  const Domain& domain = list.domain();
  const double cos_max = std::cos(c.max_angle_deg * std::numbers::pi / 180.0);
  const double d2 = c.max_distance * c.max_distance;
  const double reach2 = reach(c) * reach(c);
  const auto& off = list.offsets();
  const auto& nb = list.neighbors();
  for (std::size_t i = 0; i + 1 < off.size(); ++i) {
    if (off[i] == off[i + 1] || el.kind[i] != ElementKind::CntSegment) continue;
    const Vec3 bi = el.axis(i);
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
      const std::size_t j = nb[k];
      const Vec3 r = domain.delta(el.x[i], el.x[j]);
      const double r2 = r.squaredNorm();
      if (!(r2 < reach2) || el.cnt_pair_excluded(i, j, c.exclusion)) continue;
      if (!(std::abs(bi.dot(el.axis(j))) > cos_max)) continue;  // γ ≥ max angle
      if (r2 < d2) ++n.thesis;
      const double axial = r.dot(bi);
      if (std::abs(axial) <= c.half_length && perpendicular(r, bi).squaredNorm() < d2)
        ++n.registry_free;
    }
  }
  return n;
}

}  // namespace

AlignedPairCounts count_aligned_pairs(const Elements& el, const AlignedPairCriteria& c,
                                      const Domain& domain) {
  check_criteria(c);
  if (el.size() < 2) return {};
  NeighborList list(reach(c), 0.0, domain);
  list.set_kinds(KindPairs::of(ElementKind::CntSegment, ElementKind::CntSegment));
  const int exclusion = c.exclusion;
  list.set_exclusion([exclusion](const Elements& e, std::size_t i, std::size_t j) {
    return e.cnt_pair_excluded(i, j, exclusion);
  });
  list.build(el);
  return count_listed(el, list, c);
}

std::optional<AlignedPairCounts> count_aligned_pairs(const Elements& el,
                                                     const NeighborList& candidates,
                                                     const AlignedPairCriteria& c) {
  check_criteria(c);
  if (el.size() < 2) return AlignedPairCounts{};
  const KindPairs kinds = candidates.kinds();
  if (!(candidates.cutoff() >= reach(c)) ||
      !kinds.has(ElementKind::CntSegment, ElementKind::CntSegment) ||
      candidates.needs_rebuild(el) || candidates.offsets().size() != el.size() + 1)
    return std::nullopt;
  return count_listed(el, candidates, c);
}

double stabilisation_time(std::span<const double> t, std::span<const double> count,
                          double fraction) {
  constexpr const char* kWhere = "stabilisation_time";
  require_same_length(t, count, kWhere, "t", "count");
  require_finite_series(t, kWhere, "t");
  require_finite_series(count, kWhere, "count");
  require_increasing(t, kWhere, "t");
  if (!(fraction >= 0 && fraction <= 1))
    throw std::invalid_argument("stabilisation_time: fraction must lie in [0, 1]");
  const double end = count.back();
  const double growth = end - count.front();
  const double sign = growth < 0 ? -1.0 : 1.0;  // a falling count mirrors a rising one
  const double allowed = fraction * std::abs(growth);
  std::size_t k = 0;
  while (sign * (end - count[k]) > allowed) ++k;  // stops at the last sample at the latest
  return t[k];
}

}  // namespace mdem
