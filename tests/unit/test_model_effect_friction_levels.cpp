// friction_levels against its closed forms on a frictionless motor: the steady speed under
// the added Coulomb and viscous levels, and the breakaway at the added static level.
#include <gtest/gtest.h>

#include <cmath>

#include "model/model.hpp"
#include "support/inputs.hpp"

namespace mcg::model {
namespace {

constexpr double k_Tc_Nm = 1.5e-3;
constexpr double k_excess_Nm = 0.8e-3;
constexpr double k_c1 = 3e-6;

Model frictionless_with_levels() {
  Model m;
  m.params.motor.friction = Friction{};
  m.effects.push_back(parse_effect("friction_levels:Tc_Nm=0.0015,Ts_excess_Nm=0.0008,c1_Nm_s_rad=3e-6"));
  return m;
}

TEST(ModelEffectFrictionLevels, SteadySpeedUnderTheAddedCoulombAndViscousLevels) {
  // Kt (v - Ke w) / R = Tc + c1 w  =>  w = (Kt v / R - Tc) / (Kt Ke / R + c1), both directions.
  const Model m = frictionless_with_levels();
  const Machine& mm = m.params.motor;
  for (double v : {7.0, -7.0}) {
    const double w =
        (mm.Kt_Nm_A * std::abs(v) / mm.R_ohm - k_Tc_Nm) / (mm.Kt_Nm_A * mm.Ke_V_s_rad / mm.R_ohm + k_c1);
    EXPECT_NEAR(simulate(m, test::constant_inputs(v, 1.5)).omega_rad_s.back(), std::copysign(w, v), 1e-6 * w);
  }
}

TEST(ModelEffectFrictionLevels, BreakawayAtTheAddedStaticLevel) {
  const Model m = frictionless_with_levels();
  const Machine& mm = m.params.motor;
  const double v_break = (k_Tc_Nm + k_excess_Nm) * mm.R_ohm / mm.Kt_Nm_A;
  EXPECT_EQ(simulate(m, test::constant_inputs(0.98 * v_break, 0.3)).omega_rad_s.back(), 0.0);
  EXPECT_GT(simulate(m, test::constant_inputs(1.02 * v_break, 0.3)).omega_rad_s.back(), 0.0);
  // Without the effect the frictionless motor turns at any voltage.
  Model bare = m;
  bare.effects.clear();
  EXPECT_GT(simulate(bare, test::constant_inputs(0.01, 0.3)).omega_rad_s.back(), 0.0);
}

}  // namespace
}  // namespace mcg::model
