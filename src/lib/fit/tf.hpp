// Rational transfer-function fit to a measured frequency response (mcg-fit tf).
#pragma once

#include "fit/nls.hpp"
#include "table/table.hpp"

#include <complex>
#include <string>
#include <vector>

namespace mcg::fit {

/// A frequency response as mcg-sweep bode writes it: f_hz (increasing, > 0), mag_db,
/// phase_deg and optionally coherence (0..1).
struct FrequencyResponse {
  std::string source;
  std::vector<double> f_hz;
  std::vector<double> mag_db;
  std::vector<double> phase_deg;
  std::vector<double> coherence;  ///< empty when the table has none
};

/// Reads and checks the columns; throws naming the file and line of a bad value.
FrequencyResponse read_frequency_response(const table::Table& table);

/// G(s) = num(s) / den(s), coefficients in descending powers of s. After a fit, den's
/// constant term is 1 when the plant has no pole at s = 0 (the report's form
/// [1.6194e-5 .016437 1]), otherwise den is monic.
struct RationalTf {
  std::vector<double> num;
  std::vector<double> den;

  std::complex<double> operator()(std::complex<double> s) const;
};

struct TfFitOptions {
  int poles = 2;
  int zeros = 0;
  /// Frequencies outside [f_min_hz, f_max_hz] are ignored.
  double f_min_hz = 0.0;
  double f_max_hz = 1e300;
  /// Weight each point by gamma^2 / (1 - gamma^2) (the inverse variance of the log
  /// magnitude of an H1 estimate) when the response has a coherence column.
  bool use_coherence = true;
  /// Sanathanan-Koerner re-weighted linear iterations before the nonlinear refinement.
  int sk_iterations = 30;
  /// Fit a transport delay too: G(s) e^(-s delay_s), delay_s >= 0. Sampled data carry one:
  /// a zero-order hold alone lags like half a sample period.
  bool fit_delay = false;
};

/// One factor of the normalised (Bode) form of G(s), with its standard error.
///   real root r != 0: corner_rad_s = |r|, factor (s/|r| + 1) for r < 0, (1 - s/r) for r > 0
///   complex pair:     corner_rad_s = wn = |r|, zeta = -Re(r)/wn, (s^2/wn^2 + 2 zeta s/wn + 1)
///   root at 0:        corner_rad_s = 0, factor s
struct Factor {
  bool complex_pair = false;
  bool unstable = false;  ///< Re(r) > 0
  double corner_rad_s = 0.0;
  double zeta = 0.0;
  double corner_se = 0.0;
  double zeta_se = 0.0;
};

/// The fitted model with the statistics of the nonlinear refinement.
/// The residual of point k is log(G(j w_k) / H_k), a complex number whose real part is the
/// log-magnitude error (nepers) and whose imaginary part is the phase error (rad), each
/// multiplied by sqrt(weight_k). Gain K is the ratio of the lowest nonzero coefficients
/// (the DC gain when there is no root at 0), so G(s) = K * prod(zero factors) / prod(pole factors).
struct TfFit {
  RationalTf tf;
  double gain = 0.0;
  double gain_se = 0.0;
  std::vector<Factor> poles;  ///< sorted by corner frequency
  std::vector<Factor> zeros;
  double delay_s = 0.0;  ///< 0 unless options.fit_delay
  double delay_se = 0.0;
  double rms_mag_db = 0.0;      ///< unweighted, over the points used
  double rms_phase_deg = 0.0;
  std::size_t points = 0;
  NlsResult nls;  ///< over the scaled coefficients (see tf.cpp)
};

/// Fits G(s) with the given numbers of poles and zeros: Levy's linearised least squares,
/// Sanathanan-Koerner iterations, then Levenberg-Marquardt on the log-magnitude and phase
/// errors. With a delay, the linear stages run on the response with trial delays removed
/// (a grid over 0..pi/w_max) and the best start is refined jointly with the delay. Throws mcg::Error on too few points, zeros > poles, or a fit that does not
/// converge.
TfFit fit_tf(const FrequencyResponse& response, const TfFitOptions& options);

/// The Bode (factored) form in the syntax mcg-design reads, e.g.
/// "16.557/((s/65+1)*(s/950+1))", numbers with `digits` significant digits.
std::string format_factored(const TfFit& fit, int digits = 5);

/// Roots of a polynomial given in descending powers (leading zeros ignored).
std::vector<std::complex<double>> polynomial_roots(const std::vector<double>& coefficients);

}  // namespace mcg::fit
