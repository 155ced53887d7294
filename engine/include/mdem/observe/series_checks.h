#pragma once
// Input checks shared by the observables of sampled series (tensile.md §3.4–3.6): each throws
// std::invalid_argument naming the function, the series and what is allowed.
#include <span>
#include <string_view>

namespace mdem {

// `values` is non-empty and every entry finite; else names `where`, `what` and the first bad index.
void require_finite_series(std::span<const double> values, std::string_view where,
                           std::string_view what);
// `a` and `b` have the same length.
void require_same_length(std::span<const double> a, std::span<const double> b,
                         std::string_view where, std::string_view what_a, std::string_view what_b);
// `values` never decreases (equal neighbours allowed).
void require_non_decreasing(std::span<const double> values, std::string_view where,
                            std::string_view what);
// `values` strictly increases (sample times).
void require_increasing(std::span<const double> values, std::string_view where,
                        std::string_view what);
// `value` is finite and positive.
void require_positive(double value, std::string_view where, std::string_view what);

}  // namespace mdem
