// Unit tests of [controller] sections as board registers: the scale factor, F, refusals.
#include <gtest/gtest.h>

#include <sstream>

#include "common/error.hpp"
#include "config/ini.hpp"
#include "link/connection.hpp"
#include "test_support_error.hpp"

namespace mcg::link {
namespace {

std::vector<std::pair<const RegisterInfo*, double>> regs_of(const std::string& text) {
  std::istringstream in(text);
  return controller_registers(config::Ini::parse(in, "c.ini"));
}

double value_of(const std::vector<std::pair<const RegisterInfo*, double>>& regs, std::string_view name) {
  for (const auto& [reg, value] : regs) {
    if (reg->name == name) return value;
  }
  ADD_FAILURE() << "no " << name;
  return 0.0;
}

std::string error_of(const std::string& text) {
  return test::error_of([&] { regs_of(text); });
}

TEST(LinkControllerIni, ReportPiMapsToBoardUnits) {
  // The report's PI on 512-count/rev errors with 922 counts of full scale: each coefficient
  // scales by (512/60000) (60000/2048) (1000/922) = 0.25 * 1000/922 on the board.
  const auto regs = regs_of(
      "[controller]\ntype = pi\nb = 11.645 -6.987\na = 1 -1\ndt_s = 0.001\ninput_scale = 0.008533333333333333\n"
      "duty_full_scale = 922\n");
  const double k = 0.25 * 1000.0 / 922.0;
  // Unrounded: writing at 2^-12 rounds to round(11.645 k 2^12) = 12933, and load notes it.
  EXPECT_DOUBLE_EQ(value_of(regs, "b0"), 11.645 * k);
  EXPECT_NEAR(value_of(regs, "b0"), 11.645 * k, 0.5 / 4096.0);
  EXPECT_NEAR(value_of(regs, "b1"), -6.987 * k, 0.5 / 4096.0);
  EXPECT_EQ(value_of(regs, "b2"), 0.0);
  EXPECT_EQ(value_of(regs, "coef_frac"), 12.0);  // 3.1575 * 4096 = 12933.3 fits in 16 bits
  EXPECT_EQ(value_of(regs, "mode"), 2.0);
  EXPECT_EQ(regs.front().first->name, "coef_frac");
}

TEST(LinkControllerIni, LargeGainsGetFewerFractionalBits) {
  // kp = 644 (the report's P design in its own units) -> 644 * 0.25 * 1000/922 = 174.6: Q7 holds
  // up to 255.99, Q8 only 127.99.
  const auto regs = regs_of("[controller]\nb = 644\na = 1\n");
  EXPECT_EQ(value_of(regs, "coef_frac"), 7.0);
  EXPECT_NEAR(value_of(regs, "kp"), 644 * 0.25 * 1000.0 / 922.0, 0.5 / 128.0);
  EXPECT_EQ(value_of(regs, "mode"), 1.0);
}

TEST(LinkControllerIni, FixedPointSectionIsWrittenBitForBit) {
  // mcg-design's [fixed_point] for the exact Tustin PI: the board's registers at F = 12.
  const auto regs = regs_of(
      "[controller]\nb = 11.66983 -7.0019\na = 1 -1\n[fixed_point]\nmode = pi\ncoef_frac = 12\n"
      "b0 = 12961\nb1 = -7777\nb2 = 0\n");
  EXPECT_EQ(value_of(regs, "coef_frac"), 12.0);
  EXPECT_EQ(value_of(regs, "b0"), 12961.0 / 4096.0);
  EXPECT_EQ(value_of(regs, "b1"), -7777.0 / 4096.0);
  EXPECT_EQ(value_of(regs, "b2"), 0.0);
  EXPECT_EQ(value_of(regs, "mode"), 2.0);
  const auto p = regs_of("[controller]\nb = 644\na = 1\n[fixed_point]\nmode = p\ncoef_frac = 7\nkp = 22350\n");
  EXPECT_EQ(value_of(p, "kp"), 22350.0 / 128.0);
  EXPECT_EQ(value_of(p, "mode"), 1.0);
  EXPECT_EQ(error_of("[controller]\nb = 1\n[fixed_point]\nmode = pi\ncoef_frac = 13\n"),
            "c.ini:5: [fixed_point] coef_frac: not 0..12");
  EXPECT_EQ(error_of("[controller]\nb = 1\n[fixed_point]\nmode = pi\ncoef_frac = 8\nb0 = 40000\n"),
            "c.ini:6: [fixed_point] b0: not a 16-bit integer");
  // output = duty: y is the duty, so 1000 per unit instead of 1000/922.
  const auto duty = regs_of("[controller]\nb = 0.01\na = 1\noutput = duty\n");
  EXPECT_NEAR(value_of(duty, "kp"), 0.01 * 0.25 * 1000.0, 1e-12);
}

TEST(LinkControllerIni, FormsTheBoardCannotRun) {
  EXPECT_EQ(error_of("[controller]\nb = 1 2\na = 1 -0.5\n").substr(0, 41), "c.ini:3: [controller] a: the board runs P");
  EXPECT_EQ(error_of("[controller]\nb = 1\na = 1\ndt_s = 0.002\n").substr(0, 69),
            "c.ini:4: [controller] dt_s: the board's controller runs every 0.001 s");
  EXPECT_EQ(error_of("[controller]\nb = 1e9 1\na = 1 -1\n"),
            "c.ini:2: [controller] b: fixed point: b0 = 1000000000 is 271149674.6203905 /1000 duty per pulse/ms on the board, "
            "beyond its 16 bits even at coef_frac = 0");
  EXPECT_TRUE(regs_of("[plant]\nk = 1\n").empty());
}

}  // namespace
}  // namespace mcg::link
