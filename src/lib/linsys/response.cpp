// Closed-loop step responses and their metrics.
#include "linsys/response.hpp"

#include "common/error.hpp"
#include "linsys/analysis.hpp"
#include "linsys/c2d.hpp"

#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>

namespace mcg::linsys {

namespace {

/// 10 time constants of the slowest stable pole, or of the slowest corner if unstable.
double auto_duration(const std::vector<Complex>& poles, Domain domain, double dt_s) {
  double slowest = 0.0;
  for (const Complex& p : poles) {
    double sigma = 0.0;
    if (domain == Domain::s) {
      sigma = -p.real();
    } else {
      if (std::abs(p) == 0.0) continue;
      sigma = -std::log(std::abs(p)) / dt_s;
    }
    if (sigma > 0.0 && (slowest == 0.0 || sigma < slowest)) slowest = sigma;
  }
  if (slowest == 0.0) return domain == Domain::z ? 1000.0 * dt_s : 10.0;
  return 10.0 / slowest;
}

/// x(t) between samples where the response is known in closed form; empty otherwise.
using Exact = std::function<double(double)>;

/// The time in [t0, t1] where x crosses level: by bisection on the exact x if there is one and
/// it brackets the level, else by linear interpolation of the samples x0, x1.
double crossing(double t0, double t1, double x0, double x1, double level, const Exact& exact) {
  if (exact && (exact(t0) - level) * (exact(t1) - level) <= 0.0) {
    const bool rising = exact(t0) < level;
    for (int i = 0; i < 60 && t1 - t0 > 1e-15 * std::max(1.0, t1); ++i) {
      const double c = 0.5 * (t0 + t1);
      if ((exact(c) < level) == rising) {
        t0 = c;
      } else {
        t1 = c;
      }
    }
    return 0.5 * (t0 + t1);
  }
  return t0 + (level - x0) / (x1 - x0) * (t1 - t0);
}

/// The time after which |x| stays within band: the crossing back into the band (continuous),
/// or the first sample inside after the last one outside (sampled, which counts |x| >= band as
/// outside, as python-control does); 0 if never out, NaN if still out at the end.
double settle_time(const std::vector<double>& t, const std::vector<double>& x, double band, bool sampled,
                   const Exact& abs_x) {
  for (std::size_t i = x.size(); i-- > 0;) {
    const bool out = sampled ? std::abs(x[i]) >= band : std::abs(x[i]) > band;
    if (!out) continue;
    if (i + 1 >= x.size()) return std::nan("");
    if (sampled) return t[i + 1];
    return crossing(t[i], t[i + 1], std::abs(x[i]), std::abs(x[i + 1]), band, abs_x);
  }
  return t.empty() ? std::nan("") : t[0];
}

/// Index of the first sample with y >= level, or y.size() if none.
std::size_t first_index(const std::vector<double>& y, double level) {
  for (std::size_t i = 0; i < y.size(); ++i) {
    if (y[i] >= level) return i;
  }
  return y.size();
}

/// First time y reaches level: the crossing (continuous) or the sample's time (sampled); NaN if never.
double first_reach(const std::vector<double>& t, const std::vector<double>& y, double level, bool sampled,
                   const Exact& exact) {
  const std::size_t i = first_index(y, level);
  if (i == y.size()) return std::nan("");
  if (i == 0 || sampled) return t[i];
  return crossing(t[i - 1], t[i], y[i - 1], y[i], level, exact);
}

/// The step response of a continuous rational G from rest and its slope at time t, from
/// exp([[A B],[0 0]] t) = [[Φ Γ],[0 1]]: x(t) = Γ, y = C x + D, y' = C (A x + B).
class ClosedFormStep {
 public:
  explicit ClosedFormStep(const Tf& g) : m_ss(realise(g)) {
    const Eigen::Index n = m_ss.a.rows();
    m_aug = Eigen::MatrixXd::Zero(n + 1, n + 1);
    m_aug.topLeftCorner(n, n) = m_ss.a;
    m_aug.topRightCorner(n, 1) = m_ss.b;
  }
  Eigen::Index order() const { return m_ss.a.rows(); }
  double value(double t) const { return (m_ss.c * state(t))(0) + m_ss.d; }
  double slope(double t) const { return (m_ss.c * (m_ss.a * state(t) + m_ss.b))(0); }

 private:
  Eigen::VectorXd state(double t) const {
    const Eigen::Index n = m_ss.a.rows();
    const Eigen::MatrixXd e = (m_aug * t).exp();
    return e.topRightCorner(n, 1);
  }
  StateSpace m_ss;
  Eigen::MatrixXd m_aug;
};

}  // namespace

std::vector<double> simulate(const Tf& h0, const std::vector<double>& input) {
  const Tf h = fold_delay(h0, "simulation");
  const Poly den = trim(h.den);
  const Poly num0 = trim(h.num);
  if (num0.size() > den.size()) fail("cannot simulate an improper transfer function {}", tf_text(h));
  const std::size_t n = den.size();
  Poly num(n, 0.0);
  for (std::size_t i = 0; i < num0.size(); ++i) num[n - num0.size() + i] = num0[i];
  std::vector<double> a(n);
  std::vector<double> b(n);
  for (std::size_t i = 0; i < n; ++i) {
    a[i] = den[i] / den[0];
    b[i] = num[i] / den[0];
  }
  std::vector<double> state(n, 0.0);
  std::vector<double> out(input.size());
  for (std::size_t k = 0; k < input.size(); ++k) {
    const double u = input[k];
    const double y = b[0] * u + (n > 1 ? state[0] : 0.0);
    for (std::size_t i = 1; i < n; ++i) {
      state[i - 1] = b[i] * u - a[i] * y + (i < n - 1 ? state[i] : 0.0);
    }
    out[k] = y;
  }
  return out;
}

namespace {

/// Open loop: y = C·G·r and u = C·r, each exact at the samples through its ZOH transform
/// (a step is constant between samples; ZOH handles a fractional delay exactly).
StepResponse open_step(const Tf& plant, const std::optional<Tf>& controller, double t_end_s, int points) {
  StepResponse out;
  Tf c;
  c.domain = plant.domain;
  c.dt_s = plant.dt_s;
  if (controller) c = *controller;
  Tf loop = series(c, plant);
  Tf to_y;
  Tf to_u;
  double h = 0.0;
  double t_end = t_end_s;
  if (plant.discrete()) {
    to_y = fold_delay(loop, "loop");
    to_u = fold_delay(c, "controller");
    h = plant.dt_s;
    if (t_end <= 0.0) t_end = auto_duration(roots(to_y.den), Domain::z, h);
  } else {
    if (t_end <= 0.0) t_end = auto_duration(roots(loop.den), Domain::s, 0.0);
    h = t_end / points;
    to_y = c2d(loop, h, C2dMethod::zoh, 0.0, "loop");
    to_u = c2d(c, h, C2dMethod::zoh, 0.0, "controller");
    out.rational = loop;
    out.rational->delay_s = 0.0;
    out.shift_s = loop.delay_s;
  }
  out.sampled = plant.discrete();
  const double count = std::floor(t_end / h + 1e-9) + 1.0;
  if (count > 2e6) fail("step response of {} samples is too long; shorten --t-end", count);
  const auto n = static_cast<std::size_t>(count);
  const std::vector<double> r(n, 1.0);
  out.t_s.resize(n);
  for (std::size_t k = 0; k < n; ++k) out.t_s[k] = static_cast<double>(k) * h;
  out.y = simulate(to_y, r);
  out.u = simulate(to_u, r);
  Tf folded = loop.discrete() ? fold_delay(loop, "loop") : loop;
  folded.delay_s = 0.0;
  out.final_value = is_stable(roots(trim(folded.den)), folded.domain) ? folded.dc_gain()
                                                                      : std::numeric_limits<double>::quiet_NaN();
  return out;
}

}  // namespace

StepResponse step_response(const Tf& plant, const std::optional<Tf>& controller, double t_end_s, int points,
                           bool open_loop) {
  if (open_loop) return open_step(plant, controller, t_end_s, points);
  Tf g = plant;
  Tf c;
  c.domain = g.domain;
  c.dt_s = g.dt_s;
  if (controller) c = *controller;
  StepResponse out;
  double h = 0.0;
  double t_end = t_end_s;
  if (g.discrete()) {
    g = fold_delay(g, "plant");
    c = fold_delay(c, "controller");
    h = g.dt_s;
  } else {
    if (t_end <= 0.0) t_end = auto_duration(closed_loop_poles(series(c, g)), Domain::s, 0.0);
    h = t_end / points;
    const double tau = g.delay_s + c.delay_s;
    long m = 0;
    if (tau > 0.0) {
      m = std::max(1L, static_cast<long>(std::ceil(tau / h)));
      h = tau / static_cast<double>(m);
      out.note = fmt::format("continuous delay simulated as {} samples of {} s around the ZOH loop", m, h);
    }
    Tf g0 = g;
    g0.delay_s = 0.0;
    Tf c0 = c;
    c0.delay_s = 0.0;
    g = c2d(g0, h, C2dMethod::zoh, 0.0, "plant");
    c = c2d(c0, h, C2dMethod::zoh, 0.0, "controller");
    g.den = mul(g.den, monomial(static_cast<int>(m)));
    g = cancel_origin(g);
  }
  // r → y = CG/(1 + CG) and r → u = C/(1 + CG), in the domain of g and c.
  auto closed_pair = [](const Tf& cc, const Tf& gg, Tf& to_y, Tf& to_u) {
    const Poly den = add(mul(cc.den, gg.den), mul(cc.num, gg.num));
    to_y = gg;
    to_y.num = mul(cc.num, gg.num);
    to_y.den = den;
    to_y.delay_s = 0.0;
    to_u = to_y;
    to_u.num = mul(cc.num, gg.den);
  };
  Tf closed;
  Tf to_u;
  closed_pair(c, g, closed, to_u);
  if (!plant.discrete() && plant.delay_s + (controller ? controller->delay_s : 0.0) == 0.0) {
    // Without a delay the continuous closed loop is rational: its ZOH transform is exact for a step.
    Tf cs = controller ? *controller : Tf{};
    Tf cy;
    Tf cu;
    closed_pair(cs, plant, cy, cu);
    closed = c2d(cy, h, C2dMethod::zoh, 0.0, "closed loop");
    to_u = c2d(cu, h, C2dMethod::zoh, 0.0, "closed loop");
    out.rational = cy;
  }
  out.sampled = plant.discrete();
  if (t_end <= 0.0) t_end = auto_duration(roots(closed.den), Domain::z, h);
  const double count = std::floor(t_end / h + 1e-9) + 1.0;
  if (count > 2e6) fail("step response of {} samples is too long; shorten --t-end", count);
  const auto n = static_cast<std::size_t>(count);
  std::vector<double> r(n, 1.0);
  out.t_s.resize(n);
  for (std::size_t k = 0; k < n; ++k) out.t_s[k] = static_cast<double>(k) * h;
  out.y = simulate(closed, r);
  out.u = simulate(to_u, r);
  const Tf exact_loop = controller ? series(*controller, plant) : plant;
  Tf exact_closed = exact_loop.discrete() ? fold_delay(exact_loop, "loop") : exact_loop;
  exact_closed.delay_s = 0.0;
  exact_closed = feedback(exact_closed);
  out.final_value = closed_loop_stable(exact_loop)
                        ? exact_closed.dc_gain()
                        : std::numeric_limits<double>::quiet_NaN();
  return out;
}

namespace {

/// step_metrics, with the response between samples where it is known exactly (exact_y).
StepMetrics metrics(const std::vector<double>& t, const std::vector<double>& y, double yf, double r,
                    const StepLimits& limits, bool sampled, const Exact& exact_y) {
  StepMetrics m;
  m.final_value = yf;
  m.steady_state_error = r - yf;
  std::size_t peak = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    if (std::abs(y[i]) > std::abs(y[peak])) peak = i;
  }
  m.peak = y.empty() ? std::nan("") : std::abs(y[peak]);
  m.peak_time_s = y.empty() ? std::nan("") : t[peak];
  if (y.empty() || !std::isfinite(yf) || yf == 0.0) {
    m.rise_time_s = m.settling_time_s = m.transient_time_s = std::nan("");
    m.settling_min = m.settling_max = m.overshoot_pct = m.undershoot_pct = std::nan("");
    return m;
  }
  const double sign = yf > 0.0 ? 1.0 : -1.0;
  std::vector<double> ys(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) ys[i] = sign * y[i];
  const double af = std::abs(yf);
  Exact y_signed;
  Exact dev_abs;
  if (exact_y) {
    y_signed = [&](double x) { return sign * exact_y(x); };
    dev_abs = [&](double x) { return std::abs(exact_y(x) - yf); };
  }
  m.rise_time_s = first_reach(t, ys, limits.rise_high * af, sampled, y_signed) -
                  first_reach(t, ys, limits.rise_low * af, sampled, y_signed);
  const std::size_t risen = first_index(ys, limits.rise_high * af);
  if (risen < y.size()) {
    const auto [lo, hi] = std::minmax_element(y.begin() + static_cast<std::ptrdiff_t>(risen), y.end());
    m.settling_min = *lo;
    m.settling_max = *hi;
    if (!sampled) {
      // A continuous y passes through the high rise level itself at the rise instant.
      m.settling_min = std::min(m.settling_min, sign * limits.rise_high * af);
      m.settling_max = std::max(m.settling_max, sign * limits.rise_high * af);
    }
  } else {
    m.settling_min = m.settling_max = std::nan("");
  }
  const auto [lo, hi] = std::minmax_element(ys.begin(), ys.end());
  m.overshoot_pct = std::max(0.0, 100.0 * (*hi - af) / af);
  m.undershoot_pct = std::max(0.0, -100.0 * *lo / af);
  std::vector<double> dev(y.size());
  double dev_max = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    dev[i] = y[i] - yf;
    dev_max = std::max(dev_max, std::abs(dev[i]));
  }
  m.settling_time_s = settle_time(t, dev, limits.settling * af, sampled, dev_abs);
  m.transient_time_s = settle_time(t, dev, limits.settling * dev_max, sampled, dev_abs);
  return m;
}

}  // namespace

StepMetrics step_metrics(const std::vector<double>& t, const std::vector<double>& y, double yf, double r,
                         const StepLimits& limits, bool sampled) {
  return metrics(t, y, yf, r, limits, sampled, Exact{});
}

StepMetrics step_info(const StepResponse& s, double reference, const StepLimits& limits) {
  if (s.sampled || !s.rational || s.y.size() < 3) return step_metrics(s.t_s, s.y, s.final_value, reference, limits, s.sampled);
  const ClosedFormStep step(*s.rational);
  if (step.order() == 0) return step_metrics(s.t_s, s.y, s.final_value, reference, limits, false);
  const double shift = s.shift_s;
  const Exact exact_y = [&](double t) { return t < shift ? 0.0 : step.value(t - shift); };
  StepMetrics m = metrics(s.t_s, s.y, s.final_value, reference, limits, false, exact_y);
  // An extremum of y at an inner sample k: y' changes sign between its neighbours.
  const auto extremum = [&](std::size_t k, double dir) -> std::optional<std::pair<double, double>> {
    if (k == 0 || k + 1 >= s.y.size()) return std::nullopt;
    double a = std::max(0.0, s.t_s[k - 1] - shift);
    double b = s.t_s[k + 1] - shift;
    if (!(dir * step.slope(a) >= 0.0 && dir * step.slope(b) <= 0.0)) return std::nullopt;
    for (int i = 0; i < 60 && b - a > 1e-15 * std::max(1.0, b); ++i) {
      const double c = 0.5 * (a + b);
      if (dir * step.slope(c) >= 0.0) {
        a = c;
      } else {
        b = c;
      }
    }
    const double t = 0.5 * (a + b);
    const double v = step.value(t);
    if (dir * v < dir * s.y[k]) return std::nullopt;
    return std::pair{t + shift, v};
  };
  const auto at = [&](auto it) { return static_cast<std::size_t>(it - s.y.begin()); };
  const auto peak = std::max_element(s.y.begin(), s.y.end(), [](double x, double y) { return std::abs(x) < std::abs(y); });
  if (const auto e = extremum(at(peak), *peak > 0.0 ? 1.0 : -1.0)) {
    m.peak = std::abs(e->second);
    m.peak_time_s = e->first;
  }
  const double yf = s.final_value;
  if (!std::isfinite(yf) || yf == 0.0) return m;
  const double sign = yf > 0.0 ? 1.0 : -1.0;
  const double af = std::abs(yf);
  const auto [lo, hi] = std::minmax_element(s.y.begin(), s.y.end());
  const auto high_side = sign > 0.0 ? hi : lo;
  const auto low_side = sign > 0.0 ? lo : hi;
  if (const auto e = extremum(at(high_side), sign)) {
    m.overshoot_pct = std::max(m.overshoot_pct, 100.0 * (sign * e->second - af) / af);
  }
  if (const auto e = extremum(at(low_side), -sign)) {
    m.undershoot_pct = std::max(m.undershoot_pct, -100.0 * sign * e->second / af);
  }
  std::size_t risen = 0;
  while (risen < s.y.size() && sign * s.y[risen] < limits.rise_high * af) ++risen;
  if (risen < s.y.size()) {
    const auto [rlo, rhi] = std::minmax_element(s.y.begin() + static_cast<std::ptrdiff_t>(risen), s.y.end());
    if (const auto e = extremum(at(rhi), 1.0)) m.settling_max = std::max(m.settling_max, e->second);
    if (const auto e = extremum(at(rlo), -1.0)) m.settling_min = std::min(m.settling_min, e->second);
  }
  return m;
}

}  // namespace mcg::linsys
