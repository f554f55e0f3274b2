// Grey-box fit: parameters changed in a simulation, measured like the rig, fitted back.
#include "fit/greybox.hpp"

#include "common/error.hpp"
#include "test_fit_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

namespace mcg::fit {
namespace {

using testing::measure;
using testing::Program;

/// Voltage steps in the three clutch states with a generator load switched in: excites the
/// electrical (R, L, Kt, Ke) and the mechanical (J, friction) parameters.
model::Inputs identification_run() {
  Program p;
  p.hold(0.0, 0.1, 0).hold(6.0, 0.4, 0).hold(11.0, 0.4, 0).hold(3.0, 0.4, 0);
  p.hold(8.0, 0.4, 2).hold(12.0, 0.4, 2, 5.6).hold(4.0, 0.4, 2, 5.6).hold(9.0, 0.4, 2);
  p.hold(-7.0, 0.5, 2);  // -3.7 A at the reversal: the ADC saturates
  return p.inputs;
}

TEST(FitGreybox, WindowAverageRpmIsTheExactMeanSpeed) {
  const std::vector<double> t{0.0, 0.001, 0.002, 0.003, 0.004, 0.005, 0.006, 0.007};
  std::vector<double> theta;
  for (double x : t) theta.push_back(30.0 * x * x);  // w = 60 t rad/s
  const double to_rpm = 60.0 / (2.0 * M_PI);
  const auto rpm = window_average_rpm(t, theta, RpmEstimator{0.003, 2048.0});
  // Mean speed over [t - W, t] = 60 (t - W/2) rad/s; before the start the shaft is at rest.
  EXPECT_NEAR(rpm[5], 60.0 * (0.005 - 0.0015) * to_rpm, 1e-9);
  EXPECT_NEAR(rpm[1], 30.0 * 1e-6 / 0.003 * to_rpm, 1e-9);
  EXPECT_EQ(rpm[0], 0.0);
  // Off the sample grid the angle at t - W is interpolated linearly between samples.
  const auto half = window_average_rpm(t, theta, RpmEstimator{0.0025, 2048.0});
  EXPECT_NEAR(half[5], (theta[5] - 0.5 * (theta[2] + theta[3])) / 0.0025 * to_rpm, 1e-9);
}

TEST(FitGreybox, FitPercentIsMatlabNrmse) {
  const std::vector<double> y{1.0, 2.0, 3.0, 4.0};
  EXPECT_DOUBLE_EQ(fit_percent(y, y), 100.0);
  // |e| = 1, |y - mean| = sqrt(5): 100 (1 - 1/sqrt(5)).
  EXPECT_NEAR(fit_percent(y, {1.0, 2.0, 3.0, 5.0}), 100.0 * (1.0 - 1.0 / std::sqrt(5.0)), 1e-12);
  EXPECT_DOUBLE_EQ(fit_percent(y, {2.5, 2.5, 2.5, 2.5}), 0.0);
}

// The truth differs from the built-in rig by +12 % inertia, -6 % Kt and Ke, +8 % R and +20 %
// Coulomb friction of the motor (the param_mismatch kind of error); rpm from encoder counts,
// current with ADC noise and saturation (declared in # i_measurement, so the clipped samples
// are left out). Stated tolerances: J, Kt, Ke, R within 1 %, Tc within 5 %.
TEST(FitGreybox, ChangedParametersComeBack) {
  model::Model truth;
  truth.params.motor.J_kg_m2 *= 1.12;
  truth.params.generator.J_kg_m2 *= 1.12;
  truth.params.motor.Kt_Nm_A *= 0.94;
  truth.params.motor.Ke_V_s_rad *= 0.94;
  truth.params.motor.R_ohm *= 1.08;
  truth.params.motor.friction.Tc_Nm *= 1.2;
  const auto table = measure(truth, identification_run(), 21);

  FitProblem problem;
  problem.runs.push_back(make_run(table, {}, problem.model.params));
  EXPECT_EQ(problem.runs[0].outputs, (std::vector<std::string>{"rpm", "i"}));
  problem.free = {"motor.J_kg_m2", "motor.Kt_Nm_A", "motor.Ke_V_s_rad", "motor.R_ohm", "motor.Tc_Nm"};
  problem.model.params.generator.J_kg_m2 *= 1.12;
  problem.sim.max_step_s = 2.5e-4;
  const FitResult result = fit_model(problem);
  ASSERT_TRUE(result.nls.converged) << result.nls.reason;
  const auto& p = result.model.params.motor;
  const auto& want = truth.params.motor;
  EXPECT_NEAR(p.J_kg_m2, want.J_kg_m2, 0.01 * want.J_kg_m2);
  EXPECT_NEAR(p.Kt_Nm_A, want.Kt_Nm_A, 0.01 * want.Kt_Nm_A);
  EXPECT_NEAR(p.Ke_V_s_rad, want.Ke_V_s_rad, 0.01 * want.Ke_V_s_rad);
  EXPECT_NEAR(p.R_ohm, want.R_ohm, 0.01 * want.R_ohm);
  EXPECT_NEAR(p.friction.Tc_Nm, want.friction.Tc_Nm, 0.05 * want.friction.Tc_Nm);
  for (Eigen::Index i = 0; i < result.nls.values.size(); ++i) {
    EXPECT_GT(result.nls.std_errors[i], 0.0);
    EXPECT_LT(result.nls.std_errors[i], 0.01 * std::abs(result.nls.values[i]));
    EXPECT_EQ(result.nls.correlation(i, i), 1.0);
    for (Eigen::Index j = 0; j < i; ++j) EXPECT_EQ(result.nls.correlation(i, j), result.nls.correlation(j, i));
  }
  EXPECT_GT(result.nls.iterations, 0);
  ASSERT_EQ(result.runs.size(), 1U);
  EXPECT_GT(result.runs[0].fit_percent[0], 97.0);
  EXPECT_GT(result.runs[0].fit_percent[1], 90.0);
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(FitGreybox, BudgetSpentSaysNotConverged) {
  FitProblem problem;
  problem.runs.push_back(make_run(measure(model::Model{}, identification_run(), 22), {"rpm"}, problem.model.params));
  problem.free = {"motor.J_kg_m2"};
  problem.model.params.motor.J_kg_m2 *= 2.0;
  problem.nls.max_evaluations = 2;
  const FitResult result = fit_model(problem);
  EXPECT_FALSE(result.nls.converged);
  EXPECT_EQ(result.nls.reason, "evaluation budget spent before convergence");
}

TEST(FitGreybox, BadProblemsAreNamed) {
  const model::Model rig;
  const auto table = measure(rig, identification_run(), 23);
  FitProblem problem;
  problem.runs.push_back(make_run(table, {"rpm"}, rig.params));
  problem.free = {"motor.J_kg_m2", "motor.Q"};
  EXPECT_EQ(error_of([&] { fit_model(problem); }), "unknown parameter 'motor.Q' (see mcg-fit model --list)");
  problem.free = {"motor.R_ohm", "motor.R_ohm"};
  EXPECT_EQ(error_of([&] { fit_model(problem); }), "parameter 'motor.R_ohm' is listed twice");

  const auto at_rest = measure(rig, Program{}.hold(0.2, 1.0, 0).inputs, 24);
  problem.runs = {make_run(at_rest, {"rpm"}, rig.params)};
  problem.free = {"motor.R_ohm"};
  EXPECT_EQ(error_of([&] { fit_model(problem); }), "sim.csv: column 'rpm' is constant: no excitation to fit");

  EXPECT_EQ(error_of([&] { make_run(measure(rig, Program{}.hold(1.0, 0.03, 0).inputs, 25), {}, rig.params); }),
            "sim.csv: too short: 30 rows (at least 50 needed)");
  EXPECT_EQ(error_of([&] { make_run(table, {"torque"}, rig.params); }),
            "unknown output 'torque' (one of rpm, i, i_gen, v_gen, omega)");
  auto no_v = table;
  no_v.names[1] = "u";
  EXPECT_EQ(error_of([&] { make_run(no_v, {}, rig.params); }), "sim.csv: missing column 'v' (has: t,u,clutch,r_load,rpm,i)");
}

}  // namespace
}  // namespace mcg::fit
