// Residual analysis for the gap diagnosis: where a residual (measured minus simulated) lies
// by operating regime and frequency band, whether it is white and independent of the input
// (the classic system-identification checks), and the noise floor of the measurement chain.
#pragma once

#include "fit/greybox.hpp"  // rms_finite
#include "model/model.hpp"

#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace mcg::fit {

/// Samples within this time after an event count as transient.
inline constexpr double k_transient_window_s = 0.1;
/// A jump of the applied voltage larger than this between two rows is an event, V.
inline constexpr double k_event_voltage_jump_V = 1.0;
/// On a current or torque drive, a jump of the command by more than this share of its largest
/// magnitude (and far beyond its row-to-row noise: drive_jump) is an event.
inline constexpr double k_event_drive_share = 0.05;
/// The report's low-speed regime: moving slower than this share of the largest |speed| measured
/// (relative, so that it means the same on a 60:1 gearmotor's output shaft and a fast spindle).
inline constexpr double k_low_speed_share = 0.05;

/// Row indices n (n >= 1) where an input changes: the clutch state, the relay (r_load
/// switching between open and closed or changing value), or the drive's command jumps
/// (drive_command(inputs)): |v(n) - v(n-1)| > 1 V; a current or torque command by more than
/// drive_jump(u, kind, 1 V, k_event_drive_share).
std::vector<std::size_t> event_rows(const model::Inputs& inputs);

/// Per row: true when the row lies within k_transient_window_s after an event row
/// (0 <= t(n) - t(event) < 0.1 s, the comparison tolerant of rounding in t by 1e-9 s).
std::vector<bool> transient_mask(const model::Inputs& inputs);

/// One regime of the breakdown: which samples, the RMS of the residual over them and
/// their share of the total squared residual,
///   rms = sqrt(sum_{n in regime} r_n^2 / count),  share = sum_{n in regime} r_n^2 / sum_n r_n^2.
/// Only finite residual samples count; rms is NaN for an empty regime.
struct RegimeStat {
  std::string group;    ///< "all", "clutch", "load", "speed", "direction", "timing", "band"
  std::string regime;   ///< "state 0", "open", "stuck", "< 12.5 rad/s", "forward", "1-10 Hz", ...
  std::size_t samples = 0;
  double rms = 0.0;
  double share = 0.0;
};

/// What a breakdown needs besides the residual: the inputs of the run and the measured
/// speed (stuck = |speed| below half the resolution `rpm_resolution`; low = moving below
/// `low_speed`, both in the measured series' unit; `low_label` names that bound in the report's
/// unit, "12.5 rad/s").
struct RegimeContext {
  const model::Inputs* inputs = nullptr;
  std::span<const double> rpm_measured;
  double rpm_resolution = 0.0;
  double low_speed = 0.0;
  std::string low_label;
};

/// Breakdown of `residual` (one value per row of the context's inputs) over the time-domain
/// regimes: all; clutch state 0/1/2; load open/closed; speed stuck / below low_speed / above;
/// direction forward (rpm >= 0) / reverse; transient / steady. Regimes without samples are
/// kept (samples = 0) so that tables of several models line up.
std::vector<RegimeStat> regime_breakdown(const RegimeContext& context, std::span<const double> residual);

/// The frequency bands of band_breakdown(), Hz: [0, 1), [1, 10), [10, 50), [50, Nyquist]; a
/// band ends at the Nyquist frequency when that is lower, and one that starts at or above it
/// is empty (0 samples, left out of the tables).
const std::vector<double>& band_edges_hz();

/// Breakdown of the residual's power over frequency bands (periodogram of the mean-included
/// residual, NaN samples as 0, zero-padded to a power of two; Parseval: the band powers sum
/// to the total). rms is the residual RMS the band alone would give; share its part of the
/// total power. dt_s is the (median) sample period.
std::vector<RegimeStat> band_breakdown(std::span<const double> residual, double dt_s);

/// Whiteness and input-independence of a residual (Ljung, System Identification, 16.6):
///   rho_rr(k) = sum r_n r_{n-k} / sum r_n^2 for lags first_lag..max_lag,
///   rho_ru(k) = sum r_n u_{n-k} / sqrt(sum r^2 sum u^2) for lags 0..max_lag (u = input minus
///   its mean), both over the finite samples (r mean-removed).
/// Portmanteau tests at the 99 % level: Ljung-Box Q_rr = N (N + 2) sum rho_rr(k)^2 / (N - k)
/// and Q_ru = N sum rho_ru(k)^2, each against the chi-square quantile with as many degrees
/// of freedom as lags (Wilson-Hilferty approximation). The speed estimator correlates its own
/// noise over its window, so the autocorrelation test starts after it (first_lag).
struct Whiteness {
  std::size_t samples = 0;
  double bound = 0.0;                ///< 2.58 / sqrt(N): the 99 % band of a single rho
  std::size_t first_lag = 1;         ///< first autocorrelation lag tested
  double max_auto = 0.0;             ///< max |rho_rr(k)| over the tested lags
  std::size_t max_auto_lag = 0;
  double q_auto = 0.0;               ///< Ljung-Box statistic
  double q_auto_limit = 0.0;         ///< its 99 % chi-square quantile
  double max_cross = 0.0;            ///< max |rho_ru(k)| over 0 <= k <= max_lag
  std::size_t max_cross_lag = 0;
  double q_cross = 0.0;
  double q_cross_limit = 0.0;
  bool white() const { return q_auto <= q_auto_limit; }
  bool independent() const { return q_cross <= q_cross_limit; }
};
Whiteness whiteness(std::span<const double> residual, std::span<const double> input, std::size_t max_lag,
                    std::size_t first_lag);

/// The noise floor of one measured output, in its unit.
struct NoiseFloor {
  double chain = 0.0;   ///< from the measurement chain (estimator resolution, ADC, stated noise)
  double data = 0.0;    ///< from the data: high-frequency content of the steady, moving samples
  double floor() const { return chain > data ? chain : data; }
};

/// Encoder speed estimator (counts over a window W, c counts per revolution): the
/// resolution is q = 60 / (W c) rpm, and the quantisation error of a count difference is
/// the difference of two independent uniform errors of one count, RMS q / sqrt(6), while
/// the shaft turns (none while it is stuck). chain = q sqrt(moving fraction / 6).
/// data = RMS of the second difference d_n = y_{n+1} - 2 y_n + y_{n-1} over the steady
/// (non-transient), moving rows, divided by sqrt(6) (for white noise, and for the window
/// estimator's noise too, var d = 6 var y).
NoiseFloor rpm_noise_floor(std::span<const double> rpm_measured, const std::vector<bool>& transient,
                           double window_s, double counts_per_rev);

/// Current measurement: ADC step `adc_step_A` and stated noise sigma `sigma_A`:
/// chain = sqrt(sigma^2 + step^2 / 12); data as for the speed, over the steady rows.
NoiseFloor current_noise_floor(std::span<const double> i_measured, const std::vector<bool>& transient,
                               double adc_step_A, double sigma_A);

/// The p-quantile of the chi-square distribution with `dof` degrees of freedom
/// (Wilson-Hilferty: dof (1 - 2/(9 dof) + z_p sqrt(2/(9 dof)))^3, z_p the normal quantile).
double chi_square_quantile(double dof, double z_p);

}  // namespace mcg::fit
