// Edit distance between short names, for "did you mean" suggestions.
#pragma once

#include <cstddef>
#include <string_view>

namespace mcg {

/// Optimal string alignment distance of a and b: insertions, deletions, substitutions and swaps
/// of neighbours each cost one (the names compared are a few characters long).
std::size_t edit_distance(std::string_view a, std::string_view b);

}  // namespace mcg
