// Grey-box fit: parameters changed in a simulation, measured like the rig, fitted back.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include "common/error.hpp"
#include "config/ini.hpp"
#include "fit/greybox.hpp"
#include "test_fit_support.hpp"
#include "test_support_error.hpp"

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

// A caller that needs only the model and its statistics (each fit of the gap search) skips
// the simulation of the runs at the optimum: the fit itself is the same to the last bit.
TEST(FitGreybox, SkippingTheRunsAtTheOptimumChangesNothingElse) {
  FitProblem problem;
  const auto table = measure(model::Model{}, identification_run(), 23);
  problem.runs.push_back(make_run(table, {}, problem.model.params));
  problem.free = {"motor.J_kg_m2", "motor.R_ohm", "motor.Tc_Nm"};
  problem.model.params.motor.J_kg_m2 *= 1.3;
  problem.model.params.motor.R_ohm *= 0.9;
  const FitResult with_runs = fit_model(problem);
  problem.evaluate_runs = false;
  const FitResult without = fit_model(problem);
  ASSERT_EQ(with_runs.runs.size(), 1U);
  EXPECT_TRUE(without.runs.empty());
  ASSERT_TRUE(with_runs.nls.converged) << with_runs.nls.reason;
  EXPECT_EQ(without.nls.simulations, with_runs.nls.simulations);
  EXPECT_EQ(without.nls.cost, with_runs.nls.cost);
  for (Eigen::Index i = 0; i < with_runs.nls.values.size(); ++i) {
    EXPECT_EQ(without.nls.values[i], with_runs.nls.values[i]);
    EXPECT_EQ(without.nls.std_errors[i], with_runs.nls.std_errors[i]);
  }
  EXPECT_EQ(without.se_widening, with_runs.se_widening);
  EXPECT_EQ(without.warnings, with_runs.warnings);
}

using test::error_of;

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

/// Speed-only runs of a motor alone: steps up and down, a reversal, rests in between.
model::Inputs speed_only_run() {
  Program p;
  p.hold(0.0, 0.1, 0).hold(5.0, 0.4, 0).hold(12.0, 0.4, 0).hold(2.0, 0.4, 0).hold(0.0, 0.3, 0);
  p.hold(-8.0, 0.4, 0).hold(-3.0, 0.4, 0).hold(9.0, 0.5, 0);
  return p.inputs;
}

model::Model speed_only_truth() {
  model::Model truth;
  truth.params.motor.J_kg_m2 *= 1.3;
  truth.params.motor.Kt_Nm_A *= 0.9;
  truth.params.motor.Ke_V_s_rad *= 0.9;
  truth.params.motor.friction.Tc_Nm *= 1.4;
  return truth;
}

// Speed alone fixes R/Kt, Tc R/Kt and J R/(Kt Ke): the default frees J, Kt (Ke tied) and Tc,
// leaves the measured R alone, and recovers the truth within 2 % with no warning.
TEST(FitGreybox, SpeedOnlyDefaultTiesKeToKtAndLeavesRAlone) {
  const model::Model truth = speed_only_truth();
  FitProblem problem;
  problem.runs.push_back(make_run(measure(truth, speed_only_run(), 31, false), {}, problem.model.params));
  problem.free = default_free(problem.runs, {}, problem.ties);
  EXPECT_EQ(problem.free, (std::vector<std::string>{"motor.J_kg_m2", "motor.Kt_Nm_A", "motor.Tc_Nm"}));
  ASSERT_EQ(problem.ties.size(), 1U);
  EXPECT_EQ(problem.ties[0], (std::pair<std::string, std::string>{"motor.Ke_V_s_rad", "motor.Kt_Nm_A"}));
  problem.sim.max_step_s = 2.5e-4;
  const FitResult r = fit_model(problem);
  EXPECT_TRUE(r.trustworthy()) << r.nls.reason << (r.warnings.empty() ? "" : ": " + r.warnings[0]);
  const auto& m = r.model.params.motor;
  EXPECT_NEAR(m.J_kg_m2, truth.params.motor.J_kg_m2, 0.02 * truth.params.motor.J_kg_m2);
  EXPECT_NEAR(m.Kt_Nm_A, truth.params.motor.Kt_Nm_A, 0.02 * truth.params.motor.Kt_Nm_A);
  EXPECT_EQ(m.Ke_V_s_rad, m.Kt_Nm_A);
  EXPECT_NEAR(m.friction.Tc_Nm, truth.params.motor.friction.Tc_Nm, 0.05 * truth.params.motor.friction.Tc_Nm);
  EXPECT_EQ(m.R_ohm, model::Model{}.params.motor.R_ohm);
  // With a current the default frees R and Ke as well.
  FitProblem with_i;
  with_i.runs.push_back(make_run(measure(truth, speed_only_run(), 31), {}, with_i.model.params));
  EXPECT_EQ(default_free(with_i.runs, {"motor.R_ohm"}, with_i.ties),
            (std::vector<std::string>{"motor.J_kg_m2", "motor.Kt_Nm_A", "motor.Ke_V_s_rad", "motor.Tc_Nm"}));
  EXPECT_TRUE(with_i.ties.empty());
}

// The degenerate set on speed-only data (R and Kt free together) is not reported as converged.
TEST(FitGreybox, DegenerateFreeSetIsFlagged) {
  FitProblem problem;
  problem.runs.push_back(make_run(measure(speed_only_truth(), speed_only_run(), 32, false), {}, problem.model.params));
  problem.free = {"motor.J_kg_m2", "motor.R_ohm", "motor.Kt_Nm_A", "motor.Ke_V_s_rad", "motor.Tc_Nm"};
  problem.sim.max_step_s = 2.5e-4;
  const FitResult r = fit_model(problem);
  EXPECT_FALSE(r.trustworthy());
  ASSERT_FALSE(r.warnings.empty());
  const bool correlated = std::any_of(r.warnings.begin(), r.warnings.end(), [](const std::string& w) {
    return w.find("correlated") != std::string::npos || w.find("not determined") != std::string::npos;
  });
  EXPECT_TRUE(correlated) << r.warnings[0];
  ASSERT_EQ(r.flags.size(), r.warnings.size());
  EXPECT_TRUE(std::any_of(r.flags.begin(), r.flags.end(), [](const FitFlag& f) { return f.undetermined(); }));
}

// A viscous coefficient the fit drives below zero (a friction that would push the shaft) is
// physically impossible: flagged whatever its bounds allow, and the fit is not trustworthy.
TEST(FitGreybox, ANegativeViscousCoefficientIsFlagged) {
  model::Model truth;
  truth.params.motor.friction.viscous[0] = -4e-6;
  FitProblem problem;
  problem.runs.push_back(make_run(measure(truth, speed_only_run(), 35, false), {}, problem.model.params));
  problem.free = {"motor.visc1_Nm_s_rad"};
  const FitResult r = fit_model(problem);
  EXPECT_NEAR(r.model.params.motor.friction.viscous[0], -4e-6, 1e-6);
  EXPECT_FALSE(r.trustworthy());
  ASSERT_EQ(r.flags.size(), 1U) << r.warnings[0];
  EXPECT_EQ(r.flags[0].kind, FitFlag::Kind::impossible);
  EXPECT_EQ(r.flags[0].names, (std::vector<std::string>{"motor.visc1_Nm_s_rad"}));
  EXPECT_TRUE(r.flags[0].undetermined());
  EXPECT_NE(r.warnings[0].find("is a negative viscous friction (it would drive the shaft): physically impossible"),
            std::string::npos)
      << r.warnings[0];
}

// A ripple of 5 uN m on the rig's motor moves its speed by far less than the noise: its phase,
// fitted, has a finite standard error wider than its whole range -pi..pi, which says nothing
// about it. It is flagged as not determined, as an infinite error would be.
/// The rig's motor with the ripple `cogging` (an effect's text), its speed measured with noise
/// seed `seed`, and the ripple's phase fitted alone from `start_rad`.
FitResult fit_ripple_phase(const std::string& cogging, double start_rad, unsigned seed) {
  model::Model truth;
  truth.effects.push_back(model::parse_effect(cogging));
  FitProblem problem;
  problem.model = truth;
  problem.model.effects.back().set("phase_rad", start_rad);
  problem.runs.push_back(make_run(measure(truth, speed_only_run(), seed, false), {}, problem.model.params));
  problem.free = {"cogging.phase_rad"};
  return fit_model(problem);
}

TEST(FitGreybox, AnErrorBeyondHalfTheRangeIsNotDetermined) {
  const FitResult r = fit_ripple_phase("cogging:T_c_Nm=5e-6,N_per_rev=14,phase_rad=0.7", -0.5, 37);
  ASSERT_EQ(r.nls.std_errors.size(), 1);
  EXPECT_TRUE(std::isfinite(r.reported_se(0)));
  EXPECT_GT(r.reported_se(0), std::numbers::pi);
  ASSERT_EQ(r.flags.size(), 1U);
  EXPECT_EQ(r.flags[0].kind, FitFlag::Kind::undetermined);
  EXPECT_NE(r.warnings[0].find("cogging.phase_rad: not determined by the data (standard error "),
            std::string::npos)
      << r.warnings[0];
  EXPECT_NE(r.warnings[0].find(" rad beyond half its range -3.14159 to 3.14159)"), std::string::npos)
      << r.warnings[0];
}

// A phase is periodic: a fit starting just across -pi from the truth steps over it and comes
// back wrapped into the range, where a bounded phase would stop at -pi, flagged at its bound.
TEST(FitGreybox, APhaseWrapsRatherThanStoppingAtItsBound) {
  const FitResult r = fit_ripple_phase("cogging:T_c_Nm=2e-3,N_per_rev=14,phase_rad=3.0", -2.9, 38);
  ASSERT_TRUE(r.nls.converged);
  EXPECT_TRUE(r.flags.empty()) << r.warnings[0];
  const double se = r.reported_se(0);
  EXPECT_LT(se, 0.05);
  EXPECT_NEAR(r.nls.values[0], 3.0, 4.0 * se);
  EXPECT_DOUBLE_EQ(r.model.effects.back().get("phase_rad"), r.nls.values[0]);
}

TEST(FitGreybox, AParameterAtItsBoundIsFlagged) {
  FitProblem problem;
  model::Model truth;
  truth.params.motor.J_kg_m2 *= 3.0;
  problem.runs.push_back(make_run(measure(truth, speed_only_run(), 34, false), {}, problem.model.params));
  problem.free = {"motor.J_kg_m2"};
  problem.bounds["motor.J_kg_m2"] = {1e-6, 1.2e-5};
  const FitResult r = fit_model(problem);
  ASSERT_EQ(r.warnings.size(), 1U) << r.warnings[1];
  EXPECT_EQ(r.warnings[0], "motor.J_kg_m2 = 1.2e-05 kg m^2 is at its upper bound");
  ASSERT_EQ(r.flags.size(), 1U);
  EXPECT_EQ(r.flags[0].kind, FitFlag::Kind::at_bound);
  EXPECT_FALSE(r.flags[0].undetermined());
}

// Closed-form cases of the at-bound rule: within 1e-3 of the (log) range; pressed against it
// (within 1 % and a tenth of a standard error); a level bounded by 0 only when it is 0 in all
// but name and its error covers it.
TEST(FitGreybox, AtABoundWhenTheDataCannotTellItFromTheBound) {
  EXPECT_EQ(bound_reached(0.5004, 0.01, 0.5, 2.0), BoundSide::lower);
  EXPECT_EQ(bound_reached(0.5009, 0.14, 0.5, 2.0), BoundSide::lower);
  EXPECT_EQ(bound_reached(0.5009, 0.001, 0.5, 2.0), BoundSide::none);
  EXPECT_EQ(bound_reached(0.52, 10.0, 0.5, 2.0), BoundSide::none);
  EXPECT_EQ(bound_reached(1.999, 0.01, 0.5, 2.0), BoundSide::upper);
  EXPECT_EQ(bound_reached(1.99, 0.5, 0.5, 2.0), BoundSide::upper);
  EXPECT_EQ(bound_reached(-0.99, 0.5, -1.0, 1.0), BoundSide::lower);
  EXPECT_EQ(bound_reached(-0.99, 0.05, -1.0, 1.0), BoundSide::none);
  EXPECT_EQ(bound_reached(1e-12, 1e-9, 0.0, 10.0), BoundSide::lower);
  EXPECT_EQ(bound_reached(1e-12, 1e-13, 0.0, 10.0), BoundSide::none);
  EXPECT_EQ(bound_reached(1e-3, 1.0, 0.0, 10.0), BoundSide::none);
  EXPECT_EQ(bound_reached(5.0, 1.0, 0.0, std::numeric_limits<double>::infinity()), BoundSide::none);
}

// A small viscous level the data fix to well within its size is not "at its lower bound" of 0,
// although it is below 1e-6 of the catalog's range (sized for large motors): flagging it would
// have the pinning hold it at 0.
TEST(FitGreybox, ASmallDeterminedLevelIsNotAtItsZeroBound) {
  model::Model truth;
  truth.effects.push_back(model::parse_effect("friction_levels:Tc_Nm=0.001,c1_Nm_s_rad=5e-7"));
  FitProblem problem;
  problem.model.effects.push_back(model::parse_effect("friction_levels:Tc_Nm=0.001,c1_Nm_s_rad=1e-6"));
  problem.runs.push_back(make_run(measure(truth, speed_only_run(), 36, false), {}, problem.model.params));
  problem.free = {"friction_levels.c1_Nm_s_rad"};
  const FitResult r = fit_model(problem);
  ASSERT_EQ(r.nls.values.size(), 1);
  EXPECT_NEAR(r.nls.values[0], 5e-7, 2e-8);
  EXPECT_LT(r.nls.std_errors[0], 0.1 * r.nls.values[0]);
  EXPECT_TRUE(r.flags.empty()) << r.warnings[0];
}

// What the runs do not set is pinned: a value at a lower bound of 0 at 0, an infinite error at
// the given value (when there is one); a bound that is not 0, a correlation or an undetermined
// parameter without a given value stay flagged.
TEST(FitGreybox, UndeterminedParametersArePinnedAtTheGivenValueOrTheirZeroBound) {
  using Kind = FitFlag::Kind;
  const std::vector<FitFlag> flags{{Kind::at_bound, {"hbridge.R_on_ohm"}, 0.0},
                                   {Kind::at_bound, {"param_mismatch.R_scale"}, 0.5},
                                   {Kind::undetermined, {"param_mismatch.static_scale"}},
                                   {Kind::undetermined, {"stribeck.v_s_rad_s"}},
                                   {Kind::correlated, {"motor.J_kg_m2", "motor.Kt_Nm_A"}},
                                   {Kind::impossible, {"motor.visc1_Nm_s_rad"}},
                                   {Kind::at_bound, {"param_mismatch.J_scale"}, 5.0},
                                   {Kind::at_bound, {"param_mismatch.Kt_scale"}, 2.0}};
  // J_scale drifted to its upper bound with an infinite error; Kt_scale's bound is the data's word.
  const std::vector<std::string> names{"param_mismatch.J_scale", "param_mismatch.Kt_scale"};
  const std::vector<double> errors{std::numeric_limits<double>::infinity(), 0.01};
  const auto pins =
      undetermined_pins(flags, names, errors, [](const std::string& name) -> std::optional<double> {
        if (name.starts_with("param_mismatch.")) return 1.0;
        return std::nullopt;
      });
  ASSERT_EQ(pins.size(), 3U);
  EXPECT_EQ(pins[0].name, "hbridge.R_on_ohm");
  EXPECT_EQ(pins[0].value, 0.0);
  EXPECT_EQ(pins[0].why, k_pinned_bound);
  EXPECT_EQ(pins[1].name, "param_mismatch.static_scale");
  EXPECT_EQ(pins[1].value, 1.0);
  EXPECT_EQ(pins[1].why, k_pinned_given);
  EXPECT_EQ(pins[2].name, "param_mismatch.J_scale");
  EXPECT_EQ(pins[2].value, 1.0);
  EXPECT_EQ(pins[2].why, k_pinned_given);
}

// A driver's on-resistance the speed-only runs do not see (the truth has none): fit_model drives
// it towards its bound 0 in log coordinates (1e-11 +- inf, flagged); fit_model_pinned holds it at
// 0, refits the rest without it and reports a trustworthy fit that names it pinned.
TEST(FitGreybox, AResistanceAtItsZeroBoundIsPinnedThereAndTheRestRefitted) {
  model::Model truth;
  truth.effects.push_back(model::default_effect("hbridge"));
  model::set_parameter(truth, "hbridge.R_on_ohm", 0.0);
  model::set_parameter(truth, "hbridge.deadband", 0.04);
  FitProblem problem;
  problem.model.effects.push_back(model::default_effect("hbridge"));
  problem.runs.push_back(make_run(measure(truth, speed_only_run(), 36, false), {}, problem.model.params));
  problem.free = {"motor.J_kg_m2", "hbridge.R_on_ohm", "hbridge.deadband"};
  const FitResult plain = fit_model(problem);
  EXPECT_FALSE(plain.trustworthy());
  const FitResult r = fit_model_pinned(problem);
  ASSERT_EQ(r.pinned.size(), 1U);
  EXPECT_EQ(r.pinned[0].name, "hbridge.R_on_ohm");
  EXPECT_EQ(r.pinned[0].why, k_pinned_bound);
  EXPECT_EQ(model::get_parameter(r.model, "hbridge.R_on_ohm"), 0.0);
  EXPECT_EQ(r.nls.names, (std::vector<std::string>{"motor.J_kg_m2", "hbridge.deadband"}));
  EXPECT_TRUE(r.trustworthy()) << (r.warnings.empty() ? r.nls.reason : r.warnings[0]);
  EXPECT_NEAR(model::get_parameter(r.model, "hbridge.deadband"), 0.04, 0.002);
}

// Bounds follow the given model: a motor 1000 times the rig's inertia can be fitted.
TEST(FitGreybox, BoundsAreRelativeToTheGivenModel) {
  model::Model big;
  big.params.motor.J_kg_m2 = 7e-3;
  big.params.motor.R_ohm = 0.5;
  const auto infos = model::parameters(big);
  const auto find = [&](const std::string& name) {
    return *std::find_if(infos.begin(), infos.end(), [&](const auto& p) { return p.name == name; });
  };
  EXPECT_DOUBLE_EQ(find("motor.J_kg_m2").upper, 7e-2);
  EXPECT_DOUBLE_EQ(find("motor.J_kg_m2").lower, 7e-4);
  // Friction up to the stall torque Kt supply / R; viscous c1 up to stall torque / no-load speed.
  const double stall = big.params.motor.Kt_Nm_A * big.params.supply_V / 0.5;
  EXPECT_DOUBLE_EQ(find("motor.Tc_Nm").upper, stall);
  EXPECT_DOUBLE_EQ(find("motor.visc1_Nm_s_rad").upper, stall / (big.params.supply_V / big.params.motor.Ke_V_s_rad));

  std::istringstream text("[bounds]\nmotor.J_kg_m2 = 1e-3 1\nparam_mismatch.R_scale = 0.2 5\n");
  const auto ini = config::Ini::parse(text, "b.ini");
  const auto b = read_bounds(ini, big);
  EXPECT_EQ(b.at("motor.J_kg_m2"), (std::pair<double, double>{1e-3, 1.0}));
  EXPECT_EQ(b.at("param_mismatch.R_scale"), (std::pair<double, double>{0.2, 5.0}));
  std::istringstream bad("[bounds]\nmotor.J_kg_m2 = 1 0.1\nmotor.Q = 1 2\n");
  EXPECT_EQ(error_of([&] { read_bounds(config::Ini::parse(bad, "b.ini"), big); }),
            "b.ini:2: [bounds] motor.J_kg_m2: lower bound must be below the upper");
}

// Speed measured behind a 5:1 gearbox, as the capture's `# gear_ratio:` states: fitted back.
TEST(FitGreybox, GearRatioDividesTheMeasuredSpeed) {
  const model::Model truth = speed_only_truth();
  auto table = measure(truth, speed_only_run(), 35, false);
  for (double& x : table.col("rpm")) x /= 5.0;
  table.meta.set("gear_ratio", "5");
  FitProblem problem;
  problem.runs.push_back(make_run(table, {}, problem.model.params));
  apply_speed_path(problem.runs[0], {});
  EXPECT_EQ(problem.runs[0].gear_ratio, 5.0);
  problem.free = default_free(problem.runs, {}, problem.ties);
  const FitResult r = fit_model(problem);
  EXPECT_TRUE(r.trustworthy());
  EXPECT_NEAR(r.model.params.motor.Kt_Nm_A, truth.params.motor.Kt_Nm_A, 0.02 * truth.params.motor.Kt_Nm_A);
  EXPECT_GT(r.runs[0].fit_percent[0], 95.0);
}

// A speed the drive low-passed before logging (tau 40 ms, stated as `# speed_filter:`): the
// model is filtered the same way, so the true model fits it and the fit recovers Kt; the same
// data read without the statement leave the true model far off.
TEST(FitGreybox, AStatedSpeedFilterIsModelled) {
  const model::Model truth = speed_only_truth();
  auto table = measure(truth, speed_only_run(), 37, false);
  const auto filter = measurement::parse_speed_filter("first-order low-pass, time constant 0.04 s");
  table.set("rpm", filter.apply(table.col("t"), table.col("rpm")));
  const fit::Run unstated = make_run(table, {}, truth.params);
  table.meta.set("speed_filter", measurement::format_speed_filter(filter));
  fit::Run run = make_run(table, {}, truth.params);
  apply_speed_path(run, {});
  EXPECT_GT(evaluate_model(truth, std::vector<fit::Run>{run})[0].fit_percent[0], 97.0);
  EXPECT_LT(evaluate_model(truth, std::vector<fit::Run>{unstated})[0].fit_percent[0], 90.0);
  FitProblem problem;
  problem.runs.push_back(run);
  problem.free = default_free(problem.runs, {}, problem.ties);
  const FitResult r = fit_model(problem);
  EXPECT_TRUE(r.trustworthy());
  EXPECT_NEAR(r.model.params.motor.Kt_Nm_A, truth.params.motor.Kt_Nm_A, 0.02 * truth.params.motor.Kt_Nm_A);

  measurement::SpeedPath ini;
  ini.filter = measurement::parse_speed_filter("moving average over 0.01 s");
  EXPECT_EQ(error_of([&] { apply_speed_path(run, ini); }),
            "sim.csv: speed_filter 'first-order low-pass, time constant 0.04 s' differs from the model's "
            "[measurement] speed_filter 'moving average over 0.01 s'");
}

// A torque-driven run whose logged torque carries a constant offset (0.8 mN m, a third of the
// Coulomb level), the shaft turning both ways, speed measured by the encoder: the drive's bias
// freed beside the default set (its effect brought in at 0) comes back with J, Tc and c1, and
// the jackknife over the stretches gives each a finite error, reported when it is the larger.
// Without the bias term the fit leaves a residual ten times larger.
/// The torque-driven run of the tests below: the rig with a drive bias of 0.8 mN m, fitted with
/// the default free set and the bias.
FitProblem driven_offset_problem(model::Model& truth) {
  truth.effects.push_back(model::default_effect("friction_asymmetry"));
  truth.effects.back().set("dT_Nm", 8e-4);
  Program p;
  for (const double v : {0.0, 6.0, 10.0, 3.0, -6.0, -10.0, -3.0, 8.0, 0.0}) p.hold(v, 1.0, 0);
  p.inputs.T_cmd_Nm.clear();
  for (const double v : p.inputs.v_V) p.inputs.T_cmd_Nm.push_back(1e-3 * v);
  table::Table table = measure(truth, p.inputs, 41, false);
  table.set("T_Nm", p.inputs.T_cmd_Nm);
  FitProblem problem;
  problem.runs.push_back(make_run(table, {}, problem.model.params, 50, DriveInput{false, "T_Nm"}));
  problem.free = default_free(problem.runs, {}, problem.ties);
  return problem;
}

TEST(FitGreybox, ADrivenRunsOffsetIsFittedWithAJackknife) {
  model::Model truth;
  FitProblem problem = driven_offset_problem(truth);
  ASSERT_EQ(problem.free, (std::vector<std::string>{"motor.J_kg_m2", "motor.Tc_Nm", "motor.visc1_Nm_s_rad"}));
  problem.free.emplace_back(k_drive_offset);
  add_free_effects(problem.model, problem.free);
  ASSERT_NE(problem.model.effect("friction_asymmetry"), nullptr);
  EXPECT_EQ(model::get_parameter(problem.model, k_drive_offset), 0.0);
  problem.sim.max_step_s = 2.5e-4;
  problem.jackknife_stretches = 6;
  const FitResult r = fit_model(problem);
  EXPECT_TRUE(r.trustworthy()) << r.nls.reason << (r.warnings.empty() ? "" : ": " + r.warnings[0]);
  EXPECT_NEAR(model::get_parameter(r.model, k_drive_offset), 8e-4, 0.05 * 8e-4);
  const auto& want = truth.params.motor;
  EXPECT_NEAR(r.model.params.motor.friction.Tc_Nm, want.friction.Tc_Nm, 0.03 * want.friction.Tc_Nm);
  EXPECT_NEAR(r.model.params.motor.J_kg_m2, want.J_kg_m2, 0.03 * want.J_kg_m2);
  ASSERT_EQ(r.se_jackknife.size(), 4U);
  EXPECT_EQ(r.jackknife_stretches, 6U);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_TRUE(std::isfinite(r.se_jackknife[k]) && r.se_jackknife[k] > 0.0) << k;
    EXPECT_EQ(r.reported_se(k), std::max(r.se_jackknife[k], r.widened_se(k)));
    EXPECT_LT(r.se_jackknife[k], 0.05 * std::abs(r.nls.values[static_cast<Eigen::Index>(k)])) << k;
  }
  // The same run fitted without the bias: the friction per direction cannot take it up.
  problem.free.pop_back();
  problem.jackknife_stretches = 0;
  const FitResult without = fit_model(problem);
  EXPECT_TRUE(without.se_jackknife.empty());
  EXPECT_GT(without.nls.cost, 10.0 * r.nls.cost);
}

// The linearised jackknife (one Gauss-Newton step per stretch left out, on the fit's own
// Jacobian) gives the refitting jackknife's errors to within a third, at no simulation: the
// fit costs what it costs without a jackknife.
TEST(FitGreybox, TheLinearisedJackknifeIsTheRefitsWithoutTheirSimulations) {
  model::Model truth;
  FitProblem problem = driven_offset_problem(truth);
  problem.free.emplace_back(k_drive_offset);
  add_free_effects(problem.model, problem.free);
  problem.sim.max_step_s = 2.5e-4;
  problem.jackknife_stretches = 6;
  const FitResult refits = fit_model(problem);
  problem.jackknife_linearised = true;
  const FitResult linear = fit_model(problem);
  problem.jackknife_stretches = 0;
  const FitResult none = fit_model(problem);
  ASSERT_EQ(refits.se_jackknife.size(), 4U);
  ASSERT_EQ(linear.se_jackknife.size(), 4U);
  EXPECT_EQ(linear.jackknife_stretches, 6U);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_GT(linear.se_jackknife[k], 0.67 * refits.se_jackknife[k]) << k;
    EXPECT_LT(linear.se_jackknife[k], 1.5 * refits.se_jackknife[k]) << k;
  }
  EXPECT_EQ(linear.nls.simulations, none.nls.simulations);
  EXPECT_TRUE(none.se_jackknife.empty());
}

TEST(FitGreybox, TimeRangeOmegaAndFixedValues) {
  const auto table = measure(model::Model{}, speed_only_run(), 36, false);
  const auto part = select_time(table, 0.5, 1.0);
  EXPECT_EQ(part.rows(), 501U);
  EXPECT_EQ(part.col("t").front(), 0.5);
  EXPECT_EQ(part.first_line, table.first_line + 500);
  EXPECT_EQ(error_of([&] { select_time(table, 10.0, 11.0); }), "sim.csv: no rows between --from 10 s and --to 11 s");

  table::Table omega = table;
  omega.names[4] = "omega";
  const auto converted = with_rpm(omega);
  EXPECT_NEAR(converted.col("rpm")[600], table.col("rpm")[600] * 30.0 / M_PI, 1e-9);

  model::Model m;
  EXPECT_EQ(fix_parameters(m, {"motor.R_ohm=2.5", "motor.L_H=1e-3"}),
            (std::vector<std::string>{"motor.R_ohm", "motor.L_H"}));
  EXPECT_EQ(m.params.motor.R_ohm, 2.5);
  EXPECT_EQ(error_of([&] { fix_parameters(m, {"motor.R_ohm"}); }), "--fix: expected NAME=VALUE: 'motor.R_ohm'");
  EXPECT_EQ(error_of([&] { fix_parameters(m, {"motor.R=1"}); }),
            "--fix: unknown parameter 'motor.R' (see mcg-fit model --list)");
  EXPECT_EQ(error_of([&] { fix_parameters(m, {"motor.R_ohm=x"}); }), "--fix: motor.R_ohm: invalid number 'x'");
}

/// Per catalog effect the gap search fits: the fit of a run measured with the effect at a value
/// of its grid, started from another.
std::vector<std::pair<std::string, FitProblem>> every_effect_fit() {
  Program p;
  p.hold(0.0, 0.05, 0).hold(6.0, 0.25, 0).hold(-5.0, 0.25, 0).hold(1.2, 0.2, 0);
  p.hold(8.0, 0.25, 2).hold(11.0, 0.25, 2, 5.6).hold(3.0, 0.2, 2, 5.6).hold(-6.0, 0.25, 2);
  std::vector<std::pair<std::string, FitProblem>> fits;
  for (const model::EffectSpec& spec : model::effect_catalog()) {
    const model::EffectPlan& plan = spec.plan;
    if (!plan.candidate || plan.free.empty()) continue;
    const model::Model nominal;
    const std::vector<double> scale =
        plan.grid_scale != nullptr
            ? plan.grid_scale(nominal.params, model::voltage_drive_scale(nominal.params))
            : std::vector<double>(plan.free.size(), 1.0);
    model::Model truth = nominal;
    model::Model start = nominal;
    truth.effects.push_back(model::default_effect(spec.name));
    start.effects.push_back(model::default_effect(spec.name));
    FitProblem problem;
    for (std::size_t k = 0; k < plan.free.size(); ++k) {
      if (plan.free[k] == plan.angle_order_key) continue;
      const auto& grid = plan.grid[k];
      truth.effects.back().set(plan.free[k], grid[grid.size() > 1 ? 1 : 0] * scale[k]);
      start.effects.back().set(plan.free[k], grid[0] * scale[k] * (grid.size() > 1 ? 1.0 : 1.3));
      problem.free.push_back(spec.name + "." + plan.free[k]);
    }
    problem.runs.push_back(make_run(measure(truth, p.inputs, 31), {}, nominal.params));
    problem.model = start;
    problem.sim.smooth_stick = plan.friction;
    problem.nls.max_evaluations = 60 * static_cast<int>(problem.free.size() + 1);
    fits.emplace_back(spec.name, std::move(problem));
  }
  return fits;
}

/// `other` lands where the finite-difference fit `fd` does: within 2 % of the standard error
/// (plus 1e-6 relative), with standard errors within 2 %; where the residual is not smooth at
/// the optimum in a parameter (NlsResult::rough), within 2.5 standard errors.
void expect_lands_alike(const FitResult& fd, const FitResult& other, const std::string& effect) {
  EXPECT_TRUE(other.nls.converged) << effect << ": " << other.nls.reason;
  // Not smooth at the optimum (a clutch event moves with it): the two paths may stop at
  // different points of the rough floor, within the error.
  const auto is_rough = [](const FitResult& f) {
    return std::find(f.nls.rough.begin(), f.nls.rough.end(), true) != f.nls.rough.end();
  };
  const bool rough = is_rough(fd) || is_rough(other);
  for (Eigen::Index i = 0; i < fd.nls.values.size(); ++i) {
    const double v = fd.nls.values[i];
    const double se = fd.nls.std_errors[i];
    const std::string& name = fd.nls.names[static_cast<std::size_t>(i)];
    if (rough) {
      const double wider = std::max(se, other.nls.std_errors[i]);
      EXPECT_NEAR(other.nls.values[i], v, 2.5 * wider + 1e-6 * std::abs(v))
          << name << " +- " << wider << " (rough)";
      continue;
    }
    EXPECT_NEAR(other.nls.values[i], v, 0.02 * se + 1e-6 * std::abs(v)) << name << " +- " << se;
    EXPECT_NEAR(other.nls.std_errors[i], se, 0.02 * se) << name;
  }
}

// The gap search fits each catalog effect with Broyden updates between finite-difference
// Jacobians (NlsOptions::broyden): the updated solver lands where the finite-difference one
// does (expect_lands_alike) for every effect's fitted parameters. Effects the run does not
// determine (infinite error, or a fit that does not converge) are counted apart; most must be
// checked.
TEST(FitGreybox, BroydenUpdatesFitEveryEffectAsFiniteDifferencesDo) {
  int checked = 0;
  std::vector<std::string> unchecked;
  for (auto& [effect, problem] : every_effect_fit()) {
    const FitResult fd = fit_model(problem);
    problem.nls.broyden = true;
    const FitResult updated = fit_model(problem);
    if (!fd.nls.converged || !fd.nls.std_errors.allFinite()) {
      unchecked.push_back(effect);
      continue;
    }
    ++checked;
    expect_lands_alike(fd, updated, effect);
  }
  EXPECT_GE(checked, 8) << "not determined by the run: " << ::testing::PrintToString(unchecked);
}

// The Jacobian by sensitivities along the simulation (FitProblem::sensitivities) against the
// one by finite differences, on the same fits: it lands alike (expect_lands_alike), and no
// Jacobian falls back to finite differences.
TEST(FitGreybox, SensitivitiesFitEveryEffectAsFiniteDifferencesDo) {
  int checked = 0;
  std::vector<std::string> unchecked;
  for (auto& [effect, problem] : every_effect_fit()) {
    const FitResult fd = fit_model(problem);
    problem.sensitivities = true;
    const FitResult ad = fit_model(problem);
    EXPECT_GT(ad.nls.sensitivity_jacobians, 0) << effect;
    EXPECT_EQ(ad.nls.fd_jacobians, 0) << effect;
    if (!fd.nls.converged || !fd.nls.std_errors.allFinite()) {
      unchecked.push_back(effect);
      continue;
    }
    ++checked;
    expect_lands_alike(fd, ad, effect);
  }
  EXPECT_GE(checked, 8) << "not determined by the run: " << ::testing::PrintToString(unchecked);
}

}  // namespace
}  // namespace mcg::fit
