// Transfer-function fit to a time-domain run: an equation-error (ARX) start, then output error.
//
// The model is simulated exactly at the samples: the input held over each period (mcg-csv(5)'s
// timing), G(s) in controllable canonical form in the scaled variable x = s/w0 of tf_core, and a
// delay of D whole samples plus a fraction eps, over which the previous input still acts:
//   x[k+1] = Phi x[k] + Gamma_a u[k-D-1] + Gamma_b u[k-D]
//   Phi = e^(A T),  Gamma_b = int_0^(T-eps) e^(A s) ds B,  Gamma_a = e^(A (T-eps)) int_0^eps e^(A s) ds B
#include "fit/tf.hpp"
#include "fit/tf_core.hpp"

#include "common/demand.hpp"
#include "common/error.hpp"
#include "common/quote.hpp"
#include "measurement/measurement.hpp"
#include "signal/spectrum.hpp"

#include <Eigen/QR>
#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

namespace mcg::fit {

namespace {

using Complex = std::complex<double>;
using tf_core::Scaled;

/// Fewest samples a run must have for the time-domain fit.
constexpr std::size_t k_min_samples = 50;
/// Largest delay (samples) the equation-error start tries with --delay.
constexpr int k_max_start_delay = 25;

/// G(x) = beta(x) / alpha(x) in x = s/w0, ascending coefficients, alpha monic of degree n and
/// beta of degree <= n (padded with zeros).
struct ScaledTf {
  std::vector<double> alpha;  ///< alpha_0 .. alpha_{n-1} (alpha_n = 1)
  std::vector<double> beta;   ///< beta_0 .. beta_n
  double w0 = 1.0;
};

ScaledTf from_theta(const Scaled& sc, const Eigen::VectorXd& theta) {
  ScaledTf g;
  g.w0 = sc.w0;
  g.beta.assign(static_cast<std::size_t>(sc.n) + 1, 0.0);
  for (int i = 0; i <= sc.m; ++i) g.beta[static_cast<std::size_t>(i)] = theta[i];
  for (int i = 0; i < sc.n; ++i) g.alpha.push_back(theta[sc.m + 1 + i]);
  return g;
}

/// The exact sampled output of g e^(-s delay) for the held input u (deviations, zero before k = 0);
/// with window > 0, its mean over the last `window` periods, as a speed from encoder counts over a
/// window is: the output's integral is a state, y[k] = (int[k] - int[k - window]) / (window T).
std::vector<double> simulate_scaled(const ScaledTf& g, double delay_s, double dt_s, std::span<const double> u,
                                    std::size_t window) {
  const auto order = static_cast<Eigen::Index>(g.alpha.size());
  const Eigen::Index n = order + (window > 0 ? 1 : 0);
  const double d = g.beta[g.alpha.size()];
  Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(n + 1, n + 1);
  Eigen::RowVectorXd c = Eigen::RowVectorXd::Zero(n);
  for (Eigen::Index i = 0; i < order; ++i) {
    if (i + 1 < order) aug(i, i + 1) = g.w0;
    aug(order - 1, i) = -g.alpha[static_cast<std::size_t>(i)] * g.w0;
    c[i] = g.beta[static_cast<std::size_t>(i)] - d * g.alpha[static_cast<std::size_t>(i)];
  }
  aug(order - 1, n) = g.w0;
  if (window > 0) {
    // d int/dt = c x + d u.
    aug.block(order, 0, 1, order) = c.head(order);
    aug(order, n) = d;
  }
  const auto whole = static_cast<std::ptrdiff_t>(std::floor(delay_s / dt_s + 1e-9));
  double eps = delay_s - static_cast<double>(whole) * dt_s;
  if (eps < 1e-9 * dt_s) eps = 0.0;
  const Eigen::MatrixXd full = (aug * dt_s).exp();
  const Eigen::MatrixXd phi = full.topLeftCorner(n, n);
  Eigen::VectorXd gamma_b = full.col(n).head(n);
  Eigen::VectorXd gamma_a = Eigen::VectorXd::Zero(n);
  if (eps > 0.0) {
    const Eigen::MatrixXd late = (aug * (dt_s - eps)).exp();
    const Eigen::MatrixXd early = (aug * eps).exp();
    gamma_b = late.col(n).head(n);
    gamma_a = late.topLeftCorner(n, n) * early.col(n).head(n);
  }
  const auto input = [&](std::ptrdiff_t j) { return j < 0 ? 0.0 : u[static_cast<std::size_t>(j)]; };
  std::vector<double> y(u.size());
  std::vector<double> integral(window > 0 ? u.size() : 0);
  const double window_s = static_cast<double>(window) * dt_s;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  for (std::size_t k = 0; k < u.size(); ++k) {
    const auto now = static_cast<std::ptrdiff_t>(k) - whole;
    const double held_before = input(now - 1);
    const double held = input(now);
    if (window > 0) {
      integral[k] = x[order];
      y[k] = (integral[k] - (k >= window ? integral[k - window] : 0.0)) / window_s;
    } else {
      y[k] = c.dot(x) + d * (eps > 0.0 ? held_before : held);
    }
    x = phi * x + gamma_a * held_before + gamma_b * held;
  }
  return y;
}

std::vector<double> deviations(const std::vector<double>& u, double u_ref) {
  std::vector<double> out(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) out[k] = u[k] - u_ref;
  return out;
}

/// The equation-error fit y[k] + sum a_i y[k-i] = sum_{j=1..n} b_j u[k-j-delay] + c over the
/// run; returns its poles mapped to s (log(z)/T; a pole on or outside the unit circle, or at a
/// negative real z, is moved onto the stable real axis) and the residual sum of squares.
std::vector<Complex> arx_poles(const std::vector<double>& u, const std::vector<double>& y, int n, int delay,
                               double dt_s, double& cost) {
  const std::size_t first = static_cast<std::size_t>(n + delay + 1);
  const auto rows = static_cast<Eigen::Index>(y.size() - first);
  Eigen::MatrixXd a(rows, 2 * n + 1);
  Eigen::VectorXd b(rows);
  for (std::size_t k = first; k < y.size(); ++k) {
    const auto r = static_cast<Eigen::Index>(k - first);
    for (int i = 1; i <= n; ++i) {
      a(r, i - 1) = -y[k - static_cast<std::size_t>(i)];
      a(r, n + i - 1) = u[k - static_cast<std::size_t>(i + delay)];
    }
    a(r, 2 * n) = 1.0;
    b[r] = y[k];
  }
  const Eigen::VectorXd p = a.colPivHouseholderQr().solve(b);
  cost = (a * p - b).squaredNorm();
  std::vector<double> poly{1.0};
  for (int i = 0; i < n; ++i) poly.push_back(p[i]);
  const double slowest = -1.0 / (static_cast<double>(y.size()) * dt_s);
  std::vector<Complex> poles;
  for (const Complex& z : polynomial_roots(poly)) {
    const bool real = std::abs(z.imag()) <= 1e-9 * std::max(1.0, std::abs(z));
    if (std::abs(z) >= 1.0 || !std::isfinite(std::abs(z))) {
      poles.emplace_back(slowest, 0.0);
    } else if (real || std::abs(z) < 1e-6) {
      poles.emplace_back(std::log(std::max(std::abs(z), 1e-6)) / dt_s, 0.0);
    } else {
      poles.push_back(std::log(z) / dt_s);
    }
  }
  return poles;
}

/// Polynomial (descending) with the given roots; conjugate pairs give real coefficients.
std::vector<double> poly_from_roots(const std::vector<Complex>& roots) {
  std::vector<Complex> c{1.0};
  for (const Complex& r : roots) {
    std::vector<Complex> next(c.size() + 1, 0.0);
    for (std::size_t i = 0; i < c.size(); ++i) {
      next[i] += c[i];
      next[i + 1] -= c[i] * r;
    }
    c = next;
  }
  std::vector<double> out;
  for (const Complex& v : c) out.push_back(v.real());
  return out;
}

/// Least squares y ~ c_0 + sum_j c_j s_j over the columns s_j.
Eigen::VectorXd linear_fit(const std::vector<std::vector<double>>& columns, const std::vector<double>& y) {
  const auto rows = static_cast<Eigen::Index>(y.size());
  Eigen::MatrixXd a(rows, static_cast<Eigen::Index>(columns.size()) + 1);
  a.col(0).setOnes();
  for (std::size_t j = 0; j < columns.size(); ++j) {
    a.col(static_cast<Eigen::Index>(j) + 1) = Eigen::Map<const Eigen::VectorXd>(columns[j].data(), rows);
  }
  return a.colPivHouseholderQr().solve(Eigen::Map<const Eigen::VectorXd>(y.data(), rows));
}

double fit_percent_of(const std::vector<double>& y, const std::vector<double>& y_hat) {
  const double mean = std::accumulate(y.begin(), y.end(), 0.0) / static_cast<double>(y.size());
  double err = 0.0;
  double spread = 0.0;
  for (std::size_t k = 0; k < y.size(); ++k) {
    err += (y[k] - y_hat[k]) * (y[k] - y_hat[k]);
    spread += (y[k] - mean) * (y[k] - mean);
  }
  return spread > 0.0 ? 100.0 * (1.0 - std::sqrt(err / spread)) : -std::numeric_limits<double>::infinity();
}

/// A RationalTf (any scaling) as ScaledTf at w0 = the geometric mean of its pole magnitudes.
ScaledTf scaled_of(const RationalTf& g, double dt_s) {
  std::vector<double> num = g.num;
  std::vector<double> den = g.den;
  while (!den.empty() && den.front() == 0.0) den.erase(den.begin());
  MCG_DEMAND(!den.empty());
  while (!num.empty() && num.front() == 0.0) num.erase(num.begin());
  const std::size_t n = den.size() - 1;
  MCG_DEMAND(num.size() <= den.size());
  double w0 = 1.0 / dt_s;
  if (n > 0 && den.back() != 0.0)
    w0 = std::pow(std::abs(den.back() / den.front()), 1.0 / static_cast<double>(n));
  ScaledTf s;
  s.w0 = w0;
  // den(s) = sum D_i s^i = sum D_i w0^i x^i, normalised by D_n w0^n.
  const double lead = den.front() * std::pow(w0, static_cast<double>(n));
  for (std::size_t i = 0; i < n; ++i)
    s.alpha.push_back(den[n - i] * std::pow(w0, static_cast<double>(i)) / lead);
  s.beta.assign(n + 1, 0.0);
  for (std::size_t i = 0; i < num.size(); ++i) {
    s.beta[i] = num[num.size() - 1 - i] * std::pow(w0, static_cast<double>(i)) / lead;
  }
  return s;
}

}  // namespace

TimeSeries read_time_series(const table::Table& table, const std::string& in, const std::string& out) {
  TimeSeries ts;
  ts.source = table.source;
  ts.in = in;
  ts.out = out;
  const table::LeadingUnmeasured skipped = table::leading_unmeasured(table, {in, out});
  const table::Table rest = skipped.rows > 0 ? table::drop_leading(table, skipped.rows) : table;
  if (skipped.rows > 0) {
    ts.skipped = skipped.rows;
    ts.skipped_note = table::skipped_note(table, skipped);
  }
  table::require_increasing(rest, "t");
  table::require_finite(rest, in);
  table::require_finite(rest, out);
  if (rest.rows() < k_min_samples) {
    fail("{}: {} rows, too short for a time-domain fit (at least {})", rest.source, rest.rows(),
         k_min_samples);
  }
  const std::vector<double>& t = rest.col("t");
  const signal::Spacing spacing = signal::spacing_of(t);
  ts.dt_s = spacing.median_dt_s;
  for (std::size_t k = 1; k < t.size(); ++k) {
    const double step = t[k] - t[k - 1];
    if (std::abs(step - ts.dt_s) > 0.01 * ts.dt_s) {
      fail(
          "{}:{}: column 't': a step of {:.6g} s where the run's is {:.6g} s: the time-domain fit needs a "
          "uniformly sampled run",
          rest.source, rest.line_of(k), step, ts.dt_s);
    }
  }
  ts.u = rest.col(in);
  ts.y = rest.col(out);
  // A speed counted over a window of whole samples is modelled through that window (mcg-csv(5):
  // a tool comparing a model with a measured rpm applies the same estimator).
  if (const auto text = rest.meta.get("rpm_estimator");
      text && out.rfind("rpm", 0) == 0 && out != "rpm_true") {
    const double window_s = measurement::parse_rpm_estimator(*text, rest.source + ": rpm_estimator").window_s;
    const double samples = std::round(window_s / ts.dt_s);
    if (samples >= 1.0 && std::abs(samples * ts.dt_s - window_s) <= 1e-6 * window_s) {
      ts.window_samples = static_cast<std::size_t>(samples);
    }
  }
  const auto [lo, hi] = std::minmax_element(ts.u.begin(), ts.u.end());
  if (*lo == *hi) fail("{}: column {} never changes: the run excites nothing to fit", rest.source, quote(in));
  return ts;
}

std::vector<double> simulate_tf(const RationalTf& g, double delay_s, double dt_s, std::span<const double> u,
                                std::size_t window_samples) {
  MCG_DEMAND(dt_s > 0.0 && delay_s >= 0.0);
  return simulate_scaled(scaled_of(g, dt_s), delay_s, dt_s, u, window_samples);
}

TimeTfFit fit_tf_time(const TimeSeries& run, const TfFitOptions& options) {
  if (options.poles < 1) fail("--poles must be at least 1");
  if (options.zeros < 0 || options.zeros > options.poles) {
    fail("--zeros must be between 0 and the number of poles ({})", options.poles);
  }
  const std::vector<double> du = deviations(run.u, run.u.front());
  const int n = options.poles;
  const int max_delay =
      options.fit_delay ? std::min<int>(k_max_start_delay, static_cast<int>(run.u.size() / 20)) : 0;
  if (run.u.size() < static_cast<std::size_t>(4 * (2 * n + 1 + max_delay))) {
    fail("{}: {} samples, too few for {} poles", run.source, run.u.size(), n);
  }

  // Start: the equation-error poles at the best trial delay, then the gain and offset that fit
  // the simulated output of those poles best.
  int delay_samples = 0;
  double best_cost = std::numeric_limits<double>::infinity();
  std::vector<Complex> poles;
  for (int d = 0; d <= max_delay; ++d) {
    double cost = 0.0;
    std::vector<Complex> p = arx_poles(du, run.y, n, d, run.dt_s, cost);
    if (cost < best_cost) {
      best_cost = cost;
      poles = std::move(p);
      delay_samples = d;
    }
  }
  double w0 = 1.0;
  for (const Complex& p : poles) w0 *= std::pow(std::abs(p), 1.0 / n);
  const Scaled sc{options.zeros, n, w0};
  const std::vector<double> den_s = poly_from_roots(poles);
  RationalTf start;
  start.den = den_s;
  start.num = {den_s.back()};
  // The equation-error delay includes the window's lag (half of it), which the model has itself.
  const double delay0 =
      std::max(0.0, static_cast<double>(delay_samples) - 0.5 * static_cast<double>(run.window_samples)) *
      run.dt_s;
  // y ~ y0 + K (s_u - u_ref s_1), s_u and s_1 the unit-gain responses to u - u[0] and to 1: linear in
  // (y0, K, K u_ref).
  const std::vector<double> ones(run.u.size(), 1.0);
  const Eigen::VectorXd c = linear_fit({simulate_tf(start, delay0, run.dt_s, du, run.window_samples),
                                        simulate_tf(start, delay0, run.dt_s, ones, run.window_samples)},
                                       run.y);
  const double gain = c[1] != 0.0 ? c[1] : 1.0;
  const double y0 = c[0];
  const double u_ref0 = run.u.front() - c[2] / gain;
  const ScaledTf s0 = scaled_of(start, run.dt_s);
  Eigen::VectorXd theta(sc.m + 1 + sc.n);
  // s0 is scaled at the geometric mean of its poles' magnitudes, which is sc.w0.
  for (int i = 0; i <= sc.m; ++i) theta[i] = gain * s0.beta[static_cast<std::size_t>(i)];
  for (int i = 0; i < sc.n; ++i) theta[sc.m + 1 + i] = s0.alpha[static_cast<std::size_t>(i)];

  std::vector<ParameterSpec> specs;
  const double largest = theta.cwiseAbs().maxCoeff();
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    const bool numerator = i <= sc.m;
    const std::string name = numerator ? fmt::format("b{}", i) : fmt::format("a{}", i - sc.m - 1);
    const double floor = numerator ? 0.1 * std::abs(theta[0]) : 1e-3 * largest;
    specs.push_back({name, theta[i], Transform::linear, std::max({std::abs(theta[i]), floor, 1e-12})});
  }
  const Eigen::Index n_theta = theta.size();
  if (options.fit_delay) specs.push_back({"delay_s", delay0, Transform::linear, run.dt_s});
  const Eigen::Index i_y0 = static_cast<Eigen::Index>(specs.size());
  double spread = 0.0;
  for (double v : run.y) spread = std::max(spread, std::abs(v - y0));
  specs.push_back({"y0", y0, Transform::linear, std::max({std::abs(y0), spread, 1e-12})});
  const Eigen::Index i_u_ref = i_y0 + 1;
  const auto [u_lo, u_hi] = std::minmax_element(run.u.begin(), run.u.end());
  specs.push_back({"u_ref", u_ref0, Transform::linear, std::max(*u_hi - *u_lo, 1e-12)});

  const ResidualFunction residual = [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    const double delay = options.fit_delay ? std::abs(p[n_theta]) : 0.0;
    const std::vector<double> y_hat = simulate_scaled(from_theta(sc, p.head(n_theta)), delay, run.dt_s,
                                                      deviations(run.u, p[i_u_ref]), run.window_samples);
    for (std::size_t k = 0; k < y_hat.size(); ++k)
      r[static_cast<Eigen::Index>(k)] = p[i_y0] + y_hat[k] - run.y[k];
  };
  NlsOptions nls_options;
  nls_options.central_differences = true;
  nls_options.max_evaluations = 20000;
  TimeTfFit out;
  out.fit.nls = least_squares(specs, run.y.size(), residual, nls_options);
  if (!out.fit.nls.converged) {
    fail("{}: the time-domain transfer-function fit did not converge: {}", run.source, out.fit.nls.reason);
  }
  if (options.fit_delay) out.fit.nls.values[n_theta] = std::abs(out.fit.nls.values[n_theta]);
  tf_core::complete(sc, n_theta, options.fit_delay, largest, out.fit);
  out.fit.points = run.y.size();
  out.u_ref = out.fit.nls.values[i_u_ref];
  out.u_ref_se = out.fit.nls.std_errors[i_u_ref];
  out.y0 = out.fit.nls.values[i_y0];
  out.y0_se = out.fit.nls.std_errors[i_y0];
  std::vector<double> y_hat(run.y.size());
  double sq = 0.0;
  for (std::size_t k = 0; k < y_hat.size(); ++k) {
    y_hat[k] = run.y[k] + out.fit.nls.residuals[static_cast<Eigen::Index>(k)];
    sq += out.fit.nls.residuals[static_cast<Eigen::Index>(k)] *
          out.fit.nls.residuals[static_cast<Eigen::Index>(k)];
  }
  out.rms = std::sqrt(sq / static_cast<double>(y_hat.size()));
  out.fit_percent = fit_percent_of(run.y, y_hat);
  return out;
}

double validation_fit_percent(const TimeTfFit& fit, const TimeSeries& run) {
  // y ~ y0 + s_u - u_ref s_1 with the fitted model: (y0, u_ref) by linear least squares.
  const std::vector<double> s_u =
      simulate_tf(fit.fit.tf, fit.fit.delay_s, run.dt_s, run.u, run.window_samples);
  const std::vector<double> s_1 = simulate_tf(fit.fit.tf, fit.fit.delay_s, run.dt_s,
                                              std::vector<double>(run.u.size(), 1.0), run.window_samples);
  std::vector<double> rest(run.y.size());
  for (std::size_t k = 0; k < rest.size(); ++k) rest[k] = run.y[k] - s_u[k];
  const Eigen::VectorXd c = linear_fit({s_1}, rest);
  std::vector<double> y_hat(rest.size());
  for (std::size_t k = 0; k < y_hat.size(); ++k) y_hat[k] = s_u[k] + c[0] + c[1] * s_1[k];
  return fit_percent_of(run.y, y_hat);
}

}  // namespace mcg::fit
