// friction_asymmetry against its closed forms: direction-dependent steady speeds and
// breakaway levels of the motor alone.
#include <gtest/gtest.h>

#include <cmath>

#include "model/model.hpp"
#include "support/inputs.hpp"

namespace mcg::model {
namespace {

constexpr double k_dT_Nm = 1.2e-3;

Model asymmetric() {
  Model m;
  m.effects.push_back(parse_effect("friction_asymmetry:dT_Nm=0.0012"));
  return m;
}

/// Steady speed of the motor alone at voltage v > 0 against a kinetic level F(w) + offset:
/// Kt (v - Ke w) / R = F(w) + offset, solved by bisection on w in (0, v / Ke).
double steady_speed(const Machine& m, double v, double offset_Nm) {
  double lo = 0.0, hi = v / m.Ke_V_s_rad;
  for (int it = 0; it < 200; ++it) {
    const double w = 0.5 * (lo + hi);
    const double net = m.Kt_Nm_A * (v - m.Ke_V_s_rad * w) / m.R_ohm - m.friction.kinetic_Nm(w) - offset_Nm;
    (net > 0.0 ? lo : hi) = w;
  }
  return 0.5 * (lo + hi);
}

TEST(ModelEffectFrictionAsymmetry, SteadySpeedsDifferByDirectionAsTheLevelsSay) {
  const Machine& m = builtin_rig().motor;
  const double v = 6.0;
  const Outputs fwd = simulate(asymmetric(), test::constant_inputs(v, 1.5));
  const Outputs rev = simulate(asymmetric(), test::constant_inputs(-v, 1.5));
  EXPECT_NEAR(fwd.omega_rad_s.back(), steady_speed(m, v, k_dT_Nm), 1e-3);
  EXPECT_NEAR(-rev.omega_rad_s.back(), steady_speed(m, v, -k_dT_Nm), 1e-3);
  // Without the effect both directions run at the symmetric speed.
  const Outputs sym = simulate(Model{}, test::constant_inputs(-v, 1.5));
  EXPECT_NEAR(-sym.omega_rad_s.back(), steady_speed(m, v, 0.0), 1e-3);
  EXPECT_GT(-rev.omega_rad_s.back() - fwd.omega_rad_s.back(), 1.0);
}

TEST(ModelEffectFrictionAsymmetry, BreakawayAtTsPlusDtForwardAndTsMinusDtInReverse) {
  const Machine& m = builtin_rig().motor;
  // At rest the current settles at v / R: the shaft breaks away when Kt v / R leaves the band.
  const double v_fwd = (m.friction.Ts_Nm + k_dT_Nm) * m.R_ohm / m.Kt_Nm_A;
  const double v_rev = (m.friction.Ts_Nm - k_dT_Nm) * m.R_ohm / m.Kt_Nm_A;
  auto moves = [&](double v) {
    const Outputs out = simulate(asymmetric(), test::constant_inputs(v, 0.3));
    return std::abs(out.omega_rad_s.back()) > 0.0;
  };
  EXPECT_FALSE(moves(0.98 * v_fwd));
  EXPECT_TRUE(moves(1.02 * v_fwd));
  EXPECT_FALSE(moves(-0.98 * v_rev));
  EXPECT_TRUE(moves(-1.02 * v_rev));
  // Forward, the reverse breakaway level is not enough.
  EXPECT_FALSE(moves(1.02 * v_rev));
}

}  // namespace
}  // namespace mcg::model
