// A motor whose electrical time constant is far below any step (a low-inductance gearmotor)
// has its current solved as algebraic: the steady states stay exact, the trajectory matches
// the integrated circuit's, and a brush drop no longer forces sub-microsecond steps.
#include <gtest/gtest.h>

#include <cmath>

#include "model/model.hpp"

namespace mcg::model {
namespace {

Model gearmotor(double L_H) {
  Model m;
  Machine& mm = m.params.motor;
  mm.R_ohm = 4.2;
  mm.L_H = L_H;
  mm.Kt_Nm_A = mm.Ke_V_s_rad = 0.0062;
  mm.J_kg_m2 = 6e-7;
  mm.friction = Friction{0.0005, 0.0004, {4e-7, 0.0, 0.0}};
  m.params.supply_V = 12.0;
  return m;
}

Inputs steps(double duration_s) {
  Inputs in;
  for (std::size_t n = 0; n <= static_cast<std::size_t>(std::llround(duration_s / 1e-3)); ++n) {
    const double t = static_cast<double>(n) * 1e-3;
    in.t_s.push_back(t);
    in.v_V.push_back(t < duration_s / 2 ? 6.0 : -3.0);
    in.clutch.push_back(0.0);
    in.r_load_ohm.push_back(k_open_circuit);
  }
  return in;
}

TEST(ModelFastCircuit, SteadySpeedOfTheAlgebraicCircuitIsExact) {
  // 4.2 ohm / 0.1 mH = 42000/s: algebraic. Kt (v - Ke w)/R = Tc + c1 w at 6 V.
  const Model m = gearmotor(1e-4);
  const Machine& mm = m.params.motor;
  const double w = (mm.Kt_Nm_A * 6.0 / mm.R_ohm - 0.0004) / (mm.Kt_Nm_A * mm.Ke_V_s_rad / mm.R_ohm + 4e-7);
  const Outputs out = simulate(m, steps(3.0));  // 1.5 s at 6 V: 23 mechanical time constants
  EXPECT_NEAR(out.omega_rad_s[1499], w, 1e-6 * w);
  EXPECT_NEAR(out.i_A[1499], (6.0 - mm.Ke_V_s_rad * w) / mm.R_ohm, 1e-9);
}

TEST(ModelFastCircuit, MatchesTheIntegratedCircuitJustBelowTheThreshold) {
  // 4.2 ohm / 0.25 mH = 16800/s is integrated, 0.1 mH is algebraic: within 0.5 % of the
  // speed range everywhere (the inductance differs, so not to the last digit).
  const Outputs fast = simulate(gearmotor(1e-4), steps(0.4));
  const Outputs slow = simulate(gearmotor(2.5e-4), steps(0.4));
  double worst = 0.0;
  for (std::size_t n = 0; n < fast.rpm.size(); ++n)
    worst = std::max(worst, std::abs(fast.rpm[n] - slow.rpm[n]));
  EXPECT_LT(worst, 0.005 * 18000.0);
}

/// The gearmotor steady at 6 V with a brush drop V_b (the last row of the first half of
/// steps()): R i + V_b tanh(i/0.01) = v - Ke w (within `tol_V`) and Kt i = Tc + c1 w.
void expect_steady_at_6V(const Outputs& out, double V_b, double tol_V) {
  const double w = out.omega_rad_s[3999];
  const double i = out.i_A[3999];
  EXPECT_NEAR(4.2 * i + V_b * std::tanh(i / 0.01), 6.0 - 0.0062 * w, tol_V);
  EXPECT_NEAR(0.0062 * i, 0.0004 + 4e-7 * w, 1e-9);
}

TEST(ModelFastCircuit, ABrushDropOnALowInductanceMotorIntegratesAtOrdinarySteps) {
  Model m = gearmotor(5e-5);
  m.effects.push_back(parse_effect("brush_drop:V_b_V=2"));
  // 8 s at 1 ms in a fraction of a second (at the brush drop's sub-microsecond steps it took
  // minutes, which the test's timeout would catch).
  const Outputs out = simulate(m, steps(8.0));
  expect_steady_at_6V(out, 2.0, 1e-9);
}

TEST(ModelFastCircuit, AStrongBrushDropOnACircuitJustSlowerThanTheThresholdStaysOrdinary) {
  // 4.2 ohm / 0.25 mH is integrated, but a 3 V drop adds 300 ohm near zero current
  // (L / R_eff = 0.8 us): those steps take the current as algebraic. Reversals cross zero
  // current every half period; the steady state holds its closed form.
  Model m = gearmotor(2.5e-4);
  m.effects.push_back(parse_effect("brush_drop:V_b_V=3"));
  const Outputs out = simulate(m, steps(8.0));
  expect_steady_at_6V(out, 3.0, 1e-6);
  // At -3 V the whole drive is brush drop: the shaft runs down and sticks.
  EXPECT_EQ(out.omega_rad_s.back(), 0.0);
}

}  // namespace
}  // namespace mcg::model
