// The catalog-free discrepancy fit (see discrepancy.hpp for the method).
#include "fit/discrepancy.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "common/checked.hpp"
#include "common/units.hpp"
#include "fit/gap_parts.hpp"
#include "fit/nls.hpp"  // covariance_statistics
#include "model/effects/compiled.hpp"

namespace mcg::fit {

namespace {

// Library bases, T = basis(k, theta, w, i, t) with the coefficient in k[3] (model::ShaftTerm's
// convention): the shaft's angle and speed, the motor current and the time of the run.
using Basis = double (*)(const std::array<double, 4>&, double, double, double, double);

double b_const(const std::array<double, 4>& k, double, double, double, double) { return k[3]; }
double b_sign(const std::array<double, 4>& k, double, double w, double, double) {
  return k[3] * std::tanh(w / k[0]);
}
double b_w(const std::array<double, 4>& k, double, double w, double, double) { return k[3] * w; }
double b_w_abs_w(const std::array<double, 4>& k, double, double w, double, double) {
  return k[3] * w * std::abs(w);
}
double b_w3(const std::array<double, 4>& k, double, double w, double, double) { return k[3] * w * w * w; }
double b_stribeck(const std::array<double, 4>& k, double, double w, double, double) {
  return k[3] * std::tanh(w / k[0]) * std::exp(-std::pow(std::abs(w) / k[1], k[2]));
}
double b_sin(const std::array<double, 4>& k, double theta, double, double, double) {
  return k[3] * std::sin(k[0] * theta + k[1]);
}
/// Kt i: a torque-constant error, or a gain error of a measured current.
double b_i(const std::array<double, 4>& k, double, double, double i, double) { return k[3] * i; }
/// |i| sign(w): friction that grows with the load the current carries.
double b_abs_i(const std::array<double, 4>& k, double, double w, double i, double) {
  return k[3] * std::abs(i) * std::tanh(w / k[0]);
}
/// i sin(N theta + phase): a torque constant that varies with the angle (commutation ripple).
double b_i_sin(const std::array<double, 4>& k, double theta, double, double i, double) {
  return k[3] * i * std::sin(k[0] * theta + k[1]);
}
/// sign(w) exp(-t/tau): a friction level that fades over the run (bearings warming up).
double b_decay(const std::array<double, 4>& k, double, double w, double, double t) {
  return k[3] * std::tanh(w / k[0]) * std::exp(-t / k[1]);
}
/// A voltage V (k[3]) against the current in the armature circuit, as the torque it costs:
/// -(Kt/R) V tanh(i / 0.01 A), k[0] = Kt/R (brush_drop's shape).
double b_drop(const std::array<double, 4>& k, double, double, double i, double) {
  return -k[0] * k[3] * std::tanh(i / 0.01);
}

/// One library column: a basis with its numbers (k[3] = 1 to evaluate).
struct Candidate {
  std::string text;
  std::string unit;
  Basis basis = nullptr;
  std::array<double, 4> k{0.0, 0.0, 0.0, 1.0};
  double order = 0.0;  ///< harmonic order for sin/cos columns (paired), else 0
  std::string reading;  ///< what it is physically
};

/// A run's measured motor speed (rad/s) and angle (rad), or empty when speed is not measured.
struct Measured {
  std::vector<double> w;
  std::vector<double> theta;
  std::vector<double> i;  ///< measured current, NaN where not measured
};

Measured measured_of(const Run& run) {
  Measured m;
  const std::size_t rows = run.inputs.t_s.size();
  for (std::size_t o = 0; o < run.outputs.size(); ++o) {
    const double per = run.outputs[o] == "rpm" ? k_rad_s_per_rpm : run.outputs[o] == "omega" ? 1.0 : 0.0;
    if (per > 0.0) {
      m.w.resize(rows);
      for (std::size_t n = 0; n < rows; ++n) m.w[n] = run.measured[o][n] * per * run.gear_ratio;
    }
    if (run.outputs[o] == "i") m.i = run.measured[o];
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

/// Weak-form rows of one run from row `first` on: y (the torque integral the model lacks) and
/// the library's integrals, one row per window in which the shaft moves throughout.
void windows(const model::Compiled& c, const Run& run, std::size_t first,
             const std::vector<Candidate>& library, double w_max, std::vector<double>& y,
             std::vector<std::vector<double>>& phi) {
  const Measured m = measured_of(run);
  if (m.w.empty()) return;
  const model::Inputs& in = run.inputs;
  const std::size_t rows = in.t_s.size();
  if (rows < 2) return;
  const double dt_typ = (in.t_s.back() - in.t_s.front()) / static_cast<double>(rows - 1);
  const auto width = clamp_to_integer(std::round(k_discrepancy_window_s / dt_typ), std::size_t{4},
                                      std::numeric_limits<std::size_t>::max());
  const model::Machine& mm = c.p.motor;
  const model::Machine& mg = c.p.generator;
  const double R = mm.R_ohm + c.R_on2;
  // The current along the measured speed (measured where it is).
  std::vector<double> i(rows, 0.0);
  for (std::size_t n = 0; n + 1 < rows; ++n) {
    const double cur = std::isfinite(m.i[n]) ? m.i[n] : i[n];
    i[n] = cur;
    const double v = std::clamp(in.v_V[n], -c.p.supply_V, c.p.supply_V);
    const double w = std::isfinite(m.w[n]) ? m.w[n] : 0.0;
    const double i_ss = (v - mm.Ke_V_s_rad * w) / R;
    i[n + 1] = i_ss + (cur - i_ss) * std::exp(-R * (in.t_s[n + 1] - in.t_s[n]) / mm.L_H);
  }
  if (std::isfinite(m.i[rows - 1])) i[rows - 1] = m.i[rows - 1];
  auto torque = [&](std::size_t n) {
    const int clutch = static_cast<int>(in.clutch[n]);
    const model::Friction& f = clutch == 2 ? c.rigid : c.motor_side[static_cast<std::size_t>(clutch)];
    const double w = m.w[n];
    const double dir = w > 0.0 ? 1.0 : -1.0;
    double T = mm.Kt_Nm_A * i[n] - dir * c.kinetic(f, std::abs(w)) +
               c.extra_motor_torque(m.theta[n], w, i[n], in.t_s[n]);
    if (clutch == 2 && std::isfinite(in.r_load_ohm[n])) {
      T -= mg.Kt_Nm_A * mg.Ke_V_s_rad * w / (mg.R_ohm + in.r_load_ohm[n]);
    }
    return T;
  };
  // Near rest the shaft may be held by static friction while the estimator still reports a
  // speed: windows stay above three counts of the estimator (or 1 % of the top speed) and
  // keep one direction.
  double w_min = 0.01 * w_max;
  if (run.rpm_estimator) {
    w_min = std::max(w_min, 3.0 * 2.0 * std::numbers::pi /
                                (run.rpm_estimator->counts_per_rev * run.rpm_estimator->window_s) *
                                run.gear_ratio);
  }
  for (std::size_t a = first; a + width < rows; a += width) {
    const std::size_t b = a + width;
    bool ok = true;
    for (std::size_t n = a; n <= b && ok; ++n) {
      ok = std::isfinite(m.w[n]) && std::abs(m.w[n]) >= w_min && (m.w[n] > 0.0) == (m.w[a] > 0.0) &&
           in.clutch[n] == in.clutch[a] && in.r_load_ohm[n] == in.r_load_ohm[a];
    }
    if (!ok) continue;
    const double J = in.clutch[a] == 2.0 ? c.J_total : mm.J_kg_m2;
    double integral = 0.0;
    std::vector<double> row(library.size(), 0.0);
    for (std::size_t n = a; n < b; ++n) {
      const double h = 0.5 * (in.t_s[n + 1] - in.t_s[n]);
      integral += h * (torque(n) + torque(n + 1));
      for (std::size_t k = 0; k < library.size(); ++k) {
        const Candidate& cand = library[k];
        row[k] += h * (cand.basis(cand.k, m.theta[n], m.w[n], i[n], in.t_s[n]) +
                       cand.basis(cand.k, m.theta[n + 1], m.w[n + 1], i[n + 1], in.t_s[n + 1]));
      }
    }
    y.push_back(J * (m.w[b] - m.w[a]) - integral);
    phi.push_back(std::move(row));
  }
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

/// The least-squares solution of A x = y, its residual sum of squares and the standard errors
/// of x (covariance_statistics: infinite for a column the data do not determine).
struct Solved {
  Eigen::VectorXd x;
  Eigen::VectorXd se;
  double rss = 0.0;
};

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

}  // namespace

DiscrepancyResult fit_discrepancy(const model::Model& reference, const GapData& data,
                                  const std::vector<double>& angle_orders,
                                  const std::vector<OutputFloor>& floors) {
  DiscrepancyResult out;
  out.model = reference;
  const std::size_t f_rpm = gap_detail::floor_index(floors, "rpm");
  if (f_rpm == std::string::npos) {
    out.note = "the discrepancy fit needs the measured speed";
    return out;
  }
  out.floor_rpm = floors[f_rpm].floor;
  const model::Compiled c(reference);
  // Speed scales of the library from the training runs.
  double w_max = 0.0;
  for (const Run& run : data.train) {
    for (double w : measured_of(run).w) {
      if (std::isfinite(w)) w_max = std::max(w_max, std::abs(w));
    }
  }
  if (!(w_max > 0.0)) {
    out.note = "the shaft never turns in the training runs";
    return out;
  }
  const double eps = 0.01 * w_max;
  double t_span = 0.0;
  for (const Run& run : data.train) {
    if (!run.inputs.t_s.empty()) t_span = std::max(t_span, run.inputs.t_s.back());
  }
  const model::Machine& mm = reference.params.motor;
  std::vector<Candidate> library = {
      {"1",
       "N m",
       b_const,
       {0.0, 0.0, 0.0, 1.0},
       0.0,
       "a constant torque: a load, or an offset of a measured current"},
      {"sign(w)", "N m", b_sign, {eps, 0.0, 0.0, 1.0}, 0.0, "against the motion: Coulomb friction"},
      {"w", "N m s/rad", b_w, {0.0, 0.0, 0.0, 1.0}, 0.0, "proportional to speed: viscous friction"},
      {"w|w|",
       "N m s^2/rad^2",
       b_w_abs_w,
       {0.0, 0.0, 0.0, 1.0},
       0.0,
       "quadratic in speed: windage, a fan or fluid drag"},
      {"w^3",
       "N m s^3/rad^3",
       b_w3,
       {0.0, 0.0, 0.0, 1.0},
       0.0,
       "cubic in speed: drag rising faster than quadratic"},
      {"i",
       "N m/A",
       b_i,
       {0.0, 0.0, 0.0, 1.0},
       0.0,
       "scales with the current: a torque-constant error or a current-sensor gain"},
      {"|i| sign(w)",
       "N m/A",
       b_abs_i,
       {eps, 0.0, 0.0, 1.0},
       0.0,
       "friction that grows with the load the current carries"},
      {"-(Kt/R) tanh(i/0.01)",
       "V",
       b_drop,
       {mm.Kt_Nm_A / mm.R_ohm, 0.0, 0.0, 1.0},
       0.0,
       "a voltage drop against the current in the motor circuit: brush contact drop"},
  };
  // Stribeck-like drops at a twentieth and a fifth of the top speed, exponential and Gaussian.
  for (double scale : {0.05, 0.2}) {
    const double ws = scale * w_max;
    const std::string reading = "friction falling from rest with speed: Stribeck";
    library.push_back(
        {fmt::format("sign(w) exp(-|w|/{:.3g})", ws), "N m", b_stribeck, {eps, ws, 1.0, 1.0}, 0.0, reading});
    library.push_back({fmt::format("sign(w) exp(-(w/{:.3g})^2)", ws),
                       "N m",
                       b_stribeck,
                       {eps, ws, 2.0, 1.0},
                       0.0,
                       reading});
  }
  // Friction levels that fade over a run, on a grid of a tenth, a third and all of its span.
  for (double share : {0.1, 0.33, 1.0}) {
    const double tau = share * t_span;
    if (!(tau > 0.0)) continue;
    library.push_back(
        {fmt::format("sign(w) exp(-t/{:.3g})", tau),
         "N m",
         b_decay,
         {eps, tau, 0.0, 1.0},
         0.0,
         fmt::format("a friction level that fades during the run (tau {:.3g} s): warm-up", tau)});
  }
  // Angle harmonics: once per revolution always, and the residual's strongest orders; each
  // as a torque and as a current-scaled torque.
  std::vector<double> orders = {1.0};
  for (double order : angle_orders) {
    if (order != 1.0) orders.push_back(order);
  }
  // A harmonic as its sin and cos pair (the cos is the sin a quarter turn on).
  const auto add_harmonic = [&](const std::string& prefix, const char* unit, const auto& basis, double order,
                                const std::string& per) {
    library.push_back(
        {fmt::format("{}sin({:g} theta)", prefix, order), unit, basis, {order, 0.0, 0.0, 1.0}, order, per});
    library.push_back({fmt::format("{}cos({:g} theta)", prefix, order),
                       unit,
                       basis,
                       {order, std::numbers::pi / 2.0, 0.0, 1.0},
                       order,
                       per});
  };
  for (double order : orders) {
    add_harmonic("", "N m", b_sin, order,
                 order == 1.0
                     ? "once per revolution: an imbalance, a bent shaft or an eccentric load"
                     : fmt::format("{:g} per revolution: cogging or a load periodic in the angle", order));
  }
  for (double order : orders) {
    add_harmonic(
        "i ", "N m/A", b_i_sin, order,
        fmt::format("scales with the current, {:g} per revolution: torque ripple (Kt varying with the angle)",
                    order));
  }
  out.library_size = library.size();

  std::vector<double> y;
  std::vector<std::vector<double>> phi;
  for (const Run& run : data.train) windows(c, run, 0, library, w_max, y, phi);
  std::vector<double> yv;
  std::vector<std::vector<double>> phiv;
  for (const ScoredRun& sr : data.validate) windows(c, sr.run, sr.first_scored, library, w_max, yv, phiv);
  out.train_windows = y.size();
  out.validation_windows = yv.size();
  // Forward selection fits a few columns at a time: the windows must outnumber the library and
  // be enough (k_discrepancy_min_windows) to tell a term from noise at three standard errors.
  const std::size_t needed = std::max(k_discrepancy_min_windows, library.size() + 1);
  if (y.size() < needed) {
    out.note =
        fmt::format("too few windows in which the shaft turns ({} of 20 ms; {} needed)", y.size(), needed);
    return out;
  }
  const Eigen::Map<const Eigen::VectorXd> Y(y.data(), static_cast<Eigen::Index>(y.size()));

  // Forward stepwise sparse regression: of the terms (a harmonic with its sin/cos pair) that
  // remove at least k_discrepancy_threshold of the training residual the model leaves and
  // stand three standard errors from 0, the one that lowers the training residual most joins,
  // provided it lowers the validation residual too (a term that does not carry over to
  // held-out runs describes the training runs' noise); one at a time, so of collinear
  // columns only one joins.
  std::vector<std::size_t> active;
  const Eigen::Map<const Eigen::VectorXd> Yv(yv.data(), static_cast<Eigen::Index>(yv.size()));
  auto validation_rss = [&](const std::vector<std::size_t>& set, const Eigen::VectorXd& xi) {
    if (yv.empty()) return 0.0;
    return set.empty() ? Yv.squaredNorm() : (Yv - matrix_of(phiv, set) * xi).squaredNorm();
  };
  const double rss0 = Y.squaredNorm();
  double rss = rss0;
  double rss_v = validation_rss({}, {});
  while (active.size() < library.size()) {
    std::vector<std::pair<double, std::vector<std::size_t>>> options;
    std::vector<Eigen::VectorXd> solutions;
    for (std::size_t k = 0; k < library.size(); ++k) {
      if (std::find(active.begin(), active.end(), k) != active.end()) continue;
      if (library[k].order != 0.0 && library[k].k[1] != 0.0) continue;  // joins with its sin column
      std::vector<std::size_t> trial = active;
      trial.push_back(k);
      if (library[k].order != 0.0) trial.push_back(k + 1);
      Solved fit = solve(matrix_of(phi, trial), Y);
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
      if (!yv.empty() && !(r_v < rss_v)) continue;
      active = options[q].second;
      rss = options[q].first;
      rss_v = r_v;
      joined = true;
      break;
    }
    if (!joined) break;
  }
  if (active.empty()) {
    out.note = "no term of the library explains a clear part of the torque residual";
    return out;
  }
  // The selected terms as a model: coefficients in physical units with their standard errors,
  // sin/cos pairs combined into one harmonic, largest part of the fitted residual first.
  auto described = [&](const std::vector<std::size_t>& set, model::Model& m,
                       std::vector<DiscrepancyTerm>& terms, double& train_pct, double& validation_pct) {
    const Eigen::MatrixXd A = matrix_of(phi, set);
    const Solved fit = solve(A, Y);
    const Eigen::VectorXd& coef = fit.x;
    train_pct = 100.0 * (1.0 - fit.rss / Y.squaredNorm());
    validation_pct =
        yv.empty() ? 0.0
                   : 100.0 * (1.0 - (Yv - matrix_of(phiv, set) * coef).squaredNorm() / Yv.squaredNorm());
    m = reference;
    std::vector<std::pair<double, DiscrepancyTerm>> ranked;
    for (std::size_t j = 0; j < set.size(); ++j) {
      const Candidate& cand = library[set[j]];
      const auto J = static_cast<Eigen::Index>(j);
      DiscrepancyTerm t;
      t.basis = cand.text;
      t.reading = cand.reading;
      t.coefficient = coef[J];
      t.std_error = fit.se[J];
      t.unit = cand.unit;
      if (cand.order != 0.0) {
        if (cand.k[1] != 0.0) continue;  // the cos column joins its sin column, the next one
        const double cs = coef[J];
        const double cc = coef[J + 1];
        const double amp = std::hypot(cs, cc);
        const double ses = fit.se[J];
        const double sec = fit.se[J + 1];
        const std::string lead = cand.basis == b_i_sin ? "i " : "";
        t.order = cand.order;
        t.phase_rad = std::atan2(cc, cs);
        t.coefficient = amp;
        t.std_error = std::hypot(cs * ses, cc * sec) / amp;
        t.phase_se_rad = std::hypot(cc * ses, cs * sec) / (amp * amp);
        t.basis = fmt::format("{}sin({:g} theta + phase)", lead, cand.order);
        t.equation = fmt::format("{} {} * {}sin({:g} theta {} rad)", signed_number(amp), cand.unit, lead,
                                 cand.order, signed_number(t.phase_rad));
        m.shaft_terms.push_back({t.equation, nullptr, {cand.order, t.phase_rad, 0.0, amp}, cand.basis});
        ranked.emplace_back((A.col(J) * cs + A.col(J + 1) * cc).norm(), t);
        continue;
      }
      t.equation = fmt::format("{} {} * {}", signed_number(t.coefficient), t.unit, cand.text);
      std::array<double, 4> k = cand.k;
      k[3] = t.coefficient;
      m.shaft_terms.push_back({t.equation, nullptr, k, cand.basis});
      ranked.emplace_back((A.col(J) * coef[J]).norm(), t);
    }
    std::stable_sort(ranked.begin(), ranked.end(),
                     [](const auto& x, const auto& z) { return x.first > z.first; });
    terms.clear();
    for (auto& [part, t] : ranked) terms.push_back(std::move(t));
  };
  // Kept only where the held-out runs gain: the model with the terms is simulated on the
  // validation runs, and a term (a harmonic with its pair) whose removal, the rest refitted,
  // does not raise the validation speed RMS leaves; the terms leave altogether when the
  // model with them does not beat the reference there.
  out.rms_before_rpm = gap_detail::evaluate(reference, data, floors).rms[f_rpm];
  auto held_out = [&](const std::vector<std::size_t>& set) {
    model::Model m;
    std::vector<DiscrepancyTerm> terms;
    double tp = 0.0;
    double vp = 0.0;
    described(set, m, terms, tp, vp);
    return gap_detail::evaluate(m, data, floors).rms[f_rpm];
  };
  auto without = [&](const std::vector<std::size_t>& set, std::size_t j) {
    std::vector<std::size_t> rest;
    const bool pair = library[set[j]].order != 0.0;
    for (std::size_t q = 0; q < set.size(); ++q) {
      if (q != j && !(pair && q == j + 1)) rest.push_back(set[q]);
    }
    return rest;
  };
  double rms_all = held_out(active);
  while (active.size() > 1) {
    std::size_t drop = active.size();
    double best = rms_all;
    for (std::size_t j = 0; j < active.size(); ++j) {
      if (library[active[j]].order != 0.0 && library[active[j]].k[1] != 0.0) continue;
      const std::vector<std::size_t> rest = without(active, j);
      if (rest.empty()) continue;
      const double r = held_out(rest);
      if (r <= best) {
        best = r;
        drop = j;
      }
    }
    if (drop == active.size()) break;
    out.dropped.push_back(library[active[drop]].text);
    active = without(active, drop);
    rms_all = best;
  }
  if (!(rms_all < out.rms_before_rpm)) {
    out.note = fmt::format(
        "the terms found ({}) do not lower the validation speed RMS once simulated with the model; none kept",
        library[active.front()].text);
    out.rms_after_rpm = out.rms_before_rpm;
    return out;
  }
  described(active, out.model, out.terms, out.train_explained_pct, out.validation_explained_pct);
  out.rms_after_rpm = rms_all;
  return out;
}

std::vector<model::Effect> catalog_seeds(const DiscrepancyResult& result, const model::Model& reference) {
  std::vector<model::Effect> seeds;
  for (const DiscrepancyTerm& t : result.terms) {
    const bool torque_harmonic = t.order != 0.0 && t.basis.rfind("sin(", 0) == 0;
    if (torque_harmonic && !reference.effect("cogging")) {
      model::Effect e = model::default_effect("cogging");
      e.set("T_c_Nm", std::min(t.coefficient, 0.02));
      e.set("N_per_rev", t.order);
      e.set("phase_rad", t.phase_rad);
      seeds.push_back(std::move(e));
    } else if (t.basis == "-(Kt/R) tanh(i/0.01)" && t.coefficient > 0.0 && !reference.effect("brush_drop")) {
      model::Effect e = model::default_effect("brush_drop");
      e.set("V_b_V", std::min(t.coefficient, 3.0));
      seeds.push_back(std::move(e));
    }
  }
  return seeds;
}

}  // namespace mcg::fit
