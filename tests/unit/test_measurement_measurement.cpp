// The measurement metadata grammar: rpm_estimator and i_measurement parse, format back to the
// same text, and reject text outside the grammar naming the clause.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <vector>

#include "config/ini.hpp"
#include "measurement/measurement.hpp"
#include "test_support_error.hpp"

namespace mcg::measurement {
namespace {

using test::error_of;

TEST(Measurement, RpmEstimatorRoundTrip) {
  const CountEstimator e = parse_rpm_estimator("counts over 0.002 s window, 65536 counts/rev");
  EXPECT_EQ(e.window_s, 0.002);
  EXPECT_EQ(e.counts_per_rev, 65536.0);
  EXPECT_EQ(format_rpm_estimator(e), "counts over 0.002 s window, 65536 counts/rev");
  EXPECT_EQ(error_of([] { parse_rpm_estimator("counts over 0 s window, 2048 counts/rev", "a.csv"); }),
            "a.csv: window must be > 0 s in 'counts over 0 s window, 2048 counts/rev'");
}

TEST(Measurement, BoardCurrentChainTextIsTheContractText) {
  CurrentChain board = board_current_chain();
  board.sigma_A = 0.003;
  const std::string text = format_i_measurement(board);
  EXPECT_EQ(text,
            "1 ohm shunt, 10-bit ADC over 0-5 V with 2.5 V mid-scale offset (range -2.5..2.495 A, saturates), "
            "noise sigma 0.003 A");
  const CurrentChain back = parse_i_measurement(text);
  EXPECT_EQ(format_i_measurement(back), text);
  EXPECT_DOUBLE_EQ(back.step_A(), 5.0 / 1024.0);
  EXPECT_EQ(back.sigma_A, 0.003);
  EXPECT_TRUE(back.saturates);
  EXPECT_EQ(back.range_low_A, -2.5);
  EXPECT_EQ(back.range_high_A, 2.495);
}

TEST(Measurement, QuantiseIsTheBoardAdcAndItsRailsAreAtRail) {
  const CurrentChain board = board_current_chain();
  // Codes 0..1023 at 5/1024 V per code, 2.5 V offset, 1 ohm.
  EXPECT_DOUBLE_EQ(board.quantise(0.0), 0.0);
  EXPECT_DOUBLE_EQ(board.quantise(0.1), 20.0 * 5.0 / 1024.0);
  EXPECT_DOUBLE_EQ(board.quantise(9.0), 1023.0 * 5.0 / 1024.0 - 2.5);
  EXPECT_DOUBLE_EQ(board.quantise(-9.0), -2.5);
  EXPECT_TRUE(board.at_rail(board.quantise(9.0)));
  EXPECT_TRUE(board.at_rail(board.quantise(-9.0)));
  EXPECT_FALSE(board.at_rail(board.quantise(2.49)));
  EXPECT_FALSE(board.at_rail(board.quantise(-2.49)));
  EXPECT_FALSE(CurrentChain{}.at_rail(1e9));
}

TEST(Measurement, ParsesTheOtherForms) {
  const CurrentChain sim = parse_i_measurement("simulated, noise sigma 0.01 A");
  EXPECT_TRUE(sim.simulated);
  EXPECT_EQ(sim.sigma_A, 0.01);
  EXPECT_TRUE(std::isnan(sim.step_A()));
  EXPECT_EQ(format_i_measurement(sim), "simulated, noise sigma 0.01 A");
  // A chain stated without the ADC span: the rails are known, the step is not (1 uA margin).
  const CurrentChain no_span = parse_i_measurement("0.1 ohm shunt, 12-bit ADC (range -10..10 A), nominal noise sigma 0.02 A");
  EXPECT_EQ(no_span.shunt_ohm, 0.1);
  EXPECT_EQ(no_span.adc_bits, 12.0);
  EXPECT_FALSE(no_span.saturates);
  EXPECT_EQ(no_span.sigma_A, 0.02);
  EXPECT_TRUE(std::isnan(no_span.step_A()));
  EXPECT_TRUE(no_span.at_rail(10.0));
  EXPECT_FALSE(no_span.at_rail(9.999));
  const CurrentChain shunted = parse_i_measurement("0.5 ohm shunt, 12-bit ADC over -5-5 V");
  EXPECT_DOUBLE_EQ(shunted.step_A(), 10.0 / 4096.0 / 0.5);
}

TEST(Measurement, RejectsTextOutsideTheGrammar) {
  EXPECT_EQ(error_of([] { parse_i_measurement("hall sensor, noise sigma 0.01 A", "run.csv: i_measurement"); }),
            "run.csv: i_measurement: clause 'hall sensor' of 'hall sensor, noise sigma 0.01 A': expected "
            "'<R> ohm shunt', '<B>-bit ADC ...', 'noise sigma <s> A' or 'simulated'");
  EXPECT_EQ(error_of([] { parse_i_measurement("noise sigma 3 mA"); }),
            "i_measurement: clause 'noise sigma 3 mA' of 'noise sigma 3 mA': expected '[nominal ]noise sigma <s> A' "
            "with s >= 0");
  EXPECT_EQ(error_of([] { parse_i_measurement("10-bit ADC (range 2..1 A)"); }),
            "i_measurement: clause '10-bit ADC (range 2..1 A)' of '10-bit ADC (range 2..1 A)': expected "
            "'<B>-bit ADC [over <lo>-<hi> V] [with <o> V mid-scale offset] [(range <a>..<b> A[, saturates])]'");
  EXPECT_EQ(error_of([] { parse_i_measurement("1 ohm shunt, 2 ohm shunt"); }),
            "i_measurement: clause '2 ohm shunt' of '1 ohm shunt, 2 ohm shunt': expected each clause at most once");
}

// The gear ratio and the speed filter: text round trips, refusals that name the key.
TEST(Measurement, GearRatioAndSpeedFilterRoundTrip) {
  EXPECT_EQ(parse_gear_ratio(" 60 "), 60.0);
  EXPECT_EQ(format_gear_ratio(parse_gear_ratio("14.5")), "14.5");
  EXPECT_EQ(
      error_of([] { parse_gear_ratio("-2", "g.csv: gear_ratio"); }),
      "g.csv: gear_ratio: expected a gear ratio > 0 (motor turns per turn of the measured shaft), got '-2'");
  for (const char* text :
       {"first-order low-pass, time constant 0.02 s", "moving average over 0.01 s", "none"}) {
    EXPECT_EQ(format_speed_filter(parse_speed_filter(text)), text);
  }
  EXPECT_EQ(
      error_of([] { parse_speed_filter("first-order low-pass, time constant 0 s", "f.csv: speed_filter"); }),
      "f.csv: speed_filter: expected 'first-order low-pass, time constant <tau> s', 'moving average over "
      "<W> s' or 'none' (tau, W > 0), got 'first-order low-pass, time constant 0 s'");
  EXPECT_THROW(parse_speed_filter("low-pass 5 Hz"), Error);
}

// A unit step through the low-pass: y_n = 1 - a^n, a = exp(-dt / tau), the held-input solution
// of tau dy/dt = x - y; NaN passes and holds the state. The moving average of a ramp over W
// is the ramp's value W/2 earlier (less half a sample).
TEST(Measurement, SpeedFilterClosedForms) {
  const double dt = 1e-3;
  const double tau = 0.02;
  std::vector<double> t(200), x(200, 1.0);
  for (std::size_t n = 0; n < t.size(); ++n) t[n] = static_cast<double>(n) * dt;
  x[0] = 0.0;
  const SpeedFilter low = parse_speed_filter("first-order low-pass, time constant 0.02 s");
  const auto y = low.apply(t, x);
  EXPECT_EQ(y[0], 0.0);
  for (std::size_t n : {1U, 20U, 150U}) {
    EXPECT_NEAR(y[n], 1.0 - std::exp(-static_cast<double>(n) * dt / tau), 1e-12) << n;
  }
  x[50] = std::nan("");
  const auto held = low.apply(t, x);
  EXPECT_TRUE(std::isnan(held[50]));
  EXPECT_NEAR(held[51], 1.0 - std::exp(-51.0 * dt / tau), 1e-12);

  std::vector<double> ramp(t.size());
  for (std::size_t n = 0; n < t.size(); ++n) ramp[n] = 3.0 * t[n];
  const auto avg = parse_speed_filter("moving average over 0.01 s").apply(t, ramp);
  for (std::size_t n : {10U, 57U, 199U}) EXPECT_NEAR(avg[n], 3.0 * (t[n] - 0.0045), 1e-9) << n;
  EXPECT_NEAR(avg[3], 3.0 * 1.5e-3, 1e-12);  // fewer samples at the start: their mean
  EXPECT_EQ(parse_speed_filter("none").apply(t, ramp), ramp);
}

// One value per fact: a command's override wins; else the capture; else the INI; else 1; a
// capture and an INI that disagree are refused.
TEST(Measurement, GearRatioIsSettledOnce) {
  EXPECT_EQ(settle_gear_ratio({}, {}, {}, "a.csv"), 1.0);
  EXPECT_EQ(settle_gear_ratio({}, 30.0, {}, "a.csv"), 30.0);
  EXPECT_EQ(settle_gear_ratio(60.0, {}, {}, "a.csv"), 60.0);
  EXPECT_EQ(settle_gear_ratio(60.0, 60.0, {}, "a.csv"), 60.0);
  EXPECT_EQ(settle_gear_ratio(60.0, 30.0, 5.0, "a.csv"), 5.0);
  EXPECT_EQ(error_of([] { settle_gear_ratio(60.0, 30.0, {}, "a.csv"); }),
            "a.csv: gear_ratio 60 differs from the model's [measurement] gear_ratio 30 (give --gear-ratio to "
            "choose)");
}

// The model INI's [measurement] section reads back what it writes; an unknown key is named.
TEST(Measurement, SpeedPathIniRoundTrip) {
  SpeedPath path;
  path.gear_ratio = 60.0;
  path.filter = parse_speed_filter("first-order low-pass, time constant 0.005 s");
  config::Ini ini;
  speed_path_to_ini(path, ini);
  std::istringstream text(ini.str());
  const SpeedPath back = speed_path_from_ini(config::Ini::parse(text, "m.ini"));
  ASSERT_TRUE(back.gear_ratio && back.filter);
  EXPECT_EQ(*back.gear_ratio, 60.0);
  EXPECT_EQ(format_speed_filter(*back.filter), "first-order low-pass, time constant 0.005 s");
  EXPECT_FALSE(speed_path_from_ini(config::Ini{}).gear_ratio);
  std::istringstream bad("[measurement]\ngear_ratio = 0\n");
  EXPECT_EQ(
      error_of([&] { speed_path_from_ini(config::Ini::parse(bad, "m.ini")); }),
      "m.ini:2: [measurement] gear_ratio: expected a gear ratio > 0 (motor turns per turn of the measured "
      "shaft), got '0'");
  std::istringstream unknown("[measurement]\ngear = 3\n");
  EXPECT_EQ(error_of([&] { speed_path_from_ini(config::Ini::parse(unknown, "m.ini")); }),
            "m.ini:2: [measurement] gear: unknown key (gear_ratio, speed_filter)");
}

}  // namespace
}  // namespace mcg::measurement
