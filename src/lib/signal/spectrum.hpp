// Frequency-response estimation from sampled input/output records: Welch-averaged H1 with
// coherence, exact values at the lines of a periodic multisine, phase unwrapping, resampling.
#pragma once

#include <complex>
#include <cstddef>
#include <span>
#include <vector>

namespace mcg::signal {

/// A frequency response: H(f) = Y(f)/X(f) at frequencies f_hz, with the magnitude-squared
/// coherence gamma^2 = |Sxy|^2 / (Sxx Syy) in [0, 1] (NaN where it cannot be measured).
struct Response {
  std::vector<double> f_hz;
  std::vector<std::complex<double>> h;
  std::vector<double> coherence;
};

/// The default Welch segment for `samples` samples: the largest power of two not above
/// samples/8 (about 15 averages at 50 % overlap), at least 256 and at most 65536 samples,
/// and never more than `samples`.
std::size_t default_segment(std::size_t samples);

/// Welch-averaged H1 estimate between input x and output y sampled every dt_s:
///   segments of `segment` samples overlapping by `overlap` (0 <= overlap < 1), each
///   mean-removed and Hann-windowed (w_k = 1/2 - 1/2 cos(2 pi k / N)), then
///   Sxx = sum |X|^2, Syy = sum |Y|^2, Sxy = sum conj(X) Y over the segments,
///   H1 = Sxy / Sxx, gamma^2 = |Sxy|^2 / (Sxx Syy),
/// at f_k = k / (N dt) for k = 1 .. N/2. Bins without input power get H = NaN.
/// Throws mcg::Error when the record is shorter than one segment or segment < 16.
Response welch_h1(std::span<const double> x, std::span<const double> y, double dt_s, std::size_t segment,
                  double overlap);

/// The response at the lines of a multisine of period `period_samples` samples: harmonic h
/// has frequency h / (period_samples dt_s). Uses the whole periods of the record, skipping the
/// first (the transient) when there are two or more; per period m the DFT at each line
///   X_m(h) = sum_k x_k exp(-2 pi i h k / P),
/// then H = sum_m conj(X_m) Y_m / sum_m |X_m|^2 and gamma^2 over the periods (NaN with one
/// period). Exact for a noiseless linear system in periodic steady state.
/// Throws mcg::Error when the record holds no whole period or a line is at or above Nyquist.
Response line_response(std::span<const double> x, std::span<const double> y, double dt_s,
                       std::size_t period_samples, std::span<const int> harmonics);

/// 20 log10 |h| (dB).
double magnitude_db(std::complex<double> h);

/// arg h in degrees, unwrapped along the vector (jumps over 180 degrees are removed by
/// adding multiples of 360); the first value lies in (-180, 180]. NaN entries are kept and
/// skipped.
std::vector<double> unwrapped_phase_deg(std::span<const std::complex<double>> h);

/// How the sample instants are spaced.
struct Spacing {
  bool uniform;     ///< every step within 0.1 % of the mean step
  double min_dt_s;  ///< shortest step
  double max_dt_s;  ///< longest step
  double median_dt_s;
};

/// Spacing of the strictly increasing instants t_s (at least two).
Spacing spacing_of(std::span<const double> t_s);

/// Linear interpolation of (t_s, y) onto the grid t_0 + k dt_s, k = 0 .. floor((t_last -
/// t_0) / dt_s). t_s must be strictly increasing.
std::vector<double> resample_linear(std::span<const double> t_s, std::span<const double> y, double dt_s);

}  // namespace mcg::signal
