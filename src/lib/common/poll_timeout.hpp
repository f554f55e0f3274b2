// poll(2)'s timeout from seconds, written once for every wait on a descriptor.
#pragma once

#include <algorithm>
#include <cmath>

namespace mcg {

/// Milliseconds for poll(2): timeout_ms = ceil(timeout_s * 1000), rounded up so that a wait never
/// ends before its deadline; 0 (do not wait) for a timeout that is not positive or is NaN; at most
/// one hour, so that any double fits the int.
inline int poll_timeout_ms(double timeout_s) {
  if (!(timeout_s > 0.0)) return 0;
  return static_cast<int>(std::min(std::ceil(timeout_s * 1e3), 3.6e6));
}

}  // namespace mcg
