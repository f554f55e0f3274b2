// The one way a double becomes an integer (an index, a count, a register value): converting a
// value outside the target's range, or nan, is undefined behaviour, and a count read from input
// sizes work and memory. Every such conversion checks the range first, here.
#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <optional>

#include "common/demand.hpp"

namespace mcg {

/// 2^53: every integer up to it is a double, so bounds up to it compare exactly.
inline constexpr double k_exact_integer_max = 9007199254740992.0;

namespace detail {

template <std::integral Int>
constexpr double lower_bound_of(Int lo) {
  return std::max(static_cast<double>(lo), -k_exact_integer_max);
}

template <std::integral Int>
constexpr double upper_bound_of(Int hi) {
  return std::min(static_cast<double>(hi), k_exact_integer_max);
}

}  // namespace detail

/// `x` as an Int when it is finite and in [lo, hi] (bounds beyond 2^53 count as 2^53), else
/// nullopt. A fraction is cut toward zero: round first where that matters.
template <std::integral Int>
std::optional<Int> to_integer(double x, Int lo, Int hi) {
  if (!(x >= detail::lower_bound_of(lo) && x <= detail::upper_bound_of(hi))) return std::nullopt;
  return static_cast<Int>(x);
}

/// `x` clamped into [lo, hi], then as an Int (an index into a range that a value beyond it
/// means the end of). `x` must not be nan (MCG_DEMAND): the caller has checked its input.
template <std::integral Int>
Int clamp_to_integer(double x, Int lo, Int hi) {
  MCG_DEMAND(!std::isnan(x));
  return static_cast<Int>(std::clamp(x, detail::lower_bound_of(lo), detail::upper_bound_of(hi)));
}

}  // namespace mcg
