// Rational transfer-function fit to a measured frequency response (mcg-fit tf).
#pragma once

#include "fit/nls.hpp"
#include "table/table.hpp"

#include <complex>
#include <span>
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
  /// What the response maps, from its `# response: IN -> OUT` metadata (mcg-sweep bode's);
  /// empty when the table does not say.
  std::string units;
  /// An rpm counted over this window (`# rpm_estimator:`), divided out of the columns above; 0: none.
  double output_window_s = 0.0;
  /// Frequencies left out where that window's response is below 0.05 (near f = k / window).
  std::size_t window_zeros = 0;
};

/// Reads and checks the columns; throws naming the file and line of a bad value. A response to an
/// rpm counted over a window (`# rpm_estimator:`, mcg-csv(5)) is the plant's times the window's
/// mean, W(s) = (1 - e^(-s T_w)) / (s T_w): W is divided out, so that a fit is the plant's, as the
/// time-domain fit models the window; near W's zeros (|W| < 0.05) points are left out and counted.
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

/// An input/output run for the time-domain fit, uniformly sampled: u[k] acts over
/// [k dt, (k+1) dt) (mcg-csv(5)'s timing), y[k] is sampled at k dt.
struct TimeSeries {
  std::string source;
  std::string in;   ///< the input column's name
  std::string out;  ///< the output column's name
  double dt_s = 0.0;
  std::vector<double> u;
  std::vector<double> y;
  std::size_t skipped = 0;   ///< leading rows without a measured value, dropped
  std::string skipped_note;  ///< what was skipped, one line; empty when nothing was
  /// y is a speed from counts over this many samples (`# rpm_estimator:`, a whole number of
  /// samples): the model is seen through that window; 0: y is the output itself.
  std::size_t window_samples = 0;
};

/// Takes columns `in` and `out` of a run (a board capture or mcg-sim's output, unedited): the
/// leading rows in which either is unmeasured are skipped (said in skipped_note), an unmeasured
/// or infinite value elsewhere, uneven sampling, a run too short or an input that never changes
/// (the run excites nothing) throws, naming the file.
TimeSeries read_time_series(const table::Table& table, const std::string& in, const std::string& out);

/// y[k] of G(s) e^(-s delay_s) driven through a zero-order hold by u, from rest: exact at the
/// sampling instants (the delay's fraction of a sample splits the held input between two steps).
/// With window_samples > 0, y[k] is the output's mean over the last window_samples periods (a
/// speed from encoder counts over a window), exactly too.
std::vector<double> simulate_tf(const RationalTf& g, double delay_s, double dt_s, std::span<const double> u,
                                std::size_t window_samples = 0);

/// The time-domain fit: the transfer function, the operating point, how well it explains the run.
/// The model is output error: y[k] = y0 + (G e^(-s delay) (u - u_ref))(k dt) + e[k], e white,
/// the run starting in the steady state of the input u_ref (u[0] for a run begun settled; for one
/// begun at rest, the input that friction holds back), y0 the output there: an affine model, whose
/// offset y0 - K u_ref absorbs the friction's.
struct TimeTfFit {
  TfFit fit;           ///< tf, Bode form and standard errors; points = samples used
  double u_ref = 0.0;  ///< the input the run starts settled at
  double u_ref_se = 0.0;
  double y0 = 0.0;  ///< the output there
  double y0_se = 0.0;
  double fit_percent = 0.0;  ///< 100 (1 - |y - y_hat| / |y - mean y|), as MATLAB's compare
  double rms = 0.0;          ///< RMS of y - y_hat, in the output's unit
};

/// Fits G(s) (options.poles, options.zeros, options.fit_delay; the band options do not apply)
/// to the run by output error: an equation-error (ARX) fit over trial delays gives the start,
/// its poles mapped to s by log(z)/dt, then Levenberg-Marquardt on y - y_hat.
TimeTfFit fit_tf_time(const TimeSeries& run, const TfFitOptions& options);

/// The fit % of `fit` on another run (held out): the model as fitted, the run's own starting
/// point (y0 and u_ref) re-estimated by linear least squares.
double validation_fit_percent(const TimeTfFit& fit, const TimeSeries& run);

/// The Bode (factored) form in the syntax mcg-design reads, e.g.
/// "16.557/((s/65+1)*(s/950+1))", numbers with `digits` significant digits.
std::string format_factored(const TfFit& fit, int digits = 5);

/// Roots of a polynomial given in descending powers (leading zeros ignored).
std::vector<std::complex<double>> polynomial_roots(const std::vector<double>& coefficients);

}  // namespace mcg::fit
