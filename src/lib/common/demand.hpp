// Invariants that stay checked in every build type, as Drake's DRAKE_DEMAND: a broken one is a
// bug in mcg, not bad input, so it stops the tool with where it broke instead of throwing
// mcg::Error (and instead of being compiled out by NDEBUG, as assert() is in release builds).
#pragma once

namespace mcg::detail {

/// Prints "mcg: internal error: CONDITION failed at FILE:LINE" on stderr and aborts.
[[noreturn]] void demand_failed(const char* condition, const char* file, int line) noexcept;

}  // namespace mcg::detail

#define MCG_DEMAND(condition) \
  ((condition) ? static_cast<void>(0) : ::mcg::detail::demand_failed(#condition, __FILE__, __LINE__))
