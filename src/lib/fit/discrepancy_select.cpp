// The discrepancy fit's regression: the measured series of a run, forward stepwise selection
// and the selected terms in physical units (see discrepancy_parts.hpp).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/units.hpp"
#include "fit/discrepancy_parts.hpp"
#include "fit/nls.hpp"  // covariance_statistics

namespace mcg::fit::discrepancy_detail {

Measured measured_of(const Run& run, std::array<double, 2> i_map) {
  Measured m;
  const std::size_t rows = run.inputs.t_s.size();
  for (std::size_t o = 0; o < run.outputs.size(); ++o) {
    const double per = rad_s_per_unit(run.outputs[o]);
    if (per > 0.0) {
      m.w.resize(rows);
      for (std::size_t n = 0; n < rows; ++n) m.w[n] = run.measured[o][n] * per * run.gear_ratio;
    }
    if (run.outputs[o] == "i") {
      m.i = run.measured[o];
      for (double& i : m.i) i = i_map[0] * i + i_map[1];
    }
  }
  if (m.w.empty()) return m;
  // A counting estimator reports the mean speed over its window, half a window late: the
  // speed at t is read at t + W/2 (the angle's harmonics are phase-sensitive to it).
  if (run.rpm_estimator && rows > 1) {
    const double dt = (run.inputs.t_s.back() - run.inputs.t_s.front()) / static_cast<double>(rows - 1);
    const double shift = 0.5 * run.rpm_estimator->window_s / dt;
    const auto whole = static_cast<std::size_t>(shift);
    const double frac = shift - static_cast<double>(whole);
    std::vector<double> w(rows, std::numeric_limits<double>::quiet_NaN());
    for (std::size_t n = 0; n + whole + 1 < rows; ++n)
      w[n] = (1.0 - frac) * m.w[n + whole] + frac * m.w[n + whole + 1];
    m.w = std::move(w);
  }
  if (m.i.empty()) m.i.assign(rows, std::numeric_limits<double>::quiet_NaN());
  m.theta.assign(rows, 0.0);
  for (std::size_t n = 1; n < rows; ++n) {
    const double dt = run.inputs.t_s[n] - run.inputs.t_s[n - 1];
    const double step = 0.5 * (m.w[n] + m.w[n - 1]) * dt;
    m.theta[n] = m.theta[n - 1] + (std::isfinite(step) ? step : 0.0);
  }
  return m;
}

Eigen::MatrixXd matrix_of(const std::vector<std::vector<double>>& rows,
                          const std::vector<std::size_t>& cols) {
  Eigen::MatrixXd A(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (std::size_t j = 0; j < cols.size(); ++j) {
      A(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(j)) = rows[r][cols[j]];
    }
  }
  return A;
}

Solved solve(const Eigen::MatrixXd& A, const Eigen::VectorXd& y) {
  Solved s;
  s.x = A.colPivHouseholderQr().solve(y);
  const Eigen::VectorXd residual = A * s.x - y;
  s.rss = residual.squaredNorm();
  Eigen::MatrixXd correlation;
  double sigma = 0.0;
  covariance_statistics(A, residual, s.se, correlation, sigma);
  return s;
}

std::string signed_number(double v) { return fmt::format("{}{:.4g}", v < 0.0 ? "- " : "+ ", std::abs(v)); }

namespace {

Eigen::Map<const Eigen::VectorXd> vector_of(const Rows& rows) {
  return {rows.y.data(), static_cast<Eigen::Index>(rows.y.size())};
}

}  // namespace

std::vector<std::size_t> select_forward(const std::vector<Column>& library, const Rows& train,
                                        const Rows& validate) {
  const Eigen::Map<const Eigen::VectorXd> Y = vector_of(train);
  const Eigen::Map<const Eigen::VectorXd> Yv = vector_of(validate);
  auto validation_rss = [&](const std::vector<std::size_t>& set, const Eigen::VectorXd& xi) {
    if (validate.y.empty()) return 0.0;
    return set.empty() ? Yv.squaredNorm() : (Yv - matrix_of(validate.phi, set) * xi).squaredNorm();
  };
  std::vector<std::size_t> active;
  const double rss0 = Y.squaredNorm();
  double rss = rss0;
  double rss_v = validation_rss({}, {});
  while (active.size() < library.size()) {
    std::vector<std::pair<double, std::vector<std::size_t>>> options;
    std::vector<Eigen::VectorXd> solutions;
    for (std::size_t k = 0; k < library.size(); ++k) {
      if (std::find(active.begin(), active.end(), k) != active.end()) continue;
      if (library[k].cos_of_pair) continue;  // joins with its sin column
      std::vector<std::size_t> trial = active;
      trial.push_back(k);
      if (library[k].order != 0.0) trial.push_back(k + 1);
      Solved fit = solve(matrix_of(train.phi, trial), Y);
      if (rss - fit.rss < k_discrepancy_threshold * rss0) continue;
      // A harmonic stands clear by its amplitude (its sin or cos part alone may be near 0).
      const auto j0 = static_cast<Eigen::Index>(active.size());
      const bool clear = library[k].order != 0.0 ? std::hypot(fit.x[j0], fit.x[j0 + 1]) >=
                                                       3.0 * std::max(fit.se[j0], fit.se[j0 + 1])
                                                 : std::abs(fit.x[j0]) >= 3.0 * fit.se[j0];
      if (!clear) continue;
      options.emplace_back(fit.rss, std::move(trial));
      solutions.push_back(std::move(fit.x));
    }
    std::vector<std::size_t> order(options.size());
    for (std::size_t q = 0; q < order.size(); ++q) order[q] = q;
    std::sort(order.begin(), order.end(),
              [&](std::size_t x, std::size_t y2) { return options[x].first < options[y2].first; });
    bool joined = false;
    for (std::size_t q : order) {
      const double r_v = validation_rss(options[q].second, solutions[q]);
      if (!validate.y.empty() && !(r_v < rss_v)) continue;
      active = options[q].second;
      rss = options[q].first;
      rss_v = r_v;
      joined = true;
      break;
    }
    if (!joined) break;
  }
  return active;
}

Described describe(const std::vector<Column>& library, const std::vector<std::size_t>& set, const Rows& train,
                   const Rows& validate, const std::function<std::string(std::size_t)>& lead) {
  Described out;
  const Eigen::Map<const Eigen::VectorXd> Y = vector_of(train);
  const Eigen::Map<const Eigen::VectorXd> Yv = vector_of(validate);
  const Eigen::MatrixXd A = matrix_of(train.phi, set);
  out.fit = solve(A, Y);
  const Eigen::VectorXd& coef = out.fit.x;
  out.train_pct = 100.0 * (1.0 - out.fit.rss / Y.squaredNorm());
  out.validation_pct =
      validate.y.empty()
          ? 0.0
          : 100.0 * (1.0 - (Yv - matrix_of(validate.phi, set) * coef).squaredNorm() / Yv.squaredNorm());
  for (std::size_t j = 0; j < set.size(); ++j) {
    const Column& col = library[set[j]];
    if (col.cos_of_pair) continue;  // joins its sin column, the one before
    const auto J = static_cast<Eigen::Index>(j);
    DiscrepancyTerm t;
    t.basis = col.text;
    t.reading = col.reading;
    t.coefficient = coef[J];
    t.std_error = out.fit.se[J];
    t.unit = col.unit;
    t.shape = col.shape;
    if (col.order != 0.0) {
      const double cs = coef[J];
      const double cc = coef[J + 1];
      const double amp = std::hypot(cs, cc);
      const double ses = out.fit.se[J];
      const double sec = out.fit.se[J + 1];
      const std::string prefix = lead(set[j]);
      t.order = col.order;
      t.phase_rad = std::atan2(cc, cs);
      t.coefficient = amp;
      t.std_error = std::hypot(cs * ses, cc * sec) / amp;
      t.phase_se_rad = std::hypot(cc * ses, cs * sec) / (amp * amp);
      t.basis = fmt::format("{}sin({:g} theta + phase)", prefix, col.order);
      t.equation = fmt::format("{} {} * {}sin({:g} theta {} rad)", signed_number(amp), col.unit, prefix,
                               col.order, signed_number(t.phase_rad));
      out.parts.push_back((A.col(J) * cs + A.col(J + 1) * cc).norm());
    } else {
      t.equation = fmt::format("{} {} * {}", signed_number(t.coefficient), t.unit, col.text);
      out.parts.push_back((A.col(J) * coef[J]).norm());
    }
    out.terms.push_back(std::move(t));
  }
  return out;
}

}  // namespace mcg::fit::discrepancy_detail
