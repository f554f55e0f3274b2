// Closed-loop step responses and their metrics.
#include "linsys/response.hpp"

#include "common/error.hpp"
#include "linsys/analysis.hpp"
#include "linsys/c2d.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

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

/// Last time |x(t)| > band, interpolated to the crossing back into the band; 0 if never out.
double last_exit(const std::vector<double>& t, const std::vector<double>& x, double band) {
  for (std::size_t i = x.size(); i-- > 0;) {
    if (std::abs(x[i]) > band) {
      if (i + 1 >= x.size()) return t[i];
      const double a = std::abs(x[i]);
      const double b = std::abs(x[i + 1]);
      const double f = (a - band) / (a - b);
      return t[i] + f * (t[i + 1] - t[i]);
    }
  }
  return 0.0;
}

/// First time y·sign reaches level, interpolated; nan if never.
double first_reach(const std::vector<double>& t, const std::vector<double>& y, double level) {
  for (std::size_t i = 0; i < y.size(); ++i) {
    if (y[i] >= level) {
      if (i == 0) return t[0];
      const double f = (level - y[i - 1]) / (y[i] - y[i - 1]);
      return t[i - 1] + f * (t[i] - t[i - 1]);
    }
  }
  return std::nan("");
}

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

StepResponse step_response(const Tf& plant, const std::optional<Tf>& controller, double t_end_s, int points) {
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
  }
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
  out.final_value = is_stable(closed_loop_poles(exact_loop), exact_loop.domain)
                        ? exact_closed.dc_gain()
                        : std::numeric_limits<double>::quiet_NaN();
  return out;
}

StepMetrics step_metrics(const std::vector<double>& t, const std::vector<double>& y, double yf, double r) {
  StepMetrics m;
  m.final_value = yf;
  m.steady_state_error = r - yf;
  if (y.empty() || !std::isfinite(yf) || yf == 0.0) {
    m.rise_time_s = m.peak_time_s = m.settling_time_s = m.transient_time_s = std::nan("");
    m.peak = y.empty() ? std::nan("") : *std::max_element(y.begin(), y.end());
    m.overshoot_pct = std::nan("");
    return m;
  }
  const double sign = yf > 0.0 ? 1.0 : -1.0;
  std::vector<double> ys(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) ys[i] = sign * y[i];
  const double af = std::abs(yf);
  m.rise_time_s = first_reach(t, ys, 0.9 * af) - first_reach(t, ys, 0.1 * af);
  const auto peak = std::max_element(ys.begin(), ys.end());
  m.peak = sign * *peak;
  m.peak_time_s = t[static_cast<std::size_t>(peak - ys.begin())];
  m.overshoot_pct = std::max(0.0, 100.0 * (*peak - af) / af);
  std::vector<double> dev(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) dev[i] = y[i] - yf;
  m.settling_time_s = last_exit(t, dev, 0.02 * af);
  double emax = 0.0;
  for (double v : y) emax = std::max(emax, std::abs(r - v));
  m.transient_time_s = last_exit(t, dev, 0.02 * emax);
  return m;
}

}  // namespace mcg::linsys
