// friction_load against its closed forms on the motor alone (steady speed, breakaway), and
// simulated with the effect, measured like the rig, its coefficient fitted back.
#include <gtest/gtest.h>

#include <cmath>

#include "fit/greybox.hpp"
#include "model/model.hpp"
#include "support/inputs.hpp"
#include "test_fit_support.hpp"

namespace mcg::model {
namespace {

constexpr double k_mu = 0.12;

Model loaded(double mu) {
  Model m;
  m.effects.push_back(parse_effect("friction_load:mu=" + std::to_string(mu)));
  return m;
}

/// Steady speed of the motor alone at v > 0: (1 - mu) Kt (v - Ke w) / R = F(w), by bisection.
double steady_speed(const Machine& m, double v, double mu) {
  double lo = 0.0, hi = v / m.Ke_V_s_rad;
  for (int it = 0; it < 200; ++it) {
    const double w = 0.5 * (lo + hi);
    const double net = (1.0 - mu) * m.Kt_Nm_A * (v - m.Ke_V_s_rad * w) / m.R_ohm - m.friction.kinetic_Nm(w);
    (net > 0.0 ? lo : hi) = w;
  }
  return 0.5 * (lo + hi);
}

TEST(ModelEffectFrictionLoad, SteadySpeedLosesMuOfTheMotorTorque) {
  const Machine& m = builtin_rig().motor;
  for (double v : {4.0, 10.0}) {
    const Outputs out = simulate(loaded(k_mu), test::constant_inputs(v, 1.5));
    EXPECT_NEAR(out.omega_rad_s.back(), steady_speed(m, v, k_mu), 1e-3) << v;
    EXPECT_LT(out.omega_rad_s.back(), steady_speed(m, v, 0.0) - 0.2) << v;
  }
}

TEST(ModelEffectFrictionLoad, BreakawayWhenTheTorqueLessMuLeavesTheStaticLevel) {
  const Machine& m = builtin_rig().motor;
  // At rest the current settles at v / R: the shaft moves when (1 - mu) Kt v / R > Ts.
  const double v_break = m.friction.Ts_Nm * m.R_ohm / (m.Kt_Nm_A * (1.0 - k_mu));
  auto moves = [&](double v) {
    const Outputs out = simulate(loaded(k_mu), test::constant_inputs(v, 0.3));
    return std::abs(out.omega_rad_s.back()) > 0.0;
  };
  EXPECT_FALSE(moves(0.98 * v_break));
  EXPECT_TRUE(moves(1.02 * v_break));
  EXPECT_FALSE(moves(-0.98 * v_break));
  EXPECT_TRUE(moves(-1.02 * v_break));
}

TEST(ModelEffectFrictionLoad, SimulatedThenFittedComesBack) {
  fit::testing::Program p;
  p.hold(0.0, 0.1, 0).hold(6.0, 0.4, 0).hold(11.0, 0.4, 0).hold(3.0, 0.4, 0);
  p.hold(8.0, 0.4, 2).hold(12.0, 0.4, 2, 5.6).hold(4.0, 0.4, 2, 5.6).hold(-7.0, 0.4, 2);
  const auto table = fit::testing::measure(loaded(k_mu), p.inputs, 5);
  fit::FitProblem problem;
  problem.model = loaded(0.02);
  problem.runs.push_back(fit::make_run(table, {}, problem.model.params));
  problem.free = {"friction_load.mu"};
  const fit::FitResult result = fit::fit_model(problem);
  ASSERT_TRUE(result.nls.converged) << result.nls.reason;
  EXPECT_NEAR(result.model.effect("friction_load")->get("mu"), k_mu, 0.05 * k_mu);
}

}  // namespace
}  // namespace mcg::model
