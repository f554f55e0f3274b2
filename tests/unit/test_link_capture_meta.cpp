// Unit tests of what a capture's board_config says the board ran (captured_board), and of the
// model running those registers (sim::board_loop_controller on raw values).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <numbers>
#include <string_view>
#include <utility>
#include <vector>

#include "link/capture_meta.hpp"
#include "link/registers.hpp"
#include "mcg_protocol.h"
#include "sim/controller.hpp"
#include "table/table.hpp"
#include "test_support_error.hpp"

namespace mcg::link {
namespace {

using ::testing::ElementsAre;
using ::testing::Pair;

table::Metadata with_config(const std::string& text) {
  table::Metadata m;
  m.set("board_config", text);
  return m;
}

std::string error_of(const std::string& text) {
  return test::error_of([&] { captured_board(with_config(text), "cap.csv"); });
}

// The list is the protocol table's capture column: the controller's set (mode among it) and the
// registers a capture's rows carry, in id order.
TEST(LinkCapturedBoard, TheStatedRegistersAreTheProtocolTablesCaptureColumn) {
  std::vector<std::string_view> expected;
  for (const RegisterInfo& reg : registers()) {
    if (reg.staged || reg.name == "rpm_cmd" || reg.name == "clutch" || reg.name == "load") {
      expected.push_back(reg.name);
    }
    EXPECT_EQ(reg.carried_by_rows, reg.name == "rpm_cmd" || reg.name == "clutch" || reg.name == "load")
        << reg.name;
  }
  const auto names = config_register_names();
  EXPECT_EQ(std::vector<std::string_view>(names.begin(), names.end()), expected);
  EXPECT_EQ(names.size(), 12u);
}

TEST(LinkCapturedBoard, ReadsTheRegistersAsTheCoreTakesThem) {
  // What mcg-serial stream writes for a board with a designed PI loaded (gains in 2^-12).
  const auto board = captured_board(
      with_config("mode=pi rpm_cmd=500 clutch=1 load=0 coef_frac=12 kp=0 b0=1.76611328125 b1=-1.059814453125 b2=0 "
                  "duty_bias=0 duty_min=0 duty_max=100"),
      "cap.csv");
  ASSERT_TRUE(board.has_value());
  EXPECT_EQ(board->mode, MCG_MODE_PI);
  EXPECT_EQ(board->mode_name, "pi");
  EXPECT_THAT(board->registers,
              ElementsAre(Pair(MCG_REG_COEF_FRAC, 12), Pair(MCG_REG_DUTY_BIAS, 0), Pair(MCG_REG_KP, 0),
                          Pair(MCG_REG_B0, 7234), Pair(MCG_REG_B1, -4341), Pair(MCG_REG_B2, 0),
                          Pair(MCG_REG_DUTY_MIN, 0), Pair(MCG_REG_DUTY_MAX, 1000)));
  EXPECT_FALSE(captured_board(table::Metadata{}, "cap.csv").has_value());
}

TEST(LinkCapturedBoard, AMalformedConfigIsOneErrorNamingTheCapture) {
  EXPECT_EQ(error_of("mode=pi b7=3"), "cap.csv: board_config: 'b7=3' is not NAME=value of a register");
  EXPECT_EQ(error_of("mode=pi b0"), "cap.csv: board_config: 'b0' is not NAME=value of a register");
  EXPECT_EQ(error_of("mode=warp"), "cap.csv: board_config: mode: invalid value 'warp' (open, p, pi, pid)");
  EXPECT_EQ(error_of("mode=pi coef_frac=12 b0=9"), "cap.csv: board_config: b0: 9 /1000 per pulse/ms is outside -8..7.999755859375 /1000 per pulse/ms");
  EXPECT_EQ(error_of("kp=1"), "cap.csv: board_config: no mode (the capture does not say what the board ran)");
}

// What the firmware core would refuse (a read-only register, limits out of order) was an abort
// (MCG_DEMAND on the core's status) when mcg-sim ran the capture: now one line naming the line.
TEST(LinkCapturedBoard, EveryBoardItReturnsTheCoreTakes) {
  EXPECT_EQ(
      error_of("mode=pi stream_seq=2"),
      "cap.csv: board_config: 'stream_seq' is not one of the registers a capture states (mode, rpm_cmd, "
      "duty_bias, kp, b0, b1, b2, coef_frac, duty_min, duty_max, clutch, load)");
  EXPECT_EQ(error_of("mode=pi duty=5"),
            "cap.csv: board_config: 'duty' is not one of the registers a capture states (mode, rpm_cmd, "
            "duty_bias, kp, b0, b1, b2, coef_frac, duty_min, duty_max, clutch, load)");
  EXPECT_EQ(error_of("mode=pi duty_min=50 duty_max=10"),
            "cap.csv: board_config: duty_min 50 % is above duty_max 10 %");
  EXPECT_EQ(error_of("mode=pi duty_max=90 duty_min=95"),
            "cap.csv: board_config: duty_min 95 % is above duty_max 90 %");
  EXPECT_EQ(error_of("mode=pi kp=1 b0=1 kp=2"), "cap.csv: board_config: 'kp' is given twice");
  table::Metadata meta;
  meta.set("source", "mcg-serial");
  meta.set("board_config", "mode=p stream_seq=2");
  meta.note_line("board_config", 7);
  EXPECT_EQ(
      test::error_of([&] { captured_board(meta, "cap.csv"); }),
      "cap.csv:7: board_config: 'stream_seq' is not one of the registers a capture states (mode, rpm_cmd, "
      "duty_bias, kp, b0, b1, b2, coef_frac, duty_min, duty_max, clutch, load)");
  // Limits below the power-on floor, in either order: the core takes the floor first.
  const auto board = captured_board(with_config("mode=p duty_max=-10 kp=1 duty_min=-50"), "cap.csv");
  ASSERT_TRUE(board.has_value());
  EXPECT_THAT(board->registers, ElementsAre(Pair(MCG_REG_KP, 256), Pair(MCG_REG_DUTY_MIN, -500),
                                            Pair(MCG_REG_DUTY_MAX, -100)));
  const auto loop = sim::board_loop_controller(board->mode, board->registers);
  EXPECT_DOUBLE_EQ(loop->tick(0.0, 420.0), -100.0 / 1000.0);
}

// The core on the captured registers holds a speed as it does on the same registers from a
// design: the same duties tick for tick.
TEST(LinkCapturedBoard, TheModelRunsTheCapturedRegisters) {
  const auto board = captured_board(with_config("mode=pi coef_frac=12 b0=1.76611328125 b1=-1.059814453125 b2=0"),
                                    "cap.csv");
  ASSERT_TRUE(board.has_value());
  // One firmware core at a time: the captured registers' run first, then the design's.
  const auto run = [](sim::LoopController& c) {
    std::vector<double> duties;
    double theta = 0.0;
    for (int k = 0; k < 200; ++k) {
      theta += 2.0 * std::numbers::pi * 3.0 / 1000.0;  // 3 rev/s: 180 rpm, under the 500 commanded
      duties.push_back(c.tick(theta, 500.0));
    }
    return duties;
  };
  const std::vector<double> captured = run(*sim::board_loop_controller(board->mode, board->registers));
  boardunits::BoardFixedPoint q;
  q.mode = "pi";
  q.coef_frac = 12;
  q.regs = {7234, -4341, 0};
  const std::vector<double> designed = run(*sim::board_loop_controller(q));
  EXPECT_EQ(captured, designed);
  EXPECT_GT(captured.back(), captured.front());  // the integrator winds up toward the command
}

}  // namespace
}  // namespace mcg::link
