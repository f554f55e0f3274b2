// A motor whose electrical time constant is far below any step (a low-inductance gearmotor)
// has its current solved as algebraic: the steady states stay exact, the trajectory matches
// the integrated circuit's, and a brush drop no longer forces sub-microsecond steps; a brush
// drop's circuit is smooth in its parameters.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

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

/// The rig behind a 2.5 ms dead time with a brush drop of V_b (test_gap_range's dead_time +
/// brush_drop pair), the clutch engaged, driven by steps of 3-12 V with the generator loaded
/// for a second: 3 s at 1 kHz.
Outputs pair_run(double V_b_V) {
  Model m;
  m.effects.push_back(parse_effect("dead_time:tau_d_s=0.0025"));
  m.effects.push_back(parse_effect("brush_drop:V_b_V=" + std::to_string(V_b_V)));
  Inputs in;
  for (int n = 0; n <= 3000; ++n) {
    const double t = n * 1e-3;
    double v = t < 0.1 ? 0.0 : 4.0;
    for (const auto& [at, level] : {std::pair{0.6, 9.0}, {1.1, 6.0}, {1.6, 12.0}, {2.1, 3.0}, {2.5, 8.0}})
      if (t >= at) v = level;
    in.t_s.push_back(t);
    in.v_V.push_back(v);
    in.clutch.push_back(2.0);
    in.r_load_ohm.push_back(t >= 0.9 && t < 1.9 ? 5.6 : k_open_circuit);
  }
  return simulate(m, in);
}

TEST(ModelFastCircuit, ABrushDropsRunIsSmoothInItsDrop) {
  // A fit's cost against the run at 1.1 V, sum (rpm - rpm_ref)^2 + ((i - i_ref) / 3 mA)^2,
  // sampled every 0.1 mV about its minimum: a parabola there, so its second differences are
  // all alike. A circuit that changes how it is solved at a current that moves with V_b
  // (algebraic below a time constant) jumps by 5 % of them; so would a step count that
  // changed the run by more than a trace.
  const Outputs ref = pair_run(1.1);
  std::vector<double> cost;
  for (int k = -40; k <= 40; ++k) {
    const Outputs out = pair_run(1.1 + 1e-4 * k);
    double c = 0.0;
    for (std::size_t n = 0; n < ref.rpm.size(); ++n) {
      const double di = (out.i_A[n] - ref.i_A[n]) / 3e-3;
      c += (out.rpm[n] - ref.rpm[n]) * (out.rpm[n] - ref.rpm[n]) + di * di;
    }
    cost.push_back(c);
  }
  std::vector<double> d2;
  for (std::size_t k = 1; k + 1 < cost.size(); ++k) d2.push_back(cost[k + 1] - 2.0 * cost[k] + cost[k - 1]);
  std::vector<double> sorted = d2;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
  const double median = sorted[sorted.size() / 2];
  ASSERT_GT(median, 0.0);
  for (std::size_t k = 0; k < d2.size(); ++k) EXPECT_NEAR(d2[k], median, 0.01 * median) << "at " << k;
}

}  // namespace
}  // namespace mcg::model
