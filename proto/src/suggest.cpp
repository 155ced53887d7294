// Nearest allowed name to a misspelt one, by optimal string alignment distance.
#include "mdem/suggest.h"

#include <algorithm>
#include <cctype>

namespace mdem {

std::size_t edit_distance(std::string_view a, std::string_view b) {
  const auto same = [](char x, char y) {
    return std::tolower(static_cast<unsigned char>(x)) ==
           std::tolower(static_cast<unsigned char>(y));
  };
  // d[i][j]: edits between a[0, i) and b[0, j); three rows suffice for the swap.
  std::vector<std::size_t> prev2(b.size() + 1), prev(b.size() + 1), row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = same(a[i - 1], b[j - 1]) ? 0 : 1;
      row[j] = std::min({prev[j] + 1, row[j - 1] + 1, prev[j - 1] + cost});
      if (i > 1 && j > 1 && same(a[i - 1], b[j - 2]) && same(a[i - 2], b[j - 1]))
        row[j] = std::min(row[j], prev2[j - 2] + 1);
    }
    std::swap(prev2, prev);
    std::swap(prev, row);
  }
  return prev[b.size()];
}

std::optional<std::string> closest_name(std::string_view given,
                                        const std::vector<std::string>& allowed) {
  const std::size_t prefix = given.rfind("--", 0) == 0 ? 2 : 0;
  const std::size_t limit = std::max<std::size_t>(1, (given.size() - prefix) / 3);
  std::optional<std::string> best;
  std::size_t best_distance = limit + 1;
  bool tie = false;
  for (const std::string& name : allowed) {
    const std::size_t d = edit_distance(given, name);
    if (d < best_distance) {
      best = name;
      best_distance = d;
      tie = false;
    } else if (d == best_distance && best && *best != name) {
      tie = true;
    }
  }
  if (!best || tie || best_distance == 0) return std::nullopt;
  return best;
}

std::string did_you_mean(std::string_view given, const std::vector<std::string>& allowed) {
  const auto name = closest_name(given, allowed);
  return name ? "; did you mean " + *name + "?" : "";
}

}  // namespace mdem
