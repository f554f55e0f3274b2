// Transfer-function fit: Levy, Sanathanan-Koerner, then Levenberg-Marquardt on log(G/H).
//
// Coefficients live in the scaled variable x = s / w0, with w0 the geometric mean of the
// band, so that the powers of x stay near 1 and the linear systems are well conditioned:
//   G = B(x) / A(x),  B = sum_{i<=m} b_i x^i,  A = x^n + sum_{i<n} a_i x^i  (monic).
#include "fit/tf.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "common/error.hpp"
#include "fit/tf_core.hpp"
#include "measurement/measurement.hpp"

namespace mcg::fit {

using Complex = std::complex<double>;

namespace tf_core {

namespace {

Complex polyval_ascending(const Eigen::VectorXd& c, Eigen::Index count, Eigen::Index offset, Complex x) {
  Complex y = 0.0;
  for (Eigen::Index i = count - 1; i >= 0; --i) y = y * x + c[offset + i];
  return y;
}

}  // namespace

Complex Scaled::numerator(const Eigen::VectorXd& theta, Complex x) const {
  return polyval_ascending(theta, m + 1, 0, x);
}

Complex Scaled::denominator(const Eigen::VectorXd& theta, Complex x) const {
  return polyval_ascending(theta, n, m + 1, x) + std::pow(x, n);
}

Complex Scaled::model(const Eigen::VectorXd& theta, double w) const {
  const Complex x(0.0, w / w0);
  return numerator(theta, x) / denominator(theta, x);
}

RationalTf to_s_domain(const Scaled& sc, const Eigen::VectorXd& theta) {
  RationalTf tf;
  for (int i = sc.m; i >= 0; --i) tf.num.push_back(theta[i] / std::pow(sc.w0, i));
  tf.den.push_back(1.0 / std::pow(sc.w0, sc.n));
  for (int i = sc.n - 1; i >= 0; --i) tf.den.push_back(theta[sc.m + 1 + i] / std::pow(sc.w0, i));
  const double norm = tf.den.back() != 0.0 ? tf.den.back() : tf.den.front();
  for (double& c : tf.num) c /= norm;
  for (double& c : tf.den) c /= norm;
  return tf;
}

double lowest_nonzero(const std::vector<double>& c) {
  for (auto it = c.rbegin(); it != c.rend(); ++it) {
    if (*it != 0.0) return *it;
  }
  return 0.0;
}

std::vector<Factor> factors_of(const std::vector<double>& coefficients) {
  std::vector<Factor> out;
  const double scale = std::max(1e-300, std::abs(lowest_nonzero(coefficients)));
  for (const Complex& r : polynomial_roots(coefficients)) {
    if (r.imag() < 0.0 && std::abs(r.imag()) > 1e-9 * std::abs(r)) continue;
    Factor f;
    f.corner_rad_s = std::abs(r);
    if (std::abs(r.imag()) > 1e-9 * std::abs(r)) {
      f.complex_pair = true;
      f.zeta = -r.real() / f.corner_rad_s;
    }
    if (f.corner_rad_s < 1e-12 * std::max(1.0, scale)) f.corner_rad_s = 0.0;
    f.unstable = r.real() > 0.0;
    out.push_back(f);
  }
  std::sort(out.begin(), out.end(), [](const Factor& a, const Factor& b) { return a.corner_rad_s < b.corner_rad_s; });
  return out;
}

Eigen::VectorXd reported(const Scaled& sc, const Eigen::VectorXd& theta) {
  const RationalTf tf = to_s_domain(sc, theta);
  std::vector<double> q{lowest_nonzero(tf.num) / lowest_nonzero(tf.den)};
  for (const auto* list : {&tf.den, &tf.num}) {
    for (const Factor& f : factors_of(*list)) {
      q.push_back(f.corner_rad_s);
      if (f.complex_pair) q.push_back(f.zeta);
    }
  }
  return Eigen::Map<Eigen::VectorXd>(q.data(), static_cast<Eigen::Index>(q.size()));
}

void complete(const Scaled& sc, Eigen::Index n_theta, bool fit_delay, double largest, TfFit& fit) {
  const Eigen::VectorXd best = fit.nls.values.head(n_theta);
  if (fit_delay) {
    fit.delay_s = fit.nls.values[n_theta];
    fit.delay_se = fit.nls.std_errors[n_theta];
  }
  fit.tf = to_s_domain(sc, best);
  fit.gain = lowest_nonzero(fit.tf.num) / lowest_nonzero(fit.tf.den);
  fit.poles = factors_of(fit.tf.den);
  fit.zeros = factors_of(fit.tf.num);

  // Delta method: cov(q) = G cov(theta) G^T with G = dq/dtheta by central differences.
  const Eigen::VectorXd q0 = reported(sc, best);
  const Eigen::Index nq = q0.size();
  const Eigen::Index nt = best.size();
  Eigen::MatrixXd g(nq, nt);
  bool same_shape = true;
  for (Eigen::Index j = 0; j < nt; ++j) {
    const double h = 1e-6 * std::max(std::abs(best[j]), 1e-8 * largest);
    Eigen::VectorXd tp = best;
    Eigen::VectorXd tm = best;
    tp[j] += h;
    tm[j] -= h;
    const Eigen::VectorXd qp = reported(sc, tp);
    const Eigen::VectorXd qm = reported(sc, tm);
    if (qp.size() != nq || qm.size() != nq) {
      same_shape = false;
      break;
    }
    g.col(j) = (qp - qm) / (2.0 * h);
  }
  Eigen::VectorXd q_se = Eigen::VectorXd::Constant(nq, std::numeric_limits<double>::quiet_NaN());
  if (same_shape && fit.nls.std_errors.head(nt).allFinite()) {
    const Eigen::VectorXd se = fit.nls.std_errors.head(nt);
    const Eigen::MatrixXd cov = se.asDiagonal() * fit.nls.correlation.topLeftCorner(nt, nt) * se.asDiagonal();
    q_se = (g * cov * g.transpose()).diagonal().cwiseSqrt();
  }
  Eigen::Index qi = 0;
  fit.gain_se = q_se[qi++];
  for (auto* list : {&fit.poles, &fit.zeros}) {
    for (Factor& f : *list) {
      f.corner_se = q_se[qi++];
      if (f.complex_pair) f.zeta_se = q_se[qi++];
    }
  }
}

}  // namespace tf_core

namespace {

using tf_core::Scaled;
using tf_core::to_s_domain;

struct Point {
  double w_rad_s;
  Complex h;
  double weight;
};

/// One linearised least-squares solve: min sum_k |(B - H A) sqrt(w_k) / |A_prev||^2.
Eigen::VectorXd linear_step(const Scaled& sc, const std::vector<Point>& pts,
                            const Eigen::VectorXd* previous) {
  const Eigen::Index unknowns = sc.m + 1 + sc.n;
  const auto rows = static_cast<Eigen::Index>(2 * pts.size());
  Eigen::MatrixXd a(rows, unknowns);
  Eigen::VectorXd b(rows);
  for (std::size_t k = 0; k < pts.size(); ++k) {
    const Complex x(0.0, pts[k].w_rad_s / sc.w0);
    double c = std::sqrt(pts[k].weight);
    if (previous != nullptr) c /= std::abs(sc.denominator(*previous, x));
    const auto r = static_cast<Eigen::Index>(2 * k);
    Complex xp = 1.0;
    for (int i = 0; i <= sc.m; ++i, xp *= x) {
      a(r, i) = c * xp.real();
      a(r + 1, i) = c * xp.imag();
    }
    xp = 1.0;
    for (int i = 0; i < sc.n; ++i, xp *= x) {
      const Complex term = -pts[k].h * xp;
      a(r, sc.m + 1 + i) = c * term.real();
      a(r + 1, sc.m + 1 + i) = c * term.imag();
    }
    const Complex rhs = pts[k].h * std::pow(x, sc.n);
    b[r] = c * rhs.real();
    b[r + 1] = c * rhs.imag();
  }
  return a.colPivHouseholderQr().solve(b);
}

std::string num_text(double x, int digits) { return fmt::format("{:.{}g}", x, digits); }

std::string factor_text(const Factor& f, int digits) {
  if (f.corner_rad_s == 0.0) return "s";
  const std::string w = num_text(f.corner_rad_s, digits);
  if (f.complex_pair) {
    return fmt::format("((s/{})^2+{}*(s/{})+1)", w, num_text(2.0 * f.zeta, digits), w);
  }
  return f.unstable ? fmt::format("(1-s/{})", w) : fmt::format("(s/{}+1)", w);
}

std::string product_text(const std::vector<Factor>& factors, int digits) {
  std::string out;
  for (const Factor& f : factors) {
    if (!out.empty()) out += '*';
    out += factor_text(f, digits);
  }
  return out;
}

}  // namespace

Complex RationalTf::operator()(Complex s) const {
  Complex n = 0.0;
  for (double c : num) n = n * s + c;
  Complex d = 0.0;
  for (double c : den) d = d * s + c;
  return n / d;
}

std::vector<Complex> polynomial_roots(const std::vector<double>& coefficients) {
  std::size_t first = 0;
  while (first < coefficients.size() && coefficients[first] == 0.0) ++first;
  std::size_t last = coefficients.size();
  std::vector<Complex> roots;
  while (last > first + 1 && coefficients[last - 1] == 0.0) {
    roots.emplace_back(0.0, 0.0);
    --last;
  }
  if (last <= first + 1) return roots;
  const auto degree = static_cast<Eigen::Index>(last - first - 1);
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(degree, degree);
  for (Eigen::Index i = 0; i < degree; ++i) {
    companion(0, i) = -coefficients[first + 1 + static_cast<std::size_t>(i)] / coefficients[first];
    if (i + 1 < degree) companion(i + 1, i) = 1.0;
  }
  const Eigen::VectorXcd eig = companion.eigenvalues();
  for (Eigen::Index i = 0; i < eig.size(); ++i) roots.push_back(eig[i]);
  return roots;
}

FrequencyResponse read_frequency_response(const table::Table& table) {
  FrequencyResponse fr;
  fr.source = table.source;
  table::require_increasing(table, "f_hz");
  table::require_finite(table, "mag_db");
  table::require_finite(table, "phase_deg");
  fr.f_hz = table.col("f_hz");
  fr.mag_db = table.col("mag_db");
  fr.phase_deg = table.col("phase_deg");
  fr.units = table.meta.get("response").value_or("");
  for (std::size_t k = 0; k < fr.f_hz.size(); ++k) {
    if (!(fr.f_hz[k] > 0.0)) fail("{}:{}: column 'f_hz': frequency must be positive", table.source, table.line_of(k));
  }
  const std::size_t arrow = fr.units.rfind("-> ");
  const bool rpm_out = arrow != std::string::npos && fr.units.substr(arrow) == "-> rpm";
  if (const auto text = table.meta.get("rpm_estimator"); text && rpm_out) {
    fr.output_window_s = measurement::parse_rpm_estimator(*text, table.source + ": rpm_estimator").window_s;
  }
  if (table.has("coherence")) {
    fr.coherence = table.col("coherence");
    for (std::size_t k = 0; k < fr.coherence.size(); ++k) {
      const double c = fr.coherence[k];
      // nan: the estimator could not judge it (lines over one period); the fit then weighs the point 1.
      if (!std::isnan(c) && !(c >= 0.0 && c <= 1.0)) {
        fail("{}:{}: column 'coherence': {} is outside 0..1", table.source, table.line_of(k), c);
      }
    }
  }
  if (fr.output_window_s > 0.0) {
    // Near a zero of W (f = k / T_w) the data holds no response: such points are left out, counted.
    constexpr double k_min_window_gain = 0.05;
    std::size_t kept = 0;
    for (std::size_t k = 0; k < fr.f_hz.size(); ++k) {
      const Complex sw(0.0, 2.0 * std::numbers::pi * fr.f_hz[k] * fr.output_window_s);
      const Complex w = (1.0 - std::exp(-sw)) / sw;
      if (std::abs(w) < k_min_window_gain) {
        ++fr.window_zeros;
        continue;
      }
      fr.f_hz[kept] = fr.f_hz[k];
      fr.mag_db[kept] = fr.mag_db[k] - 20.0 * std::log10(std::abs(w));
      fr.phase_deg[kept] = fr.phase_deg[k] - std::arg(w) * 180.0 / std::numbers::pi;
      if (!fr.coherence.empty()) fr.coherence[kept] = fr.coherence[k];
      ++kept;
    }
    fr.f_hz.resize(kept);
    fr.mag_db.resize(kept);
    fr.phase_deg.resize(kept);
    if (!fr.coherence.empty()) fr.coherence.resize(kept);
  }
  return fr;
}

TfFit fit_tf(const FrequencyResponse& response, const TfFitOptions& options) {
  if (options.poles < 1) fail("--poles must be at least 1");
  if (options.zeros < 0 || options.zeros > options.poles) {
    fail("--zeros must be between 0 and the number of poles ({})", options.poles);
  }
  std::vector<Point> pts;
  for (std::size_t k = 0; k < response.f_hz.size(); ++k) {
    const double f = response.f_hz[k];
    if (f < options.f_min_hz || f > options.f_max_hz) continue;
    double weight = 1.0;
    if (options.use_coherence && !response.coherence.empty() && !std::isnan(response.coherence[k])) {
      const double g2 = std::min(response.coherence[k], 0.999);
      weight = g2 / (1.0 - g2);
    }
    if (weight <= 0.0) continue;
    const double mag = std::pow(10.0, response.mag_db[k] / 20.0);
    pts.push_back({2.0 * std::numbers::pi * f, std::polar(mag, response.phase_deg[k] * std::numbers::pi / 180.0), weight});
  }
  const int unknowns = options.zeros + 1 + options.poles;
  if (pts.size() < static_cast<std::size_t>(unknowns)) {
    fail("{}: too short: {} usable frequencies for {} coefficients", response.source, pts.size(), unknowns);
  }
  const Scaled sc{options.zeros, options.poles, std::sqrt(pts.front().w_rad_s * pts.back().w_rad_s)};

  // Linear stages on the response with a trial delay removed; returns the start and its cost.
  const auto start_for = [&](double delay_s, double& cost) {
    std::vector<Point> shifted = pts;
    for (Point& pt : shifted) pt.h *= std::polar(1.0, pt.w_rad_s * delay_s);
    Eigen::VectorXd theta = linear_step(sc, shifted, nullptr);
    for (int it = 0; it < options.sk_iterations; ++it) {
      const Eigen::VectorXd next = linear_step(sc, shifted, &theta);
      const double change = (next - theta).norm() / std::max(1e-300, next.norm());
      theta = next;
      if (change < 1e-12) break;
    }
    cost = 0.0;
    for (const Point& pt : shifted) cost += pt.weight * std::norm(std::log(sc.model(theta, pt.w_rad_s) / pt.h));
    return theta;
  };
  double delay0 = 0.0;
  double best_cost = 0.0;
  Eigen::VectorXd theta = start_for(0.0, best_cost);
  if (options.fit_delay) {
    constexpr int k_grid = 40;
    const double max_delay = std::numbers::pi / pts.back().w_rad_s;
    for (int g = 1; g <= k_grid; ++g) {
      double cost = 0.0;
      const double d = max_delay * g / k_grid;
      const Eigen::VectorXd candidate = start_for(d, cost);
      if (candidate.allFinite() && cost < best_cost) {
        best_cost = cost;
        theta = candidate;
        delay0 = d;
      }
    }
  }
  if (!theta.allFinite()) fail("{}: the linearised fit is singular (no excitation across the band?)", response.source);

  std::vector<ParameterSpec> specs;
  const double largest = theta.cwiseAbs().maxCoeff();
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    const std::string name = i <= sc.m ? fmt::format("b{}", i) : fmt::format("a{}", i - sc.m - 1);
    specs.push_back({name, theta[i], Transform::linear, std::max(std::abs(theta[i]), 1e-8 * largest)});
  }
  const Eigen::Index n_theta = theta.size();
  if (options.fit_delay) specs.push_back({"delay_s", delay0, Transform::linear, 0.1 / pts.back().w_rad_s});
  const ResidualFunction residual = [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    const double delay = options.fit_delay ? p[n_theta] : 0.0;
    if (delay < 0.0) {
      r.setConstant(std::numeric_limits<double>::quiet_NaN());
      return;
    }
    for (std::size_t k = 0; k < pts.size(); ++k) {
      const Complex e = (std::log(sc.model(p, pts[k].w_rad_s) / pts[k].h) - Complex(0.0, pts[k].w_rad_s * delay)) *
                        std::sqrt(pts[k].weight);
      r[static_cast<Eigen::Index>(2 * k)] = e.real();
      r[static_cast<Eigen::Index>(2 * k + 1)] = e.imag();
    }
  };
  NlsOptions nls_options;
  nls_options.central_differences = true;
  TfFit fit;
  fit.nls = least_squares(specs, 2 * pts.size(), residual, nls_options);
  if (!fit.nls.converged) fail("{}: the transfer-function fit did not converge: {}", response.source, fit.nls.reason);

  const Eigen::VectorXd best = fit.nls.values.head(n_theta);
  tf_core::complete(sc, n_theta, options.fit_delay, largest, fit);
  fit.points = pts.size();

  double sq_mag = 0.0;
  double sq_phase = 0.0;
  for (const Point& pt : pts) {
    const Complex e = std::log(sc.model(best, pt.w_rad_s) / pt.h) - Complex(0.0, pt.w_rad_s * fit.delay_s);
    sq_mag += std::pow(e.real() * 20.0 / std::log(10.0), 2);
    sq_phase += std::pow(e.imag() * 180.0 / std::numbers::pi, 2);
  }
  fit.rms_mag_db = std::sqrt(sq_mag / static_cast<double>(pts.size()));
  fit.rms_phase_deg = std::sqrt(sq_phase / static_cast<double>(pts.size()));

  return fit;
}

std::string format_factored(const TfFit& fit, int digits) {
  std::string out = num_text(fit.gain, digits);
  if (!fit.zeros.empty()) out += '*' + (fit.zeros.size() == 1 ? product_text(fit.zeros, digits)
                                                              : '(' + product_text(fit.zeros, digits) + ')');
  if (!fit.poles.empty()) {
    out += '/';
    out += fit.poles.size() == 1 ? product_text(fit.poles, digits) : '(' + product_text(fit.poles, digits) + ')';
  }
  return out;
}

}  // namespace mcg::fit
