// How a run was measured: the grammar, parser and writer of the measurement metadata that
// mcg-csv(5) defines (`# rpm_estimator:`, `# i_measurement:`). Every tool that writes or reads
// these keys goes through this module, so the text has one form and one meaning.
#pragma once

#include <limits>
#include <string>
#include <string_view>

#include "boardunits/chain.hpp"  // k_board_counts_per_rev

namespace mcg::measurement {

/// `# rpm_estimator: counts over W s window, N counts/rev`: the count is floor(theta N / (2 pi))
/// as a real up/down counter holds it, and rpm(t) = (count(t) - count(t - W)) / N / W * 60.
struct CountEstimator {
  double window_s = 0.005;
  double counts_per_rev = boardunits::k_board_counts_per_rev;  ///< 512-line encoder, x4 quadrature decoding

  /// Speed resolution, rpm per count: 60 / (N W).
  double rpm_per_count() const { return 60.0 / (counts_per_rev * window_s); }
};

/// Parses the `rpm_estimator` text, e.g. "counts over 0.005 s window, 2048 counts/rev".
/// Throws mcg::Error "<where>: ..." when it does not match.
CountEstimator parse_rpm_estimator(std::string_view text, std::string_view where = "rpm_estimator");
/// The metadata text for `estimator`, in the form parse_rpm_estimator() reads.
std::string format_rpm_estimator(const CountEstimator& estimator);

/// `# i_measurement:` the chain behind the current column `i`. Grammar (clauses separated by
/// ", " outside parentheses, in any order, each at most once):
///   <R> ohm shunt
///   <B>-bit ADC [over <lo>-<hi> V] [with <o> V mid-scale offset] [(range <a>..<b> A[, saturates])]
///   [nominal ]noise sigma <s> A
///   simulated
/// Unknown quantities are NaN (the range is -inf..inf when not stated).
struct CurrentChain {
  static constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
  static constexpr double k_inf = std::numeric_limits<double>::infinity();
  double shunt_ohm = k_nan;        ///< current to ADC voltage: v = i R + offset
  double adc_bits = k_nan;
  double adc_low_V = k_nan;        ///< ADC input span
  double adc_high_V = k_nan;
  double offset_V = k_nan;         ///< mid-scale offset added before the ADC
  double range_low_A = -k_inf;     ///< the rails: readings at them mean "at least this much"
  double range_high_A = k_inf;
  bool saturates = false;
  double sigma_A = k_nan;          ///< noise standard deviation
  bool simulated = false;          ///< written by a simulation without a modelled chain

  /// One ADC step in A: (hi - lo) / 2^bits / R (R = 1 ohm when not stated); NaN when the
  /// bits or the span are not stated.
  double step_A() const;
  /// Whether a reading sits at a rail (within a tenth of an ADC step, 1 uA when the step is
  /// unknown): such a sample is not a measurement of the current.
  bool at_rail(double i_A) const;
  /// The reading of the ADC for a true current: code = clamp(round((i R + o - lo) / span 2^bits),
  /// 0, 2^bits - 1), i = (lo + code span / 2^bits - o) / R. Needs bits and span.
  double quantise(double i_A) const;
};

/// The board's current chain: 1 ohm shunt, 10-bit ADC over 0-5 V with 2.5 V mid-scale offset;
/// the range -2.5..2.495 A (code 1023 reads 2.4951 A, stated to four digits), saturating.
CurrentChain board_current_chain();

/// Parses the `i_measurement` text. Throws mcg::Error "<where>: ..." naming the clause that
/// does not match the grammar.
CurrentChain parse_i_measurement(std::string_view text, std::string_view where = "i_measurement");
/// The metadata text for `chain`, in the form parse_i_measurement() reads.
std::string format_i_measurement(const CurrentChain& chain);

}  // namespace mcg::measurement
