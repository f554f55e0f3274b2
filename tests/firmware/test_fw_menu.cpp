// The keypad and LCD menu: Kp entry (the report's board could not take it), the display lines, and
// the service period as the keypad's ramp rate.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "fw_harness.hpp"

using fwtest::Board;

namespace {

constexpr std::uint8_t k_a = 0x0A, k_b = 0x0B, k_c = 0x0C, k_d = 0x0D, k_e = 0x0E, k_f = 0x0F;

std::string lcd(int row) { return host_board_lcd(static_cast<std::uint8_t>(row)); }

void keys(Board& b, std::initializer_list<std::uint8_t> ks) {
  for (std::uint8_t k : ks) {
    b.press(k);
  }
}

// From the main screen to the Kp item, into its editor.
void edit_kp(Board& b) {
  keys(b, {k_c, k_a, k_a, k_d});
  ASSERT_EQ(lcd(0), "Kp              ");
}

}  // namespace

// The menu is the protocol table's keypad column: positions 1..n, each once, a label of at most 16
// characters on each, and the items in the order the man page lists them.
TEST(FwMenu, TheKeypadColumnNumbersTheMenuOnce) {
  std::vector<std::string> by_position(MCG_REG_COUNT);
  unsigned count = 0;
#define KEY_ROW(NAME, name, access, lo, hi, def, unit, capture, keypad, doc) \
  if (MCG_KEY_POS(keypad) != 0u) {                                           \
    ++count;                                                                 \
    ASSERT_LT(MCG_KEY_POS(keypad), MCG_REG_COUNT);                           \
    EXPECT_EQ(by_position[MCG_KEY_POS(keypad)], "") << name;                 \
    by_position[MCG_KEY_POS(keypad)] = name;                                 \
    EXPECT_GT(std::string(MCG_KEY_LABEL(keypad)).size(), 0u) << name;        \
    EXPECT_LE(std::string(MCG_KEY_LABEL(keypad)).size(), 16u) << name;       \
  } else {                                                                   \
    EXPECT_EQ(std::string(MCG_KEY_LABEL(keypad)), "") << name;               \
  }
  MCG_REGISTERS(KEY_ROW)
#undef KEY_ROW
  const std::vector<std::string> order{
      "mode",     "rpm_cmd",  "kp",        "b0",         "b1",           "b2",     "coef_frac", "duty_bias",
      "duty_min", "duty_max", "duty_step", "service_ms", "log_interval", "clutch", "load",      "stream"};
  ASSERT_EQ(count, order.size());
  for (unsigned k = 0; k < count; ++k) EXPECT_EQ(by_position[k + 1], order[k]) << k + 1;
}

// Stepping through the menu shows each item's label, and wraps at both ends.
TEST(FwMenu, AAndBStepThroughTheItemsAndWrap) {
  Board b;
  keys(b, {k_c});
  EXPECT_EQ(lcd(0), "Mode 0OL 1P 2PI ");
  keys(b, {k_b});
  EXPECT_EQ(lcd(0), "Stream 0/1      ");
  keys(b, {k_a, k_a, k_a, k_a});
  EXPECT_EQ(lcd(0), "PI/PID b0       ");
  keys(b, {k_a, k_a, k_a, k_a, k_a, k_a, k_a, k_a, k_a, k_a, k_a, k_a, k_a});
  EXPECT_EQ(lcd(0), "Mode 0OL 1P 2PI ");
}

// Report bug: "The interface on the EMAC will not receive any Kp input value from the keypad."
TEST(FwMenu, RegressionKpEnteredOnTheKeypad) {
  Board b;
  edit_kp(b);
  keys(b, {1, k_f, 5});
  EXPECT_EQ(lcd(1), "1.5_            ");
  b.press(k_d);
  EXPECT_EQ(b.read(MCG_REG_KP), 384);  // 1.5 * 2^8
  EXPECT_EQ(lcd(0), "Kp              ");
  EXPECT_EQ(lcd(1), "       1.500    ");
}

TEST(FwMenu, KpNegativeRoundedAndAtOtherFormats) {
  Board b;
  edit_kp(b);
  keys(b, {k_e, 0, k_f, 2, 5, k_d});
  EXPECT_EQ(b.read(MCG_REG_KP), -64);
  EXPECT_EQ(lcd(1), "      -0.250    ");
  // A fourth decimal is not taken; 1.234 * 256 = 315.9 rounds to 316.
  keys(b, {k_d, 1, k_f, 2, 3, 4, 5, k_d});
  EXPECT_EQ(b.read(MCG_REG_KP), 316);
  EXPECT_EQ(lcd(1), "       1.234    ");
  // At F = 12 the same typing gives round(1.234 * 4096) = 5054.
  ASSERT_EQ(b.set(MCG_REG_COEF_FRAC, 12), MCG_ST_OK);
  keys(b, {k_d, 1, k_f, 2, 3, 4, k_d});
  EXPECT_EQ(b.read(MCG_REG_KP), 5054);
  // 8.0 does not fit Q3.12: refused, Kp unchanged.
  keys(b, {k_d, 8, k_d});
  EXPECT_EQ(b.read(MCG_REG_KP), 5054);
  EXPECT_EQ(lcd(1), "refused   9     ");
}

TEST(FwMenu, EditingKeys) {
  Board b;
  edit_kp(b);
  keys(b, {2, 7, k_c});  // C deletes the last character
  EXPECT_EQ(lcd(1), "2_              ");
  keys(b, {k_c, k_c});  // on an empty entry, C cancels
  EXPECT_EQ(lcd(1), "       0.000    ");
  EXPECT_EQ(b.read(MCG_REG_KP), 0);
  keys(b, {k_b, k_d, 5, 0, 0, k_d});  // back to the speed command: 500 rpm
  EXPECT_EQ(b.read(MCG_REG_RPM_CMD), 500);
  keys(b, {k_d, 9, 0, 0, k_d});  // outside 420 +- 300: refused
  EXPECT_EQ(lcd(1), "refused   9     ");
  EXPECT_EQ(b.read(MCG_REG_RPM_CMD), 500);
  keys(b, {k_d, 1, k_f, 5, k_d});  // no decimal point in whole-number items
  EXPECT_EQ(b.read(MCG_REG_RPM_CMD), 500);
  EXPECT_EQ(lcd(1), "refused   9     ");
}

TEST(FwMenu, ModeChosenFromTheMenu) {
  Board b;
  keys(b, {k_c, k_d, 3, k_d});
  EXPECT_EQ(b.read(MCG_REG_MODE), static_cast<int>(MCG_MODE_OPEN)) << "a PID whose gains were never written";
  EXPECT_EQ(lcd(1), "refused  12     ");  // MCG_ST_NO_GAINS
  ASSERT_EQ(b.set(MCG_REG_B0, 256), MCG_ST_OK);
  keys(b, {k_d, 3, k_d});
  EXPECT_EQ(b.read(MCG_REG_MODE), static_cast<int>(MCG_MODE_PID));
  EXPECT_EQ(lcd(1), " 3 PID          ");
  keys(b, {k_c});
  EXPECT_EQ(lcd(0).substr(10), "PID --");
  EXPECT_EQ(lcd(1).substr(0, 5), "c 420");
}

TEST(FwMenu, MainScreenLines) {
  Board b;
  b.set_pulses(14);
  ASSERT_EQ(b.write(MCG_REG_DUTY, 375), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_CLUTCH, MCG_CLUTCH_ENGAGED), MCG_ST_OK);
  b.run(600, 14);
  EXPECT_EQ(lcd(0), "  410 rpm OL  C-");
  EXPECT_EQ(lcd(1), "open   d  37.5% ");
  ASSERT_EQ(b.write(MCG_REG_LOAD, 1), MCG_ST_OK);
  // b0 e[n] + b1 e[n-1] = (e[n] - e[n-1]) / 256: steady pulses keep the duty.
  ASSERT_EQ(b.set(MCG_REG_B0, 1), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_B1, -1), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_MODE, MCG_MODE_PI), MCG_ST_OK);
  ASSERT_EQ(b.write(MCG_REG_RPM_CMD, 555), MCG_ST_OK);
  b.run(500, 14);
  EXPECT_EQ(lcd(0), "  410 rpm PI  CL");
  EXPECT_EQ(lcd(1), "c 555  d  37.5% ");
}

TEST(FwMenu, DisplayRefreshesEveryHalfSecond) {
  Board b;
  b.run(500, 0);
  const std::string before = lcd(0);
  b.run(499, 20);
  EXPECT_EQ(lcd(0), before) << "not yet";
  b.run(1, 20);
  EXPECT_EQ(lcd(0), "  586 rpm OL  --");  // 320 * 1875 / 1024 = 585.9
}

// A and B ramp the duty by the duty step once per service period while held: the service period is
// the keypad's ramp rate.
TEST(FwMenu, ServicePeriodSetsTheRampRate) {
  for (int period : {40, 5}) {
    SCOPED_TRACE(period);
    Board b;
    ASSERT_EQ(b.write(MCG_REG_SERVICE_MS, period), MCG_ST_OK);
    b.key(k_a);
    b.run(400);
    b.key(MCG_KEY_NONE);
    b.run(50);
    EXPECT_NEAR(host_board_duty(), 10 * 400 / period, 10);
    b.key(k_b);
    b.run(200);
    b.key(MCG_KEY_NONE);
    b.run(50);
    EXPECT_NEAR(host_board_duty(), 10 * 200 / period, 20);
  }
}

TEST(FwMenu, SingleKeyActions) {
  Board b;
  keys(b, {1});
  EXPECT_EQ(host_board_clutch(), 1);
  keys(b, {2});
  EXPECT_EQ(host_board_load(), 1);
  keys(b, {1, 2});
  EXPECT_EQ(host_board_clutch(), 0);
  EXPECT_EQ(host_board_load(), 0);
  keys(b, {k_e});
  EXPECT_EQ(b.read(MCG_REG_STREAM), 1);
  keys(b, {k_f});
  EXPECT_EQ(b.read(MCG_REG_FLAGS) & static_cast<int>(MCG_FLAG_LOGGING), static_cast<int>(MCG_FLAG_LOGGING));
  ASSERT_EQ(b.set(MCG_REG_KP, 1), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_MODE, MCG_MODE_P), MCG_ST_OK);
  ASSERT_EQ(b.set(MCG_REG_DUTY_BIAS, 500), MCG_ST_OK);
  b.run(5);
  EXPECT_GT(host_board_duty(), 0);
  keys(b, {0});  // stop: open loop, duty 0
  EXPECT_EQ(b.read(MCG_REG_MODE), static_cast<int>(MCG_MODE_OPEN));
  EXPECT_EQ(host_board_duty(), 0);
}
