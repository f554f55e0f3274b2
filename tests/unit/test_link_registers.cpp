// Unit tests of the register table: names, scales, ranges, text in and out.
#include "link/registers.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "common/error.hpp"
#include "mcg_protocol.h"
#include "test_support_error.hpp"

namespace mcg::link {
namespace {

using test::error_of;

TEST(LinkRegisters, EveryProtocolRegisterHasOneEntry) {
  ASSERT_EQ(registers().size(), MCG_REG_COUNT - 1u);
  for (unsigned id = 1; id < MCG_REG_COUNT; ++id) {
    const RegisterInfo* reg = find_register(static_cast<std::uint8_t>(id));
    ASSERT_NE(reg, nullptr) << id;
    EXPECT_EQ(find_register(reg->name), reg);
  }
  EXPECT_EQ(find_register("RPM-CMD"), find_register(static_cast<std::uint8_t>(MCG_REG_RPM_CMD)));
  EXPECT_EQ(find_register("speed"), nullptr);
  EXPECT_EQ(error_of([] { require_register("speed"); }).substr(0, 48), "unknown register 'speed' (registers: mode, rpm_c");
}

TEST(LinkRegisters, ScalesOfTheProtocol) {
  const auto& duty = require_register("duty");
  EXPECT_EQ(to_raw(duty, 35.5, 0), 355);      // 1/1000 of full scale
  EXPECT_EQ(to_raw(duty, -100.0, 0), -1000);
  EXPECT_DOUBLE_EQ(to_engineering(duty, 355, 0), 35.5);
  const auto& kp = require_register("kp");
  EXPECT_EQ(to_raw(kp, 2.5, 8), 640);         // Q8
  EXPECT_EQ(to_raw(kp, 2.5, 12), 10240);      // Q12
  EXPECT_EQ(to_raw(kp, 3.1575, 12), 12933);   // 3.1575 * 4096 = 12933.1 -> 12933
  EXPECT_DOUBLE_EQ(to_engineering(kp, 12933, 12), 12933.0 / 4096.0);
  EXPECT_EQ(to_raw(require_register("rpm_cmd"), 420.4, 0), 420);
  // Counters travel as i16 but count up to 65535.
  EXPECT_DOUBLE_EQ(to_engineering(require_register("rx_errors"), -1, 0), 65535.0);
}

// A value read back prints as the shortest text that reads back to it: every duty in tenths of
// a percent as its decimal (157 is 15.7, not 157 * 0.1 = 15.700000000000001), and that text
// sets the same raw value again.
TEST(LinkRegisters, ReadBackIsTheShortestDecimal) {
  const auto& duty = require_register("duty");
  for (int raw = -1000; raw <= 1000; ++raw) {
    const int whole = std::abs(raw) / 10;
    const int tenth = std::abs(raw) % 10;
    const std::string expected =
        fmt::format("{}{}{}", raw < 0 ? "-" : "", whole, tenth ? fmt::format(".{}", tenth) : "");
    const std::string text = format_value(duty, static_cast<std::int16_t>(raw), 0);
    ASSERT_EQ(text, expected);
    ASSERT_EQ(to_raw(duty, parse_value(duty, text, "x"), 0), raw);
  }
  EXPECT_EQ(format_value(require_register("kp"), 12933, 12), "3.157470703125");  // exact in binary
}

TEST(LinkRegisters, RangesAreCheckedBeforeSending) {
  EXPECT_EQ(error_of([] { to_raw(require_register("rpm_cmd"), 800, 0); }), "rpm_cmd: 800 rpm is outside 120..720 rpm");
  EXPECT_EQ(error_of([] { to_raw(require_register("duty"), 100.06, 0); }), "duty: 100.06 % is outside -100..100 %");
  EXPECT_EQ(error_of([] { to_raw(require_register("kp"), 200.0, 8); }),
            "kp: 200 /1000 per pulse/ms is outside -128..127.99609375 /1000 per pulse/ms");
  EXPECT_EQ(to_raw(require_register("duty"), 100.04, 0), 1000);  // rounds into range
}

TEST(LinkRegisters, ParseAndFormat) {
  const auto& mode = require_register("mode");
  EXPECT_EQ(parse_value(mode, "PI", "set"), 2.0);
  EXPECT_EQ(parse_value(mode, "3", "set"), 3.0);
  EXPECT_EQ(format_value(mode, 3, 0), "pid");
  EXPECT_EQ(error_of([&] { parse_value(mode, "fast", "set"); }), "set: mode: invalid value 'fast' (open, p, pi, pid)");
  EXPECT_EQ(parse_value(require_register("stream"), "on", "x"), 1.0);
  // Clutch states as in every tool's CSV: 1 attached and disengaged, 2 engaged; 0 is not the board's.
  const auto& clutch = require_register("clutch");
  EXPECT_EQ(parse_value(clutch, "engaged", "x"), 2.0);
  EXPECT_EQ(parse_value(clutch, "1", "x"), 1.0);
  EXPECT_EQ(error_of([&] { parse_value(clutch, "0", "set"); }),
            "set: clutch 0 (motor alone) is not a state of the board: its clutch is mounted (1 attached and "
            "disengaged, 2 engaged)");
  EXPECT_EQ(error_of([&] { to_raw(clutch, 3.0, 0); }), "clutch: 3 is outside 1..2");
  EXPECT_EQ(error_of([] { parse_value(require_register("rpm_cmd"), "4e", "a.ini:3"); }),
            "a.ini:3: rpm_cmd: invalid value '4e'");
  EXPECT_EQ(format_value(require_register("flags"), MCG_FLAG_SATURATED | MCG_FLAG_SEQ, 0), "saturated,seq");
  EXPECT_EQ(format_value(require_register("flags"), 0, 0), "none");
  EXPECT_EQ(format_value(require_register("duty"), -355, 0), "-35.5");
  EXPECT_EQ(format_value(require_register("b1"), -3, 2), "-0.75");
  EXPECT_EQ(status_text(MCG_ST_RANGE), "value outside the register's range");
}

// Every status code of the protocol has its own text and its protocol name: a refusal never reads
// as another one (a duty in closed loop was once "board busy").
TEST(LinkRegisters, EveryStatusHasItsOwnText) {
  std::set<std::string_view> texts;
  for (unsigned st = 0; st < MCG_ST_COUNT; ++st) {
    const auto s = static_cast<std::uint8_t>(st);
    EXPECT_NE(status_text(s), "unknown status") << st;
    EXPECT_NE(status_name(s), "UNKNOWN") << st;
    texts.insert(status_text(s));
  }
  EXPECT_EQ(texts.size(), std::size_t{MCG_ST_COUNT});
  EXPECT_EQ(status_name(MCG_ST_NO_GAINS), "NO_GAINS");
  EXPECT_EQ(status_text(MCG_ST_OWNED), "the controller owns duty in a closed-loop mode; set mode open first");
}

TEST(LinkRegisters, TheControllersSetIsStaged) {
  std::vector<std::string_view> staged;
  for (const RegisterInfo& reg : registers()) {
    if (reg.staged) staged.push_back(reg.name);
    EXPECT_TRUE(!reg.staged || reg.writable) << reg.name;
  }
  EXPECT_EQ(staged, (std::vector<std::string_view>{"mode", "duty_bias", "kp", "b0", "b1", "b2", "coef_frac",
                                                   "duty_min", "duty_max"}));
  EXPECT_TRUE(require_register("commit").writable);
  EXPECT_FALSE(require_register("commit").staged);
}

}  // namespace
}  // namespace mcg::link
