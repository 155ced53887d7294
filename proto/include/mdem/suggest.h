#pragma once
// "did you mean ...?" for a misspelt name (a spec field, a command-line flag): the one allowed
// name closest to it by edits (insert, delete, replace, swap two neighbours; letters compared
// case-blind), when it is close enough to be what was meant.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mdem {

// Edits between a and b (optimal string alignment distance, case-blind).
std::size_t edit_distance(std::string_view a, std::string_view b);

// The allowed name nearest to `given`, if at most max(1, (its length - prefix) / 3) edits away
// (`prefix`: a leading "--" not counted) and nearer than any other; nullopt otherwise.
std::optional<std::string> closest_name(std::string_view given,
                                        const std::vector<std::string>& allowed);

// "; did you mean NAME?" for closest_name's answer, "" for none.
std::string did_you_mean(std::string_view given, const std::vector<std::string>& allowed);

}  // namespace mdem
