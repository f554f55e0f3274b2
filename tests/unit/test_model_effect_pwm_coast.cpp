// pwm_coast against its closed forms on the motor alone (steady speed and mean current at a
// duty, a zero duty that leaves the shaft free), and simulated with the effect, measured like
// the rig, its share fitted back.
#include <gtest/gtest.h>

#include <cmath>

#include "fit/greybox.hpp"
#include "model/model.hpp"
#include "support/inputs.hpp"
#include "test_fit_support.hpp"

namespace mcg::model {
namespace {

Model coasting(double c) {
  Model m;
  m.effects.push_back(parse_effect("pwm_coast:coast=" + std::to_string(c)));
  return m;
}

/// Steady speed of the motor alone at v > 0 (duty d = v / supply): the mean current is
/// i = (d supply - s Ke w) / R with s = 1 - c (1 - d), and Kt i = F(w); by bisection on w.
double steady_speed(const Params& p, double v, double c) {
  const Machine& m = p.motor;
  const double d = v / p.supply_V;
  const double s = 1.0 - c * (1.0 - d);
  double lo = 0.0, hi = v / (s * m.Ke_V_s_rad);
  for (int it = 0; it < 200; ++it) {
    const double w = 0.5 * (lo + hi);
    const double net = m.Kt_Nm_A * (v - s * m.Ke_V_s_rad * w) / m.R_ohm - m.friction.kinetic_Nm(w);
    (net > 0.0 ? lo : hi) = w;
  }
  return 0.5 * (lo + hi);
}

TEST(ModelEffectPwmCoast, SteadySpeedAndMeanCurrentFollowTheCoastingShare) {
  const Params p = builtin_rig();
  for (double c : {0.4, 1.0}) {
    for (double v : {2.0, 5.0, 12.0}) {
      const Outputs out = simulate(coasting(c), test::constant_inputs(v, 1.5, 1e-3, 0));
      const double w = out.omega_rad_s.back();
      EXPECT_NEAR(w, steady_speed(p, v, c), 1e-3) << c << " " << v;
      // The current column is the mean current: its torque holds the friction.
      EXPECT_NEAR(p.motor.Kt_Nm_A * out.i_A.back(), p.motor.friction.kinetic_Nm(w), 1e-9) << c << " " << v;
      // The terminals carry d supply in the on-time and Ke w in the coasting share.
      const double d = v / p.supply_V;
      EXPECT_NEAR(out.v_applied_V.back(), v + c * (1.0 - d) * p.motor.Ke_V_s_rad * w, 1e-9);
      // Against the braking drive, the speed at a low duty is far higher.
      EXPECT_GT(w, steady_speed(p, v, 0.0) * (1.0 + 0.5 * c * (1.0 - d))) << c << " " << v;
    }
  }
  // In reverse, the mirror image.
  const Outputs rev = simulate(coasting(1.0), test::constant_inputs(-5.0, 1.5, 1e-3, 0));
  EXPECT_NEAR(-rev.omega_rad_s.back(), steady_speed(p, 5.0, 1.0), 1e-3);
}

TEST(ModelEffectPwmCoast, NoCoastIsTheBrakingDriveAndFullCoastLeavesTheShaftFree) {
  const Inputs in = test::constant_inputs(6.0, 0.5, 1e-3, 0);
  EXPECT_EQ(simulate(coasting(0.0), in).rpm, simulate(Model{}, in).rpm);
  // Spun up, then duty 0: the braking drive shorts the back-emf; a coasting one opens the
  // circuit, no current flows and only friction slows the shaft.
  fit::testing::Program prog;
  prog.hold(6.0, 0.5, 0).hold(0.0, 0.005, 0);
  const Outputs free_run = simulate(coasting(1.0), prog.inputs);
  const Outputs braked = simulate(Model{}, prog.inputs);
  // 5 ms on, the coasting circuit's current has decayed by L/R towards 0 from above; the
  // braking drive's has reversed to about -Ke w / R.
  EXPECT_GE(free_run.i_A.back(), 0.0);
  EXPECT_LT(braked.i_A.back(), -0.01);
  EXPECT_LT(free_run.i_A.back(), 0.05 * -braked.i_A.back());
  EXPECT_GT(free_run.omega_rad_s.back(), braked.omega_rad_s.back() + 1.0);
}

TEST(ModelEffectPwmCoast, SimulatedThenFittedComesBack) {
  fit::testing::Program p;
  p.hold(0.0, 0.1, 0).hold(1.5, 0.4, 0).hold(3.0, 0.4, 0).hold(8.0, 0.4, 0).hold(0.0, 0.3, 0);
  p.hold(-2.0, 0.4, 0).hold(-6.0, 0.4, 0).hold(0.0, 0.3, 0);
  const auto table = fit::testing::measure(coasting(0.7), p.inputs, 5);
  fit::FitProblem problem;
  problem.model = coasting(0.3);
  problem.runs.push_back(fit::make_run(table, {}, problem.model.params));
  problem.free = {"pwm_coast.coast"};
  const fit::FitResult result = fit::fit_model(problem);
  ASSERT_TRUE(result.nls.converged) << result.nls.reason;
  EXPECT_NEAR(result.model.effect("pwm_coast")->get("coast"), 0.7, 0.02);
}

}  // namespace
}  // namespace mcg::model
