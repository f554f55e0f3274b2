// The checked double-to-integer conversions: nan, inf and values beyond the target's range
// (or beyond 2^53, where a double no longer holds every integer) are refused, never cast.
#include "common/checked.hpp"

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <limits>

namespace mcg {
namespace {

constexpr double k_inf = std::numeric_limits<double>::infinity();
constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

TEST(CommonChecked, ToIntegerRefusesWhatDoesNotFit) {
  EXPECT_EQ(to_integer(3.0, 0, 10), 3);
  EXPECT_EQ(to_integer(3.9, 0, 10), 3);  // cut toward zero: the caller rounds
  EXPECT_EQ(to_integer(-32768.0, std::int16_t{-32768}, std::int16_t{32767}), std::int16_t{-32768});
  EXPECT_FALSE(to_integer(32768.0, std::int16_t{-32768}, std::int16_t{32767}));
  EXPECT_FALSE(to_integer(k_nan, 0, 10));
  EXPECT_FALSE(to_integer(k_inf, 0, 10));
  EXPECT_FALSE(to_integer(-k_inf, 0, 10));
  EXPECT_FALSE(to_integer(-1.0, std::size_t{0}, std::size_t{10}));
  EXPECT_FALSE(to_integer(1e300, std::size_t{0}, std::numeric_limits<std::size_t>::max()));
  EXPECT_FALSE(to_integer(1.8446744073709552e19, std::size_t{0}, std::numeric_limits<std::size_t>::max()));
  EXPECT_EQ(to_integer(k_exact_integer_max, std::size_t{0}, std::numeric_limits<std::size_t>::max()),
            std::size_t{1} << 53);
  EXPECT_FALSE(
      to_integer(2.0 * k_exact_integer_max, std::int64_t{0}, std::numeric_limits<std::int64_t>::max()));
}

TEST(CommonChecked, ClampToIntegerSaturates) {
  EXPECT_EQ(clamp_to_integer(1e300, std::size_t{0}, std::size_t{64}), std::size_t{64});
  EXPECT_EQ(clamp_to_integer(-1e300, std::size_t{0}, std::size_t{64}), std::size_t{0});
  EXPECT_EQ(clamp_to_integer(k_inf, std::uint16_t{0}, std::uint16_t{65535}), std::uint16_t{65535});
  EXPECT_EQ(clamp_to_integer(12.0, -5, 5), 5);
  EXPECT_EQ(clamp_to_integer(-2.0, -5, 5), -2);
}

}  // namespace
}  // namespace mcg
