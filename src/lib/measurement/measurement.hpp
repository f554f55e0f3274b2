// How a run was measured: the grammar, parser and writer of the measurement metadata that
// mcg-csv(5) defines (`# rpm_estimator:`, `# i_measurement:`). Every tool that writes or reads
// these keys goes through this module, so the text has one form and one meaning.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "boardunits/chain.hpp"  // k_board_counts_per_rev

namespace mcg::config {
class Ini;
}

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

/// `# gear_ratio: N`: the speed (and angle) columns are of a shaft that turns once per N turns of
/// the motor (a gearbox between them): measured speed = motor speed / N. N is a finite number > 0.
/// Throws mcg::Error "<where>: ..." for anything else.
double parse_gear_ratio(std::string_view text, std::string_view where = "gear_ratio");
/// The metadata text for `ratio`, in the form parse_gear_ratio() reads.
std::string format_gear_ratio(double ratio);

/// `# speed_filter:` the filter the measured speed passed before it was logged (a drive's or a
/// tachometer's own smoothing). Forms:
///   first-order low-pass, time constant <tau> s    tau dy/dt = x - y (held input between samples:
///                                                  y_n = a y_(n-1) + (1 - a) x_n, a = exp(-dt/tau))
///   moving average over <W> s                      y_n = mean of the samples x_k with t_k in
///                                                  (t_n - W, t_n] (fewer at the start)
///   none
struct SpeedFilter {
  enum class Kind { none, low_pass, moving_average } kind = Kind::none;
  double time_constant_s = 0.0;  ///< low_pass: tau
  double window_s = 0.0;         ///< moving_average: W

  /// The filter applied to samples `x` at times `t_s` (strictly increasing), from rest at x_0.
  /// NaN samples pass as NaN and hold the filter's state.
  std::vector<double> apply(const std::vector<double>& t_s, const std::vector<double>& x) const;
};

/// A SpeedFilter run sample by sample (a simulation that writes rows as it goes); apply() is
/// this over a whole series.
class SpeedFilterStream {
 public:
  explicit SpeedFilterStream(const SpeedFilter& filter) : m_filter(filter) {}
  /// The filtered value at `t_s` (after every earlier sample); NaN passes as NaN.
  double push(double t_s, double x);

 private:
  SpeedFilter m_filter;
  double m_state = std::numeric_limits<double>::quiet_NaN();  ///< low-pass output
  double m_t_prev = 0.0;
  std::vector<std::pair<double, double>> m_window;  ///< moving average: (t, x) in the window
  std::size_t m_first = 0;                          ///< the window's oldest entry
  double m_sum = 0.0;
};

/// Parses the `speed_filter` text. Throws mcg::Error "<where>: expected ..." when it does not match.
SpeedFilter parse_speed_filter(std::string_view text, std::string_view where = "speed_filter");
/// The metadata text for `filter`, in the form parse_speed_filter() reads.
std::string format_speed_filter(const SpeedFilter& filter);

/// How the rig's speed reaches the data, as the model INI states it in its `[measurement]`
/// section (`gear_ratio = N`, `speed_filter = <text>`, the forms of the metadata keys above).
/// A capture that states a key itself is described by its own metadata; a capture and an INI
/// that state different values are an error (one fact, one value).
struct SpeedPath {
  std::optional<double> gear_ratio;
  std::optional<SpeedFilter> filter;
};

/// A capture's gear ratio: `override` (a command's --gear-ratio), else what the capture states,
/// else the INI's, else 1. A capture and an INI that state different ratios throw mcg::Error
/// "<source>: gear_ratio ... differs ..." unless an override settles it.
double settle_gear_ratio(std::optional<double> stated, std::optional<double> ini,
                         std::optional<double> override, std::string_view source);

/// The speed path of a capture, settled: the gear ratio as settle_gear_ratio() gives it, the
/// filter the capture states, else the INI's, else none. A capture and an INI that state
/// different filters throw mcg::Error naming `source`. Both fields are set in the result.
SpeedPath settle_speed_path(const SpeedPath& stated, const SpeedPath& ini,
                            std::optional<double> gear_override, std::string_view source);
/// What a capture's metadata states (`# gear_ratio:`, `# speed_filter:`), for `source`.
SpeedPath speed_path_stated(std::optional<std::string> gear_ratio, std::optional<std::string> speed_filter,
                            std::string_view source);

/// The `[measurement]` section of `ini` (absent keys stay unset). Throws mcg::Error naming the
/// file and line for an unknown key or a value outside the grammar.
SpeedPath speed_path_from_ini(const config::Ini& ini);
/// Writes the keys `path` states into `ini`'s `[measurement]` section.
void speed_path_to_ini(const SpeedPath& path, config::Ini& ini);

}  // namespace mcg::measurement
