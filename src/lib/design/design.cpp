// Exact controller design on the loop's frequency response.
#include "design/design.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "common/error.hpp"
#include "common/units.hpp"
#include "config/ini.hpp"

namespace mcg::design {

using linsys::FreqEval;
using linsys::LoopEval;
using linsys::Poly;

namespace {

double rad(double deg) { return deg * k_pi / 180.0; }
double deg(double r) { return r * 180.0 / k_pi; }
std::string num(double x) { return config::format_number(x); }

template <typename F>
double bisect(F f, double a, double b) {
  const double fa0 = f(a);
  bool neg_a = fa0 < 0.0;
  for (int i = 0; i < 200; ++i) {
    const double m = 0.5 * (a + b);
    if (m <= a || m >= b) break;
    const double fm = f(m);
    if (fm == 0.0) return m;
    if ((fm < 0.0) == neg_a) {
      a = m;
    } else {
      b = m;
    }
  }
  return 0.5 * (a + b);
}

Tf s_tf(Poly n, Poly d) {
  Tf g;
  g.num = std::move(n);
  g.den = std::move(d);
  return g;
}

/// Phase of the loop minus the target, wrapped to (−π, π].
double phase_error(const LoopEval& le, double w, double target) {
  return std::remainder(le.phase_rad(w) - target, 2.0 * k_pi);
}

/// Lowest ω where the unwrapped loop phase passes target (mod 2π); nan if it never does.
double first_phase_crossing(const LoopEval& le, double target) {
  const std::vector<double> w = linsys::scan_frequencies(le);
  double g0 = le.phase_rad(w.front()) - target;
  for (std::size_t i = 1; i < w.size(); ++i) {
    const double g1 = le.phase_rad(w[i]) - target;
    const double k0 = std::floor(g0 / (2.0 * k_pi));
    const double k1 = std::floor(g1 / (2.0 * k_pi));
    if (k0 != k1) {
      const double level = 2.0 * k_pi * std::max(k0, k1);
      const double x = bisect([&](double v) { return le.phase_rad(v) - target - level; }, w[i - 1], w[i]);
      if (std::abs(le.phase_rad(x) - target - level) < 1e-6) return x;
    }
    g0 = g1;
  }
  return std::nan("");
}

void check_pm(double pm_deg) {
  if (!(pm_deg > 0.0 && pm_deg < 180.0)) fail("phase margin must be in (0, 180) degrees, got {}", pm_deg);
}

void check_setup(const Setup& setup) {
  if (!setup.plant.proper()) fail("the plant must be proper, got {}", linsys::tf_text(setup.plant));
  if (setup.plant.discrete() && setup.dt_s > 0.0 && std::abs(setup.plant.dt_s - setup.dt_s) > 1e-12 * setup.dt_s) {
    fail("the plant is sampled at {} s but the controller at {} s", num(setup.plant.dt_s), num(setup.dt_s));
  }
  if (setup.plant.discrete() && !(setup.dt_s > 0.0)) fail("a discrete plant needs a discrete controller (--dt)");
}

Design finish(std::string kind, Tf cont, std::vector<std::pair<std::string, double>> params, double wc) {
  Design d;
  d.kind = std::move(kind);
  d.cont = std::move(cont);
  d.params = std::move(params);
  d.wc_rad_s = wc;
  return d;
}

}  // namespace

Tf running_form(const Setup& setup, const Tf& cont) {
  if (cont.discrete()) return cont;  // designed in z already (the board's PID)
  if (setup.dt_s > 0.0) return linsys::c2d(cont, setup.dt_s, setup.method, setup.prewarp_rad_s, "controller");
  return cont;
}

std::vector<Tf> loop_factors(const Setup& setup, const Tf& cont) { return {running_form(setup, cont), setup.plant}; }

Design design_p(const Setup& setup, double pm_deg) {
  check_setup(setup);
  check_pm(pm_deg);
  const LoopEval le(loop_factors(setup, s_tf({1.0}, {1.0})));
  const double wc = first_phase_crossing(le, rad(pm_deg - 180.0));
  if (!std::isfinite(wc)) {
    fail("the loop's phase never reaches {} degrees: any P gain gives a phase margin above {} degrees",
         num(pm_deg - 180.0), num(pm_deg));
  }
  const double kp = std::exp(-le.log_mag(wc));
  return finish("p", s_tf({kp}, {1.0}), {{"kp", kp}}, wc);
}

Design design_pi_zero(const Setup& setup, double pm_deg, double zero_rad_s) {
  check_setup(setup);
  check_pm(pm_deg);
  if (!(zero_rad_s > 0.0)) fail("the PI zero must be positive, got {}", zero_rad_s);
  const Tf shape = s_tf({1.0, zero_rad_s}, {1.0, 0.0});
  const LoopEval le(loop_factors(setup, shape));
  const double wc = first_phase_crossing(le, rad(pm_deg - 180.0));
  if (!std::isfinite(wc)) fail("no crossover gives {} degrees of phase margin with the PI zero at {} rad/s", num(pm_deg), num(zero_rad_s));
  const double kp = std::exp(-le.log_mag(wc));
  return finish("pi", linsys::scaled(shape, kp), {{"kp", kp}, {"ki", kp * zero_rad_s}, {"zero_rad_s", zero_rad_s}}, wc);
}

Design design_pi_crossover(const Setup& setup, double pm_deg, double wc) {
  check_setup(setup);
  check_pm(pm_deg);
  if (!(wc > 0.0)) fail("the crossover must be positive, got {}", wc);
  const double target = rad(pm_deg - 180.0);
  auto err = [&](double log_wz) {
    const LoopEval le(loop_factors(setup, s_tf({1.0, std::exp(log_wz)}, {1.0, 0.0})));
    return phase_error(le, wc, target);
  };
  const double lo = std::log(wc * 1e-6);
  const double hi = std::log(wc * 1e6);
  const double e_lo = err(lo);
  const double e_hi = err(hi);
  if (!(e_lo > 0.0 && e_hi < 0.0)) {
    const LoopEval plant({setup.plant});
    const double need = deg(std::remainder(target - plant.phase_rad(wc), 2.0 * k_pi));
    fail("a PI gives 0 to -90 degrees at {} rad/s, the phase margin needs {:.4g} degrees there", num(wc), need);
  }
  const double wz = std::exp(bisect(err, lo, hi));
  const Tf shape = s_tf({1.0, wz}, {1.0, 0.0});
  const double kp = std::exp(-LoopEval(loop_factors(setup, shape)).log_mag(wc));
  return finish("pi", linsys::scaled(shape, kp), {{"kp", kp}, {"ki", kp * wz}, {"zero_rad_s", wz}}, wc);
}

Design design_pid(const Setup& setup, double pm_deg, double wc, double ratio, double n) {
  check_setup(setup);
  check_pm(pm_deg);
  if (!(wc > 0.0)) fail("the crossover must be positive, got {}", wc);
  if (!(ratio > 0.0)) fail("Ti/Td must be positive, got {}", ratio);
  if (!(n > 0.0)) fail("the derivative filter N must be positive, got {}", n);
  const double target = rad(pm_deg - 180.0);
  auto shape = [&](double td) {
    const double ti = ratio * td;
    return s_tf({td / n + td, 1.0 + td / (n * ti), 1.0 / ti}, {td / n, 1.0, 0.0});
  };
  auto err = [&](double log_td) {
    return phase_error(LoopEval(loop_factors(setup, shape(std::exp(log_td)))), wc, target);
  };
  const double a = std::log(1e-4 / wc);
  const double b = std::log(1e4 / wc);
  const int steps = 400;
  double prev = err(a);
  double prev_x = a;
  std::optional<double> td;
  for (int i = 1; i <= steps && !td; ++i) {
    const double x = a + (b - a) * i / steps;
    const double e = err(x);
    if ((prev < 0.0) != (e < 0.0) && std::abs(prev) < k_pi / 2.0 && std::abs(e) < k_pi / 2.0) {
      td = std::exp(bisect(err, prev_x, x));
    }
    prev = e;
    prev_x = x;
  }
  if (!td) {
    fail("no PID with Ti = {}*Td and N = {} gives {} degrees of phase margin at {} rad/s", num(ratio), num(n),
         num(pm_deg), num(wc));
  }
  const Tf c = shape(*td);
  const double kp = std::exp(-LoopEval(loop_factors(setup, c)).log_mag(wc));
  const double ti = ratio * *td;
  return finish("pid", linsys::scaled(c, kp),
                {{"kp", kp}, {"ti_s", ti}, {"td_s", *td}, {"n", n}, {"ki", kp / ti}, {"kd", kp * *td}}, wc);
}

Design design_pid_board(const Setup& setup, double pm_deg, double wc, double ratio) {
  check_setup(setup);
  check_pm(pm_deg);
  if (!(setup.dt_s > 0.0)) fail("--form board: the board's PID runs every sample: --dt is required");
  if (!(wc > 0.0)) fail("the crossover must be positive, got {}", wc);
  if (!(ratio > 0.0)) fail("Ti/Td must be positive, got {}", ratio);
  const double t = setup.dt_s;
  const double target = rad(pm_deg - 180.0);
  // C(z)/Kp = 1 + (T/Ti) z/(z - 1) + (Td/T) (z - 1)/z = (b0 z^2 + b1 z + b2)/(z^2 - z).
  auto shape = [&](double td) {
    const double ti = ratio * td;
    Tf c;
    c.domain = linsys::Domain::z;
    c.dt_s = t;
    c.num = {1.0 + t / ti + td / t, -(1.0 + 2.0 * td / t), td / t};
    c.den = {1.0, -1.0, 0.0};
    return c;
  };
  auto err = [&](double log_td) {
    return phase_error(LoopEval(loop_factors(setup, shape(std::exp(log_td)))), wc, target);
  };
  const double a = std::log(1e-4 / wc);
  const double b = std::log(1e4 / wc);
  const int steps = 400;
  double prev = err(a);
  double prev_x = a;
  std::optional<double> td;
  for (int i = 1; i <= steps && !td; ++i) {
    const double x = a + (b - a) * i / steps;
    const double e = err(x);
    if ((prev < 0.0) != (e < 0.0) && std::abs(prev) < k_pi / 2.0 && std::abs(e) < k_pi / 2.0) {
      td = std::exp(bisect(err, prev_x, x));
    }
    prev = e;
    prev_x = x;
  }
  if (!td) {
    fail("no PID in the board's form with Ti = {}*Td gives {} degrees of phase margin at {} rad/s", num(ratio),
         num(pm_deg), num(wc));
  }
  const Tf c = shape(*td);
  const double kp = std::exp(-LoopEval(loop_factors(setup, c)).log_mag(wc));
  const double ti = ratio * *td;
  return finish("pid", linsys::scaled(c, kp), {{"kp", kp}, {"ti_s", ti}, {"td_s", *td}, {"ki", kp / ti}, {"kd", kp * *td}},
                wc);
}

Design design_lead(const Setup& setup, double pm_deg, double wc) {
  check_setup(setup);
  check_pm(pm_deg);
  if (!(wc > 0.0)) fail("the crossover must be positive, got {}", wc);
  const double target = rad(pm_deg - 180.0);
  auto shape = [&](double phi) {
    const double alpha = (1.0 - std::sin(phi)) / (1.0 + std::sin(phi));
    const double wz = wc * std::sqrt(alpha);
    const double wp = wc / std::sqrt(alpha);
    return s_tf({1.0 / wz, 1.0}, {1.0 / wp, 1.0});
  };
  auto err = [&](double phi) { return phase_error(LoopEval(loop_factors(setup, shape(phi))), wc, target); };
  const double lo = 1e-9;
  const double hi = k_pi / 2.0 - 1e-6;
  if (!(err(lo) < 0.0 && err(hi) > 0.0)) {
    const LoopEval plant({setup.plant});
    const double need = deg(std::remainder(target - plant.phase_rad(wc), 2.0 * k_pi));
    fail("a lead gives 0 to 90 degrees at {} rad/s, the phase margin needs {:.4g} degrees there", num(wc), need);
  }
  const double phi = bisect(err, lo, hi);
  const Tf c = shape(phi);
  const double k = std::exp(-LoopEval(loop_factors(setup, c)).log_mag(wc));
  const double alpha = (1.0 - std::sin(phi)) / (1.0 + std::sin(phi));
  return finish("lead", linsys::scaled(c, k),
                {{"k", k}, {"zero_rad_s", wc * std::sqrt(alpha)}, {"pole_rad_s", wc / std::sqrt(alpha)}, {"alpha", alpha},
                 {"phi_deg", deg(phi)}},
                wc);
}

Design design_lag(const Setup& setup, double pm_deg, double k_dc, double ratio) {
  check_setup(setup);
  check_pm(pm_deg);
  if (!(k_dc > 0.0)) fail("the lag's DC gain must be positive, got {}", k_dc);
  if (!(ratio > 1.0)) fail("the lag's zero ratio must be above 1, got {}", ratio);
  const double target = rad(pm_deg - 180.0);
  auto shape = [&](double wc, double beta) {
    const double wz = wc / ratio;
    const double wp = wz / beta;
    return s_tf({k_dc / wz, k_dc}, {1.0 / wp, 1.0});
  };
  // A continuous lag C = k_dc (1 + s/ω_z)/(1 + s/ω_p), ω_z = ω_c/ratio, ω_p = ω_z/β, has at ω_c
  // |C| = k_dc·|1 + j·ratio|/|1 + j·ratio·β| and ∠C = atan(ratio) − atan(ratio·β): β and the
  // phase follow from the plant's response alone, without building the loop for every trial.
  const bool continuous = !(setup.dt_s > 0.0);
  const LoopEval plant({setup.plant});
  // β >= 1 with |L(jω_c)| = 1, or nan when K0·|P| < 1 there (no lag needed to cross).
  auto beta_at = [&](double wc) {
    if (continuous) {
      const double m = k_dc * std::exp(plant.log_mag(wc)) * std::hypot(1.0, ratio);
      const double beta = std::sqrt(std::max(0.0, m * m - 1.0)) / ratio;
      return beta > 1.0 && beta <= 1e12 ? beta : std::nan("");
    }
    auto lm = [&](double log_beta) { return LoopEval(loop_factors(setup, shape(wc, std::exp(log_beta)))).log_mag(wc); };
    if (lm(0.0) <= 0.0) return std::nan("");
    const double top = std::log(1e12);
    if (lm(top) > 0.0) return std::nan("");
    return std::exp(bisect(lm, 0.0, top));
  };
  auto err = [&](double wc) {
    const double beta = beta_at(wc);
    if (!std::isfinite(beta)) return std::nan("");
    if (continuous) {
      return std::remainder(plant.phase_rad(wc) + std::atan(ratio) - std::atan(ratio * beta) - target, 2.0 * k_pi);
    }
    return phase_error(LoopEval(loop_factors(setup, shape(wc, beta))), wc, target);
  };
  double lo = 0.0;
  double hi = 0.0;
  plant.range(lo, hi);
  const int steps = 300;
  double prev_w = lo;
  double prev = err(lo);
  for (int i = 1; i <= steps; ++i) {
    const double w = lo * std::pow(hi / lo, static_cast<double>(i) / steps);
    const double e = err(w);
    if (std::isfinite(prev) && std::isfinite(e) && prev > 0.0 && e <= 0.0 && prev < k_pi / 2.0 && e > -k_pi / 2.0) {
      const double wc = bisect(err, prev_w, w);
      const double beta = beta_at(wc);
      const Tf c = shape(wc, beta);
      const double wz = wc / ratio;
      return finish("lag", c, {{"k_dc", k_dc}, {"zero_rad_s", wz}, {"pole_rad_s", wz / beta}, {"beta", beta}}, wc);
    }
    prev = e;
    prev_w = w;
  }
  fail("no lag with DC gain {} and zero at wc/{} gives {} degrees of phase margin", num(k_dc), num(ratio), num(pm_deg));
}

RlocusResult design_rlocus(const Setup& setup, double zeta) {
  check_setup(setup);
  if (!(zeta > 0.0 && zeta < 1.0)) fail("the damping ratio must be in (0, 1), got {}", zeta);
  if (setup.dt_s > 0.0 && !setup.plant.discrete()) {
    fail("a root-locus design needs the loop in one domain: discretise the plant (--zoh) or drop --dt");
  }
  const Tf p = setup.plant.discrete() ? linsys::fold_delay(setup.plant, "plant") : setup.plant;
  const double wd_per_wn = std::sqrt(1.0 - zeta * zeta);
  auto point = [&](double wn) {
    const Complex s(-zeta * wn, wd_per_wn * wn);
    return p.discrete() ? std::exp(s * p.dt_s) : s;
  };
  auto value = [&](double wn) {
    const Complex x = point(wn);
    Complex l = p.eval(x);
    if (!p.discrete() && p.delay_s > 0.0) l *= std::exp(-(-zeta * wn + Complex(0.0, wd_per_wn * wn)) * p.delay_s);
    return l;
  };
  double lo = 0.0;
  double hi = 0.0;
  linsys::default_range(p, lo, hi);
  if (p.discrete()) hi = k_pi / (p.dt_s * wd_per_wn);
  const std::vector<double> w = linsys::log_grid(lo, hi, 6000);
  std::optional<double> best_k;
  double best_wn = 0.0;
  for (std::size_t i = 1; i < w.size(); ++i) {
    const Complex a = value(w[i - 1]);
    const Complex b = value(w[i]);
    if ((a.imag() < 0.0) == (b.imag() < 0.0)) continue;
    const double x = bisect([&](double v) { return value(v).imag(); }, w[i - 1], w[i]);
    const Complex l = value(x);
    if (!(l.real() < 0.0) || std::abs(l.imag()) > 1e-6 * std::abs(l)) continue;
    const double k = -1.0 / l.real();
    if (!best_k || k < *best_k) {
      best_k = k;
      best_wn = x;
    }
  }
  if (!best_k) fail("the root locus never meets the damping line zeta = {}", num(zeta));
  RlocusResult r;
  r.design = finish("p", s_tf({*best_k}, {1.0}), {{"kp", *best_k}, {"zeta", zeta}}, 0.0);
  r.omega_n_rad_s = best_wn;
  r.poles = linsys::closed_loop_poles(linsys::scaled(p, *best_k));
  return r;
}

double peak_sensitivity(const std::vector<Tf>& factors, double* omega) {
  const LoopEval le(factors);
  const std::vector<double> w = linsys::scan_frequencies(le);
  auto s_mag = [&](double x) { return 1.0 / std::abs(1.0 + le.value(x)); };
  std::size_t best = 0;
  double best_v = -1.0;
  for (std::size_t i = 0; i < w.size(); ++i) {
    const double v = s_mag(w[i]);
    if (v > best_v) {
      best_v = v;
      best = i;
    }
  }
  // Golden-section refinement between the neighbours of the best grid point.
  double a = w[best > 0 ? best - 1 : 0];
  double b = w[std::min(best + 1, w.size() - 1)];
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  for (int i = 0; i < 80 && b - a > 1e-14 * b; ++i) {
    const double c = b - g * (b - a);
    const double d = a + g * (b - a);
    if (s_mag(c) > s_mag(d)) {
      b = d;
    } else {
      a = c;
    }
  }
  const double peak = std::max(best_v, s_mag(0.5 * (a + b)));
  if (omega) *omega = best_v >= s_mag(0.5 * (a + b)) ? w[best] : 0.5 * (a + b);
  return peak;
}

bool meets(const Setup& setup, const Tf& cont, const TuneLimits& limits) {
  const std::vector<Tf> f = loop_factors(setup, cont);
  {
    // A coarse look at |S| first: any sample above the limit already rules the loop out.
    const LoopEval le(f);
    double lo = 0.0;
    double hi = 0.0;
    le.range(lo, hi);
    for (double w : linsys::log_grid(lo, hi, 300)) {
      if (1.0 / std::abs(1.0 + le.value(w)) > limits.ms_max) return false;
    }
  }
  if (f[0].domain == f[1].domain) {
    if (!linsys::closed_loop_stable(linsys::series(f[0], f[1]))) return false;
  }
  const linsys::Margins m = linsys::margins(f);
  if (m.phase_margins_deg.empty()) return false;
  for (double pm : m.phase_margins_deg) {
    if (pm < limits.pm_min_deg) return false;
  }
  for (double gm : m.gain_margins) {
    if (std::abs(20.0 * std::log10(gm)) < limits.gm_min_db) return false;
  }
  return peak_sensitivity(f) <= limits.ms_max;
}

Design tune(const Setup& setup, const std::string& structure, const TuneLimits& limits) {
  check_setup(setup);
  if (structure != "p" && structure != "pi") fail("tuning structure must be p or pi, got {}", quote(structure));
  const bool pi = structure == "pi";
  std::vector<double> rhos{0.0};
  if (pi) rhos = linsys::log_grid(1.0, 0.01, 13);
  const LoopEval plant({setup.plant});
  double lo = 0.0;
  double hi = 0.0;
  plant.range(lo, hi);
  // A continuous shape (s + ρω_c)/s has at ω_c the magnitude √(1 + ρ²) and the phase
  // atan2(1, ρ) − π/2 (1 and 0 for P): no loop needs building to know them.
  const bool continuous = !(setup.dt_s > 0.0);
  auto candidate = [&](double wc, double rho) {
    const Tf shape = rho > 0.0 ? s_tf({1.0, rho * wc}, {1.0, 0.0}) : s_tf({1.0}, {1.0});
    const double log_mag = continuous ? plant.log_mag(wc) + (rho > 0.0 ? 0.5 * std::log1p(rho * rho) : 0.0)
                                      : LoopEval(loop_factors(setup, shape)).log_mag(wc);
    return linsys::scaled(shape, std::exp(-log_mag));
  };
  // The cheap test first: the phase margin at the designed crossover itself.
  auto feasible = [&](double wc, double& rho_out) {
    for (double rho : rhos) {
      const Tf c = candidate(wc, rho);
      const double phase = continuous ? plant.phase_rad(wc) + (rho > 0.0 ? std::atan2(1.0, rho) - k_pi / 2.0 : 0.0)
                                      : LoopEval(loop_factors(setup, c)).phase_rad(wc);
      const double pm = deg(std::remainder(phase + k_pi, 2.0 * k_pi));
      if (pm < limits.pm_min_deg) continue;
      if (meets(setup, c, limits)) {
        rho_out = rho;
        return true;
      }
    }
    return false;
  };
  const std::vector<double> grid = linsys::log_grid(lo, hi, 80);
  for (std::size_t i = grid.size(); i-- > 0;) {
    double rho = 0.0;
    if (!feasible(grid[i], rho)) continue;
    double good = grid[i];
    double good_rho = rho;
    if (i + 1 < grid.size()) {
      double bad = grid[i + 1];
      for (int it = 0; it < 12 && bad / good > 1.0 + 1e-5; ++it) {
        const double mid = std::sqrt(good * bad);
        double r = 0.0;
        if (feasible(mid, r)) {
          good = mid;
          good_rho = r;
        } else {
          bad = mid;
        }
      }
    }
    const Tf c = candidate(good, good_rho);
    const double kp = linsys::trim(c.num).front();
    if (pi) {
      return finish("pi", c, {{"kp", kp}, {"ki", kp * good_rho * good}, {"zero_rad_s", good_rho * good}}, good);
    }
    return finish("p", c, {{"kp", kp}}, good);
  }
  fail("no {} controller meets PM >= {} deg, GM >= {} dB, Ms <= {}", structure, num(limits.pm_min_deg),
       num(limits.gm_min_db), num(limits.ms_max));
}

}  // namespace mcg::design
