// The facts written once in common/: rpm <-> rad/s, trim, the poll(2) timeout.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/poll_timeout.hpp"
#include "common/text.hpp"
#include "common/units.hpp"

namespace mcg {
namespace {

TEST(CommonUnits, OneRevolutionPerSecondIsSixtyRpmAndTwoPiRadPerSecond) {
  EXPECT_DOUBLE_EQ(rad_s_from_rpm(60.0), 2.0 * k_pi);
  EXPECT_DOUBLE_EQ(rpm_from_rad_s(2.0 * k_pi), 60.0);
  EXPECT_DOUBLE_EQ(500.0 * k_rad_s_per_rpm, rad_s_from_rpm(500.0));
  EXPECT_DOUBLE_EQ(52.0 * k_rpm_per_rad_s, rpm_from_rad_s(52.0));
  for (const double rpm : {-720.0, 0.1, 420.0, 12345.6})
    EXPECT_NEAR(rpm_from_rad_s(rad_s_from_rpm(rpm)), rpm, 1e-12 * 1e4);
}

TEST(CommonText, TrimDropsBlanksAndTrimLineAlsoTheCarriageReturn) {
  EXPECT_EQ(trim(" \tkey = 1 \t"), "key = 1");
  EXPECT_EQ(trim("x\r"), "x\r");
  EXPECT_EQ(trim_line("  x \r"), "x");
  EXPECT_EQ(trim_line(" \r "), "");
}

TEST(CommonPollTimeout, RoundsUpAndNeverWaitsOnANonPositiveOrNaNTimeout) {
  EXPECT_EQ(poll_timeout_ms(0.0011), 2);
  EXPECT_EQ(poll_timeout_ms(0.5), 500);
  EXPECT_EQ(poll_timeout_ms(0.0), 0);
  EXPECT_EQ(poll_timeout_ms(-3.0), 0);
  EXPECT_EQ(poll_timeout_ms(std::numeric_limits<double>::quiet_NaN()), 0);
  EXPECT_EQ(poll_timeout_ms(1e12), 3600000);
}

}  // namespace
}  // namespace mcg
