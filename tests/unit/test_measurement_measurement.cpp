// The measurement metadata grammar: rpm_estimator and i_measurement parse, format back to the
// same text, and reject text outside the grammar naming the clause.
#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace mcg::measurement
