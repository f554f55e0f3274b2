#include "common/demand.hpp"

#include <cstdio>
#include <cstdlib>

namespace mcg::detail {

void demand_failed(const char* condition, const char* file, int line) noexcept {
  std::fprintf(stderr, "mcg: internal error: %s failed at %s:%d (a bug in mcg: please report it)\n", condition,
               file, line);
  std::abort();
}

}  // namespace mcg::detail
