// The regularised stick (SimOptions::smooth_stick) against the exact stick-slip, and the
// breakaway fitted on it: a small motor (Coulomb 0.6 V, breakaway 0.85 V of drive) on a
// staircase whose first moving step is 3 V, and a slow ramp that shows the breakaway.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "fit/gap_parts.hpp"
#include "fit/greybox.hpp"
#include "test_fit_support.hpp"

namespace mcg::fit {
namespace {

using testing::measure;
using testing::Program;

/// A 12 V hobby motor alone (no clutch, no generator), its friction given in volts of drive.
model::Model small_motor(double coulomb_V, double breakaway_V) {
  model::Model m;
  model::Machine& mm = m.params.motor;
  mm.R_ohm = 2.5;
  mm.L_H = 1e-3;
  mm.Kt_Nm_A = 0.015;
  mm.Ke_V_s_rad = 0.015;
  mm.J_kg_m2 = 3e-6;
  mm.friction = {};
  mm.friction.Tc_Nm = coulomb_V * mm.Kt_Nm_A / mm.R_ohm;
  mm.friction.Ts_Nm = breakaway_V * mm.Kt_Nm_A / mm.R_ohm;
  mm.friction.viscous[0] = 2e-6;
  m.params.supply_V = 12.0;
  return m;
}

double volts(const model::Model& m, double torque_Nm) {
  return torque_Nm * m.params.motor.R_ohm / m.params.motor.Kt_Nm_A;
}

/// From rest: a staircase 3, 6, 9 V and down through zero, then a ramp 0 -> 1.5 V over 3 s.
model::Inputs staircase_and_ramp() {
  Program p;
  p.hold(0.0, 0.2, 0).hold(3.0, 0.5, 0).hold(6.0, 0.5, 0).hold(9.0, 0.5, 0).hold(0.0, 0.5, 0);
  p.hold(-3.0, 0.5, 0).hold(-6.0, 0.5, 0).hold(0.0, 0.5, 0);
  p.ramp(0.0, 1.5, 3.0, 0).hold(0.0, 0.5, 0);
  return p.inputs;
}

double rms_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) s += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(s / static_cast<double>(a.size()));
}

// Well below the breakaway both models hold the shaft; above it both run alike, the
// regularised one breaking away within 0.1 ms of the exact one.
TEST(SmoothStick, HoldsAndRunsLikeTheExactModel) {
  const model::Model m = small_motor(0.6, 0.85);
  model::SimOptions smooth;
  smooth.smooth_stick = true;
  Program held;
  held.hold(0.7, 2.0, 0);
  for (double w : model::simulate(m, held.inputs, smooth).omega_rad_s) ASSERT_EQ(w, 0.0);
  Program running;
  running.hold(0.0, 0.1, 0).hold(1.0, 0.5, 0).hold(6.0, 0.5, 0);
  const model::Outputs exact = model::simulate(m, running.inputs);
  const model::Outputs regular = model::simulate(m, running.inputs, smooth);
  double largest = 0.0;
  for (std::size_t k = 0; k < exact.rpm.size(); ++k) {
    largest = std::max(largest, std::abs(exact.rpm[k] - regular.rpm[k]));
  }
  EXPECT_GT(exact.rpm[200], 100.0);
  EXPECT_LT(largest, 2.0);
  EXPECT_NEAR(regular.rpm.back(), exact.rpm.back(), 1e-6 * exact.rpm.back());
}

// On the exact stick-slip a breakaway just below a staircase level and one just above it give
// runs that differ by the whole level's motion; on the regularised stick the run moves with
// the breakaway continuously.
TEST(SmoothStick, TheRunMovesContinuouslyWithTheBreakaway) {
  const model::Inputs in = staircase_and_ramp();
  model::SimOptions smooth;
  smooth.smooth_stick = true;
  const model::Model below = small_motor(0.6, 3.0 * (1.0 - 1e-4));
  const model::Model above = small_motor(0.6, 3.0 * (1.0 + 1e-4));
  const double exact_jump = rms_difference(model::simulate(below, in).rpm, model::simulate(above, in).rpm);
  const double smooth_jump =
      rms_difference(model::simulate(below, in, smooth).rpm, model::simulate(above, in, smooth).rpm);
  EXPECT_GT(exact_jump, 100.0);
  EXPECT_LT(smooth_jump, 1.0);
}

// Started just above the 3 V step that first moves the motor (where a plain mean of the
// staircase's brackets puts the start), the breakaway fitted on the exact stick-slip is lost
// (the run does not move with it until it crosses the step); on the regularised stick it
// comes to the ramps' 0.85 V (0.005 V high: on a ramp of 0.5 V/s the regularised breakaway
// comes 0.53 % of Ts early) with a finite standard error.
TEST(SmoothStick, TheBreakawayFitDoesNotLockOntoAStep) {
  const model::Model truth = small_motor(0.6, 0.85);
  const table::Table data = measure(truth, staircase_and_ramp(), 41, false);
  const auto fit = [&](bool smooth_stick) {
    FitProblem problem;
    problem.model = small_motor(0.6, 3.05);
    problem.runs.push_back(make_run(data, {"rpm"}, problem.model.params));
    problem.free = {"motor.Ts_Nm"};
    problem.sim.smooth_stick = smooth_stick;
    return fit_model(problem);
  };
  const FitResult exact = fit(false);
  const FitResult smooth = fit(true);
  EXPECT_GT(std::abs(volts(truth, exact.model.params.motor.friction.Ts_Nm) - 0.85), 0.5);
  EXPECT_NEAR(volts(truth, smooth.model.params.motor.friction.Ts_Nm), 0.85, 0.01);
  const double se_V = volts(truth, smooth.nls.std_errors[0]);
  EXPECT_GT(se_V, 1e-6);
  EXPECT_LT(se_V, 1e-3);
}

// The gap search starts friction_levels where the data put it: given the motor without any
// friction, the static excess is the data's Ts - Tc (0.25 V of drive), not net of brackets the
// frictionless model's coasting shaft makes at the staircase's steps (which took it to its floor).
TEST(SmoothStick, TheStaticExcessStartsFromTheData) {
  const table::Table data = measure(small_motor(0.6, 0.85), staircase_and_ramp(), 42, false);
  model::Model given = small_motor(0.0, 0.0);
  given.params.motor.friction.viscous[0] = 0.0;
  const std::vector<fit::Run> runs{make_run(data, {"rpm"}, given.params)};
  const auto starts = gap_detail::data_friction_starts(given, runs);
  ASSERT_EQ(starts.count("friction_levels"), 1U);
  const auto& levels = starts.at("friction_levels");
  EXPECT_NEAR(volts(given, levels[0]), 0.6, 0.03);
  EXPECT_NEAR(volts(given, levels[1]), 0.25, 0.03);
  EXPECT_NEAR(levels[2], 2e-6, 2e-7);
}

}  // namespace
}  // namespace mcg::fit
