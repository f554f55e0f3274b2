// Unit tests of the board units: the loop chain, the fixed-point quantisation, the one
// [controller] parser and what the board runs for it.
#include "boardunits/controller.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include <fmt/format.h>

#include "boardunits/chain.hpp"
#include "boardunits/fixed_point.hpp"
#include "common/error.hpp"
#include "config/ini.hpp"
#include "link/connection.hpp"
#include "link/registers.hpp"
#include "linsys/tf.hpp"

namespace mcg::boardunits {
namespace {

config::Ini ini_of(const std::string& text) {
  std::istringstream in(text);
  return config::Ini::parse(in, "c.ini");
}

std::string error_of(const std::string& text) {
  try {
    board_controller(ini_of(text));
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(BoardunitsChain, TheReportsFigures) {
  const LoopChain c;
  EXPECT_EQ(k_board_counts_per_rev, 2048);
  EXPECT_EQ(std::string(k_board_encoder_text),
            fmt::format("{} lines, x{} quadrature decoding = {} counts/rev", k_encoder_lines, k_quadrature,
                        k_board_counts_per_rev));
  EXPECT_DOUBLE_EQ(k_supply_V, 20.0);
  EXPECT_NEAR(c.pwm_v_per_count(), 0.00542, 5e-6);  // the report's .00542
  EXPECT_NEAR(c.counts_per_rad(), 81.5, 0.05);      // the report's 81.5
  EXPECT_DOUBLE_EQ(c.input_scale(), 512.0 / 60000.0);
  EXPECT_NEAR(c.gain() * 16.557, 0.029267, 5e-7);  // docs/formats.md's DC loop gain
  EXPECT_DOUBLE_EQ(ControllerUnits{}.factor(), 0.25 * 1000.0 / 922.0);
}

TEST(BoardunitsController, OneParserForEveryTool) {
  const auto c = controller_from_ini(ini_of("[controller]\nb = 644\na = 1\n"));
  ASSERT_TRUE(c);
  EXPECT_EQ(c->b, std::vector<double>{644.0});
  EXPECT_DOUBLE_EQ(c->input_scale, 512.0 / 60000.0);
  EXPECT_FALSE(controller_from_ini(ini_of("[plant]\nk = 1\n")));
  EXPECT_EQ(error_of("[controller]\nb = 1\nwindow = 3\n"), "c.ini:3: [controller] window: unknown key");
  EXPECT_EQ(error_of("[controller]\nb = 1\ninput_scale = -1\n"), "c.ini:3: [controller] input_scale: must be > 0");
  config::Ini out;
  controller_to_ini(*c, out);
  std::istringstream text(out.str());
  const auto back = controller_from_ini(config::Ini::parse(text, "p.ini"));
  ASSERT_TRUE(back);
  EXPECT_EQ(back->b, c->b);
  EXPECT_EQ(back->a, c->a);
}

// A scale of 0 x inf made the gains nan, and nan cast to a register -2147483648 (kp = 0 ran).
TEST(BoardunitsController, AScaleThatIsNotFiniteIsRefused) {
  EXPECT_EQ(error_of("[controller]\nb = 0\na = 1\nduty_full_scale = 1e-308\n"),
            "c.ini:4: [controller] duty_full_scale: input_scale x (60000/2048) x (1000/duty_full_scale) = "
            "inf is not "
            "a finite, nonzero scale");
  EXPECT_EQ(error_of("[controller]\nb = 1\na = 1\ninput_scale = 1e300\nduty_full_scale = 1e-300\n"),
            "c.ini:5: [controller] duty_full_scale: input_scale x (60000/2048) x (1000/duty_full_scale) = "
            "inf is not "
            "a finite, nonzero scale");
  EXPECT_EQ(
      error_of("[controller]\nb = 1\na = 1\ninput_scale = 1e-320\n"),
      "c.ini:4: [controller] input_scale: input_scale x (60000/2048) x (1000/duty_full_scale) = 3.1775e-319 is "
      "not a finite, nonzero scale");
  // A finite scale over a tiny a0: b0 = 0 would be 0 x inf on the board.
  EXPECT_EQ(error_of("[controller]\nb = 0\na = 1e-320\n"),
            "c.ini:2: [controller] b: fixed point: b0 = 0 is nan on the board (b0 x 0.27114967462039047 / a0)");
  EXPECT_EQ(ControllerUnits{}.factor(), 0.25 * 1000.0 / 922.0);
}

TEST(BoardunitsController, FormsTheBoardCannotRunAreRefusedInOneLine) {
  EXPECT_EQ(error_of("[controller]\ntype = lead\nb = 1 2\na = 1 -0.5\n"),
            fmt::format("c.ini:4: [controller] a: a lead controller; {}", k_board_forms));
  EXPECT_EQ(error_of("[controller]\nb = 1 -1.8 0.81\na = 1 -1.5 0.5\n"),
            fmt::format("c.ini:3: [controller] a: {}", k_board_forms));
  EXPECT_EQ(error_of("[controller]\nb = 1\na = 1\ndt_s = 0.002\n"),
            fmt::format("c.ini:4: [controller] dt_s: the board's controller runs every 0.001 s; {}", k_board_forms));
  EXPECT_EQ(error_of("[controller]\nb = 1e9 1\na = 1 -1\n").substr(0, 38), "c.ini:2: [controller] b: fixed point: ");
  EXPECT_EQ(error_of("[controller]\nb = 1 -1e-6\na = 1 -1\n"),
            "c.ini:2: [controller] b: fixed point: b1 = -1e-06 rounds to 0 in the board's Q3.12 (the controller would "
            "change structure)");
}

TEST(BoardunitsFixedPoint, ReportPiInBoardRegisters) {
  // The report's PI on 512-count/rev errors and 922 duty counts: on the board each coefficient
  // scales by (512/2048) (1000/922); 3.1575 * 2^12 = 12933.3 fits int16, so F = 12.
  const auto q = board_fixed_point({11.645, -6.987}, {1.0, -1.0}, ControllerUnits{});
  ASSERT_TRUE(q);
  const double k = 0.25 * 1000.0 / 922.0;
  EXPECT_DOUBLE_EQ(q->factor, k);
  EXPECT_EQ(q->mode, "pi");
  EXPECT_EQ(q->coef_frac, 12);
  EXPECT_EQ(q->regs, (std::vector<std::int32_t>{12933, -7760, 0}));
  EXPECT_EQ(std::lround(11.645 * k * 4096.0), 12933);
  EXPECT_EQ(std::lround(-6.987 * k * 4096.0), -7760);
  EXPECT_EQ(q->wanted, (std::vector<double>{11.645 * k, -6.987 * k, 0.0}));  // what load notes the rounding of
  ASSERT_EQ(q->b.size(), 2U);
  EXPECT_DOUBLE_EQ(q->b[0], 12933.0 / 4096.0 / k);
  EXPECT_DOUBLE_EQ(q->b[1], -7760.0 / 4096.0 / k);
  EXPECT_EQ(q->a, (std::vector<double>{1.0, -1.0}));
  EXPECT_DOUBLE_EQ(q->acc_max, 1000.0 * std::ldexp(1.0, 20) + 8191.0 * (12933.0 + 7760.0));
}

TEST(BoardunitsFixedPoint, SameRegistersAsMcgSerial) {
  // mcg-serial quantises [controller] itself (src/lib/link/controller_ini.cpp): both must agree.
  const std::vector<std::vector<double>> bs{{11.645, -6.987}, {644.0}, {40.0, -70.0, 31.0}, {0.3, -0.29}};
  for (const auto& b : bs) {
    const std::vector<double> a = b.size() == 1 ? std::vector<double>{1.0} : std::vector<double>{1.0, -1.0};
    const auto q = board_fixed_point(b, a, ControllerUnits{});
    ASSERT_TRUE(q);
    std::istringstream text(fmt::format("[controller]\nb = {}\na = {}\n", linsys::list_text(b), linsys::list_text(a)));
    const auto regs = link::controller_registers(config::Ini::parse(text, "c.ini"));
    int frac = -1;
    std::vector<std::int32_t> raw;
    for (const auto& [reg, value] : regs) {
      if (reg->name == "coef_frac") frac = static_cast<int>(value);
    }
    for (const auto& [reg, value] : regs) {
      if (reg->unit == link::Unit::Gain) raw.push_back(link::to_raw(*reg, value, frac));
    }
    EXPECT_EQ(frac, q->coef_frac) << linsys::list_text(b);
    EXPECT_EQ(raw, q->regs) << linsys::list_text(b);
  }
}

TEST(BoardunitsFixedPoint, PGainGetsFewerFractionalBits) {
  // 644 (the report's P design) * 0.27115 = 174.62: Q8.7 holds it, Q7.8 does not.
  const auto q = board_fixed_point({644.0}, {1.0}, ControllerUnits{});
  ASSERT_TRUE(q);
  EXPECT_EQ(q->mode, "p");
  EXPECT_EQ(q->coef_frac, 7);
  EXPECT_EQ(q->regs, (std::vector<std::int32_t>{22351}));
  EXPECT_EQ(q->a, (std::vector<double>{1.0}));
}

TEST(BoardunitsFixedPoint, FormsTheBoardDoesNotRun) {
  EXPECT_FALSE(board_fixed_point({1.0, -0.5}, {1.0, -0.9}, ControllerUnits{}));  // lead/lag
  EXPECT_FALSE(board_fixed_point({1.0, -0.5}, {1.0}, ControllerUnits{}));        // FIR
  ControllerUnits slow;
  slow.dt_s = 0.002;
  EXPECT_FALSE(board_fixed_point({11.645, -6.987}, {1.0, -1.0}, slow));
  EXPECT_THROW(board_fixed_point({2e5, -1.0}, {1.0, -1.0}, ControllerUnits{}), mcg::Error);   // > 32767 at F = 0
  EXPECT_THROW(board_fixed_point({1.0, -1e-6}, {1.0, -1.0}, ControllerUnits{}), mcg::Error);  // b1 rounds to 0
}

}  // namespace
}  // namespace mcg::boardunits
