// Step responses and metrics against the closed form of a second-order system.
#include "linsys/parse.hpp"
#include "linsys/response.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace mcg::linsys {
namespace {

constexpr double k_pi = std::numbers::pi;

TEST(LinsysResponse, SecondOrderStepMetricsMatchTheClosedForm) {
  // L = ωn²/(s(s + 2ζωn)) closes to ωn²/(s² + 2ζωn s + ωn²); ζ = 0.5, ωn = 10.
  const double zeta = 0.5;
  const double wn = 10.0;
  const double wd = wn * std::sqrt(1.0 - zeta * zeta);
  auto y = [&](double t) {
    return 1.0 - std::exp(-zeta * wn * t) * (std::cos(wd * t) + zeta / std::sqrt(1.0 - zeta * zeta) * std::sin(wd * t));
  };
  const StepResponse s = step_response(parse_tf("100/(s*(s+10))", "t").tf, std::nullopt, 2.0, 20000);
  // 20000 samples of poles within 1e-3 of z = 1: the rounding of the sampled denominator alone
  // moves the response by about 1e-10.
  for (std::size_t k = 0; k < s.t_s.size(); k += 997) EXPECT_NEAR(s.y[k], y(s.t_s[k]), 3e-10) << s.t_s[k];
  const StepMetrics m = step_info(s, 1.0);
  EXPECT_DOUBLE_EQ(m.final_value, 1.0);
  // The peak is located exactly, at the root of y', not on the sample grid.
  EXPECT_NEAR(m.overshoot_pct, 100.0 * std::exp(-k_pi * zeta / std::sqrt(1.0 - zeta * zeta)), 1e-10);
  EXPECT_NEAR(m.peak_time_s, k_pi / wd, 1e-12);
  // On a grid of 100 samples the grid's peak is off; the exact one is not.
  const StepResponse coarse = step_response(parse_tf("100/(s*(s+10))", "t").tf, std::nullopt, 2.0, 100);
  EXPECT_GT(std::abs(step_metrics(coarse.t_s, coarse.y, 1.0, 1.0).peak_time_s - k_pi / wd), 1e-3);
  EXPECT_NEAR(step_info(coarse, 1.0).peak_time_s, k_pi / wd, 1e-12);
  // Rise 10-90 % and the 2 % settling time from the closed form by bisection.
  auto solve = [&](double level, double a, double b, bool rising) {
    for (int i = 0; i < 100; ++i) {
      const double c = 0.5 * (a + b);
      if ((y(c) < level) == rising) a = c; else b = c;
    }
    return a;
  };
  const double tp = k_pi / wd;
  EXPECT_NEAR(m.rise_time_s, solve(0.9, 0.0, tp, true) - solve(0.1, 0.0, tp, true), 1e-12);
  // The last exit from the 2 % band: a crossing of 1 ± 0.02 after the last extremum outside it.
  double last = 0.0;
  for (int k = 1; k < 10; ++k) {
    const double te = k * k_pi / wd;
    if (std::abs(y(te) - 1.0) > 0.02) last = te;
  }
  const int k_last = static_cast<int>(std::lround(last * wd / k_pi));
  const double level = k_last % 2 == 1 ? 1.02 : 0.98;
  const double settle = solve(level, last, last + k_pi / wd, k_last % 2 == 0);
  EXPECT_NEAR(m.settling_time_s, settle, 1e-12);
  EXPECT_DOUBLE_EQ(m.steady_state_error, 0.0);
}

TEST(LinsysResponse, TypeZeroLoopKeepsItsSteadyStateError) {
  // L = 4/(s+1): y_f = 4/5, error 0.2; the peak error max|y − y_f| is y_f itself (at t = 0).
  const StepResponse s = step_response(parse_tf("4/(s+1)", "t").tf, std::nullopt, 3.0, 30000);
  const StepMetrics m = step_metrics(s.t_s, s.y, s.final_value, 1.0);
  EXPECT_NEAR(m.final_value, 0.8, 1e-15);
  EXPECT_NEAR(m.steady_state_error, 0.2, 1e-15);
  // y = 0.8(1 − e^(−5t)): |y − y_f| = 0.8 e^(−5t) leaves 2 % of 0.8 at ln(50)/5, for both the
  // band on y_f and the band on the peak error.
  EXPECT_NEAR(m.settling_time_s, std::log(50.0) / 5.0, 1e-7);
  EXPECT_NEAR(m.transient_time_s, std::log(50.0) / 5.0, 1e-7);
  // Started below zero the two differ: |y − y_f| = e^(−5t) leaves 2 % of y_f (0.016) at ln(62.5)/5
  // and 2 % of its own peak (0.02) at ln(50)/5.
  std::vector<double> y2(s.y.size());
  for (std::size_t k = 0; k < y2.size(); ++k) y2[k] = 0.8 - (0.8 - s.y[k]) * 1.25;  // starts at −0.2
  const StepMetrics m2 = step_metrics(s.t_s, y2, 0.8, 1.0);
  EXPECT_NEAR(m2.settling_time_s, std::log(62.5) / 5.0, 1e-7);
  EXPECT_NEAR(m2.transient_time_s, std::log(50.0) / 5.0, 1e-7);
  EXPECT_NEAR(m2.undershoot_pct, 25.0, 1e-12);
  EXPECT_NEAR(m.rise_time_s, std::log(9.0) / 5.0, 1e-7);
  EXPECT_DOUBLE_EQ(m.overshoot_pct, 0.0);
}

TEST(LinsysResponse, OpenLoopStepOfTheDelayedPlant) {
  // 2 e^(−0.1 s)/(s + 5): y = 0.4 (1 − e^(−5(t − 0.1))) after the delay.
  const StepResponse s = step_response(parse_tf("2exp(-0.1s)/(s+5)", "t").tf, std::nullopt, 2.0, 2000, true);
  for (std::size_t k = 0; k < s.t_s.size(); k += 101) {
    const double t = s.t_s[k];
    EXPECT_NEAR(s.y[k], t < 0.1 ? 0.0 : 0.4 * (1.0 - std::exp(-5.0 * (t - 0.1))), 1e-12) << t;
  }
  const StepMetrics m = step_info(s, 1.0, StepLimits{0.05, 0.95, 0.05});
  EXPECT_DOUBLE_EQ(s.final_value, 0.4);
  EXPECT_NEAR(m.rise_time_s, std::log(0.95 / 0.05) / 5.0, 1e-12);
  EXPECT_NEAR(m.settling_time_s, 0.1 + std::log(20.0) / 5.0, 1e-12);
  // An integrator has no final value: the metrics say so.
  const StepResponse i = step_response(parse_tf("1/s", "t").tf, std::nullopt, 1.0, 100, true);
  EXPECT_TRUE(std::isnan(i.final_value));
  EXPECT_TRUE(std::isnan(step_info(i, 1.0).settling_time_s));
}

TEST(LinsysResponse, DiscreteLoopRunsAtItsSamplePeriod) {
  // L = 0.5/(z − 1): y[k] = 1 − 0.5^k exactly.
  Tf l = parse_tf("0.5/(z-1)", "t").tf;
  l.dt_s = 0.01;
  const StepResponse s = step_response(l, std::nullopt, 0.1, 0);
  ASSERT_EQ(s.t_s.size(), 11u);
  for (std::size_t k = 0; k < s.y.size(); ++k) EXPECT_NEAR(s.y[k], 1.0 - std::pow(0.5, static_cast<double>(k)), 1e-15);
}

}  // namespace
}  // namespace mcg::linsys
