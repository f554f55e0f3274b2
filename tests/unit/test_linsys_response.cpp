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
  for (std::size_t k = 0; k < s.t_s.size(); k += 997) EXPECT_NEAR(s.y[k], y(s.t_s[k]), 1e-10) << s.t_s[k];
  const StepMetrics m = step_metrics(s.t_s, s.y, s.final_value, 1.0);
  EXPECT_DOUBLE_EQ(m.final_value, 1.0);
  // The peak is taken from samples 1e-4 s apart: off by at most y''(t_p) h²/8.
  EXPECT_NEAR(m.overshoot_pct, 100.0 * std::exp(-k_pi * zeta / std::sqrt(1.0 - zeta * zeta)), 1e-4);
  EXPECT_NEAR(m.peak_time_s, k_pi / wd, 1e-4);
  // Rise 10-90 % and the 2 % settling time from the closed form by bisection.
  auto solve = [&](double level, double a, double b, bool rising) {
    for (int i = 0; i < 100; ++i) {
      const double c = 0.5 * (a + b);
      if ((y(c) < level) == rising) a = c; else b = c;
    }
    return a;
  };
  const double tp = k_pi / wd;
  EXPECT_NEAR(m.rise_time_s, solve(0.9, 0.0, tp, true) - solve(0.1, 0.0, tp, true), 1e-7);
  // The last exit from the 2 % band: a crossing of 1 ± 0.02 after the last extremum outside it.
  double last = 0.0;
  for (int k = 1; k < 10; ++k) {
    const double te = k * k_pi / wd;
    if (std::abs(y(te) - 1.0) > 0.02) last = te;
  }
  const int k_last = static_cast<int>(std::lround(last * wd / k_pi));
  const double level = k_last % 2 == 1 ? 1.02 : 0.98;
  const double settle = solve(level, last, last + k_pi / wd, k_last % 2 == 0);
  EXPECT_NEAR(m.settling_time_s, settle, 1e-7);
  EXPECT_DOUBLE_EQ(m.steady_state_error, 0.0);
}

TEST(LinsysResponse, TypeZeroLoopKeepsItsSteadyStateError) {
  // L = 4/(s+1): y_f = 4/5, error 0.2; the older 2 %-of-peak-error band is 0.02 of the step.
  const StepResponse s = step_response(parse_tf("4/(s+1)", "t").tf, std::nullopt, 3.0, 30000);
  const StepMetrics m = step_metrics(s.t_s, s.y, s.final_value, 1.0);
  EXPECT_NEAR(m.final_value, 0.8, 1e-15);
  EXPECT_NEAR(m.steady_state_error, 0.2, 1e-15);
  // y = 0.8(1 − e^(−5t)): |y − y_f| = 0.8 e^(−5t) leaves 0.016 at ln(50)/5 and 0.02 at ln(40)/5.
  EXPECT_NEAR(m.settling_time_s, std::log(50.0) / 5.0, 1e-7);
  EXPECT_NEAR(m.transient_time_s, std::log(40.0) / 5.0, 1e-7);
  EXPECT_NEAR(m.rise_time_s, std::log(9.0) / 5.0, 1e-7);
  EXPECT_DOUBLE_EQ(m.overshoot_pct, 0.0);
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
