// Margins by root finding on the exact frequency response; closed-loop poles; gain ranges.
#include "linsys/analysis.hpp"

#include <algorithm>
#include <cmath>

#include "common/error.hpp"
#include "common/units.hpp"

namespace mcg::linsys {

namespace {

/// Bisection of f on [a, b] with f(a), f(b) of opposite sign, to the last representable bit.
template <typename F>
double bisect(F f, double a, double b) {
  double fa = f(a);
  for (int i = 0; i < 200; ++i) {
    const double m = 0.5 * (a + b);
    if (m <= a || m >= b) break;
    const double fm = f(m);
    if (fm == 0.0) return m;
    if ((fm < 0.0) == (fa < 0.0)) {
      a = m;
      fa = fm;
    } else {
      b = m;
    }
  }
  return 0.5 * (a + b);
}

double wrap_pi(double x) {
  double r = std::remainder(x, 2.0 * k_pi);
  if (r <= -k_pi) r += 2.0 * k_pi;
  return r;
}

/// Sorts `v` and keeps one of each run of values equal within 1e-10 relative: the same crossing
/// found from two grid intervals. O(n log n): a long delay has a phase crossing per 2 pi / tau.
void sort_unique(std::vector<double>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end(),
                      [](double a, double b) { return std::abs(b - a) <= 1e-10 * std::max(std::abs(a), std::abs(b)); }),
          v.end());
}

/// Dense scan grid for crossovers of `le` on [lo, hi].
std::vector<double> scan_grid(const LoopEval& le, double lo, double hi) {
  // A corner that underflows (1e308*s/(s+1e-308): a root at 1e-616) or overflows must not make
  // the range infinite, nor its point count an out-of-range integer.
  lo = std::max(lo, 1e-300);
  hi = std::clamp(hi, lo * 10.0, 1e300);
  const double decades = std::log10(hi / lo);
  std::vector<double> w = log_grid(lo, hi, static_cast<int>(std::clamp(decades * 400.0, 200.0, 240000.0)));
  // Lightly damped roots turn the phase within a few percent of |root|: sample them finely.
  for (const FreqEval& fe : le.factors()) {
    const Tf& g = fe.tf();
    auto dense_near = [&](Complex r) {
      double wn = 0.0;
      double zeta = 1.0;
      if (g.discrete()) {
        if (std::abs(r) == 0.0) return;
        const Complex sr = std::log(r) / g.dt_s;
        wn = std::abs(sr);
        zeta = wn > 0.0 ? -sr.real() / wn : 1.0;
      } else {
        wn = std::abs(r);
        zeta = wn > 0.0 ? -r.real() / wn : 1.0;
      }
      if (wn <= 0.0 || std::abs(zeta) > 0.2) return;
      const double width = std::max(std::abs(zeta), 1e-6) * wn;
      const double centre = g.discrete() ? std::abs(std::arg(r)) / g.dt_s : std::abs(r.imag());
      for (int k = -200; k <= 200; ++k) {
        const double x = centre + width * k / 20.0;
        if (x > lo && x < hi) w.push_back(x);
      }
    };
    for (const Complex& z : fe.zeros()) dense_near(z);
    for (const Complex& p : fe.poles()) dense_near(p);
  }
  const double delay = le.delay_s();
  if (delay > 0.0) {
    const double step = k_pi / (4.0 * delay);
    const double n = std::min((hi - lo) / step, 200000.0);
    for (int k = 0; k <= static_cast<int>(n); ++k) w.push_back(lo + step * k);
  }
  std::sort(w.begin(), w.end());
  w.erase(std::unique(w.begin(), w.end()), w.end());
  w.erase(std::remove_if(w.begin(), w.end(), [&](double x) { return x < lo || x > hi; }), w.end());
  return w;
}

double dc_value(const Tf& g, double x) { return eval(g.num, x) / eval(g.den, x); }

/// Real points of L where it may sit on the negative real axis exactly: ω = 0 (no root at
/// s = 0 / z = 1) and, in z, ω = π/T.
void real_axis_points(const Tf& g, std::vector<double>& omegas, std::vector<double>& values) {
  const double x0 = g.discrete() ? 1.0 : 0.0;
  if (eval(g.den, x0) != 0.0) {
    omegas.push_back(0.0);
    values.push_back(dc_value(g, x0));
  }
  if (g.discrete() && eval(g.den, -1.0) != 0.0) {
    const double wn = k_pi / g.dt_s;
    omegas.push_back(wn);
    // A whole-sample delay e^(−jπk) = (−1)^k at Nyquist.
    const double k = std::round(g.delay_s / g.dt_s);
    values.push_back(dc_value(g, -1.0) * (std::fmod(k, 2.0) == 0.0 ? 1.0 : -1.0));
  }
}

}  // namespace

std::vector<double> log_grid(double lo, double hi, int n) {
  std::vector<double> w(static_cast<std::size_t>(n));
  const double a = std::log(lo);
  const double b = std::log(hi);
  for (int i = 0; i < n; ++i) w[static_cast<std::size_t>(i)] = std::exp(a + (b - a) * i / (n - 1));
  w.front() = lo;
  w.back() = hi;
  return w;
}

void default_range(const Tf& g, double& lo, double& hi) {
  const FreqEval fe(g);
  const std::vector<double> corners = fe.corner_frequencies();
  double cmin = 1.0;
  double cmax = 1.0;
  if (!corners.empty()) {
    cmin = *std::min_element(corners.begin(), corners.end());
    cmax = *std::max_element(corners.begin(), corners.end());
  }
  if (g.delay_s > 0.0) cmax = std::max(cmax, 1.0 / g.delay_s);
  lo = cmin * 1e-3;
  hi = cmax * 1e3;
  if (g.discrete()) {
    hi = k_pi / g.dt_s;
    lo = std::min(lo, hi * 1e-5);
  }
}

std::vector<double> scan_frequencies(const LoopEval& le) {
  double lo = 0.0;
  double hi = 0.0;
  le.range(lo, hi);
  return scan_grid(le, lo, hi);
}

Margins margins(const Tf& loop) {
  if (!loop.proper()) fail("margins need a proper loop transfer function, got {}", tf_text(loop));
  return margins(std::vector<Tf>{loop});
}

LoopEval::LoopEval(const std::vector<Tf>& factors) {
  for (const Tf& f : factors) {
    m_factors.emplace_back(f);
    if (f.discrete()) m_dt_s = m_dt_s == 0.0 ? f.dt_s : std::min(m_dt_s, f.dt_s);
  }
}

double LoopEval::log_mag(double w) const {
  double acc = 0.0;
  for (const FreqEval& f : m_factors) acc += f.log_mag(w);
  return acc;
}

double LoopEval::phase_rad(double w) const {
  double acc = 0.0;
  for (const FreqEval& f : m_factors) acc += f.phase_rad(w);
  return acc;
}

Complex LoopEval::value(double w) const {
  Complex acc(1.0, 0.0);
  for (const FreqEval& f : m_factors) acc *= f.value(w);
  return acc;
}

double LoopEval::delay_s() const {
  double acc = 0.0;
  for (const FreqEval& f : m_factors) acc += f.tf().delay_s;
  return acc;
}

void LoopEval::range(double& lo, double& hi) const {
  lo = INFINITY;
  hi = 0.0;
  bool integrating = false;
  bool differentiating = false;
  bool strictly_proper = false;
  for (const FreqEval& f : m_factors) {
    double a = 0.0;
    double b = 0.0;
    default_range(f.tf(), a, b);
    lo = std::min(lo, a);
    hi = std::max(hi, b);
    const Tf& g = f.tf();
    integrating = integrating || zeros_at_origin(g.den) > 0;
    differentiating = differentiating || zeros_at_origin(g.num) > 0;
    strictly_proper = strictly_proper || g.strictly_proper();
    if (g.discrete()) {
      for (const Complex& p : f.poles()) integrating = integrating || std::abs(p - Complex(1.0, 0.0)) < 1e-12;
      for (const Complex& z : f.zeros()) differentiating = differentiating || std::abs(z - Complex(1.0, 0.0)) < 1e-12;
    }
  }
  if (m_dt_s > 0.0) {
    hi = k_pi / m_dt_s;
    lo = std::min(lo, hi * 1e-5);
  }
  for (int i = 0; i < 40 && integrating && log_mag(lo) < std::log(1e4); ++i) lo /= 10.0;
  for (int i = 0; i < 40 && differentiating && log_mag(lo) > std::log(1e-4); ++i) lo /= 10.0;
  if (m_dt_s == 0.0) {
    for (int i = 0; i < 40 && strictly_proper && log_mag(hi) > std::log(1e-4); ++i) hi *= 10.0;
  }
}

Margins margins(const std::vector<Tf>& factors) {
  Margins m;
  for (const Tf& f : factors) {
    if (is_zero(f.num)) return m;
  }
  const LoopEval fe(factors);
  double lo = 0.0;
  double hi = 0.0;
  fe.range(lo, hi);
  const std::vector<double> w = scan_grid(fe, lo, hi);
  std::vector<double> lm(w.size());
  std::vector<double> ph(w.size());
  for (std::size_t i = 0; i < w.size(); ++i) {
    lm[i] = fe.log_mag(w[i]);
    ph[i] = fe.phase_rad(w[i]);
  }
  for (std::size_t i = 0; i + 1 < w.size(); ++i) {
    if (std::isfinite(lm[i]) && std::isfinite(lm[i + 1]) && (lm[i] > 0.0) != (lm[i + 1] > 0.0)) {
      m.gain_crossovers_rad_s.push_back(bisect([&](double x) { return fe.log_mag(x); }, w[i], w[i + 1]));
    } else if (lm[i] == 0.0) {
      m.gain_crossovers_rad_s.push_back(w[i]);
    }
    const double u0 = std::floor((ph[i] + k_pi) / (2.0 * k_pi));
    const double u1 = std::floor((ph[i + 1] + k_pi) / (2.0 * k_pi));
    if (u0 != u1) {
      const double target = 2.0 * k_pi * std::max(u0, u1) - k_pi;
      const double x = bisect([&](double v) { return fe.phase_rad(v) - target; }, w[i], w[i + 1]);
      if (std::abs(fe.phase_rad(x) - target) < 1e-6) m.phase_crossovers_rad_s.push_back(x);
    }
  }
  std::vector<double> axis_w;
  std::vector<double> axis_v;
  if (factors.size() == 1) real_axis_points(factors.front(), axis_w, axis_v);
  for (std::size_t i = 0; i < axis_w.size(); ++i) {
    if (axis_v[i] < 0.0) m.phase_crossovers_rad_s.push_back(axis_w[i]);
  }
  sort_unique(m.gain_crossovers_rad_s);
  sort_unique(m.phase_crossovers_rad_s);
  for (double x : m.gain_crossovers_rad_s) {
    const double pm = wrap_pi(fe.phase_rad(x) + k_pi);
    const double pm_deg = pm * 180.0 / k_pi;
    m.phase_margins_deg.push_back(pm_deg);
    const double dm = pm > 0.0 && x > 0.0 ? pm / x : std::numeric_limits<double>::quiet_NaN();
    m.delay_margins_s.push_back(dm);
    if (std::abs(pm_deg) < std::abs(m.pm_deg)) {
      m.pm_deg = pm_deg;
      m.pm_omega_rad_s = x;
    }
    if (std::isfinite(dm) && dm < m.dm_s) m.dm_s = dm;
  }
  for (double x : m.phase_crossovers_rad_s) {
    const double gm = std::exp(-fe.log_mag(x));
    m.gain_margins.push_back(gm);
    if (std::abs(std::log(gm)) < std::abs(std::log(m.gm))) {
      m.gm = gm;
      m.gm_omega_rad_s = x;
    }
  }
  return m;
}

namespace {

/// The closed loop's characteristic polynomial den + num; a continuous delay as its [6/6] Padé
/// approximant in x = s·τ, `tau_s` then the scale back to s (1 without a delay).
Poly characteristic(const Tf& loop, double& tau_s, bool* padded, int* den_degree = nullptr) {
  Tf l = loop;
  tau_s = 1.0;
  if (padded) *padded = false;
  if (l.discrete()) {
    l = fold_delay(l, "loop");
  } else if (l.delay_s > 0.0) {
    // Solved in x = s tau, where the Pade coefficients are O(1): in s their tau^k spread (1e29
    // for a day-long delay) left the companion matrix's roots meaningless.
    tau_s = l.delay_s;
    const double tau = tau_s;
    const auto in_x = [tau](const Poly& q) {  // q(x / tau)
      Poly r = q;
      double f = 1.0;
      for (std::size_t i = r.size(); i-- > 0; f /= tau) r[i] *= f;
      return r;
    };
    l.num = in_x(l.num);
    l.den = in_x(l.den);
    l.delay_s = 0.0;
    l = series(l, pade(1.0, 6));
    if (padded) *padded = true;
  }
  if (den_degree) *den_degree = degree(l.den);
  return add(l.den, l.num);
}

}  // namespace

std::vector<Complex> closed_loop_poles(const Tf& loop, bool* padded) {
  double tau_s = 1.0;
  std::vector<Complex> poles = roots(characteristic(loop, tau_s, padded));
  for (Complex& x : poles) x /= tau_s;
  return poles;
}

bool closed_loop_stable(const Tf& loop) {
  double tau_s = 1.0;
  int den_degree = 0;
  const Poly p = characteristic(loop, tau_s, nullptr, &den_degree);
  // 1 + L(∞) = 0 (L = −1 − 1/z): a closed-loop pole at infinity, the loop is not well posed.
  if (degree(p) < den_degree) return false;
  return roots_stable(p, loop.discrete());
}

bool is_stable(const std::vector<Complex>& poles, Domain domain) {
  for (const Complex& p : poles) {
    if (domain == Domain::s ? !(p.real() < 0.0) : !(std::abs(p) < 1.0)) return false;
  }
  return true;
}

std::vector<double> boundary_gains(const Tf& loop) {
  std::vector<double> k;
  if (is_zero(loop.num)) return k;
  const Margins m = margins(loop);
  for (double gm : m.gain_margins) {
    if (gm > 0.0 && std::isfinite(gm)) k.push_back(gm);
  }
  // A root through infinity: the leading coefficient of den + K·num vanishes.
  Tf l = loop.discrete() ? fold_delay(loop, "loop") : loop;
  const Poly num = trim(l.num);
  const Poly den = trim(l.den);
  if (num.size() == den.size()) {
    const double kinf = -den.front() / num.front();
    if (kinf > 0.0) k.push_back(kinf);
  }
  sort_unique(k);
  return k;
}

std::vector<GainRange> stable_gain_ranges(const Tf& loop) {
  const std::vector<double> k = boundary_gains(loop);
  std::vector<double> edges{0.0};
  edges.insert(edges.end(), k.begin(), k.end());
  edges.push_back(std::numeric_limits<double>::infinity());
  std::vector<GainRange> out;
  for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
    const double a = edges[i];
    const double b = edges[i + 1];
    double probe = 0.0;
    if (a == 0.0) {
      probe = std::isfinite(b) ? b / 2.0 : 1.0;
    } else if (!std::isfinite(b)) {
      probe = a * 2.0;
    } else {
      probe = std::sqrt(a * b);
    }
    // Many probes for a long delay in z (a crossover per 2π/τ): Schur–Cohn, not eigenvalues.
    const Tf probed = scaled(loop, probe);
    double tau_s = 1.0;
    // Never joined across a boundary gain: there a root lies on the boundary or at infinity (L = -1
    // is stable for every K but 1, where 1 + K·L vanishes identically).
    if (loop.discrete() ? schur_cohn_stable(characteristic(probed, tau_s, nullptr)) : closed_loop_stable(probed)) {
      out.push_back(GainRange{a, b});
    }
  }
  return out;
}

}  // namespace mcg::linsys
