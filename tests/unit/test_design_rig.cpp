// The rig model linearised: against the DC-motor closed form, and against the report's plant.
#include "common/error.hpp"
#include "design/rig.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace mcg::design {
namespace {

TEST(DesignRig, MotorAloneIsTheDcMotorTransferFunction) {
  // ω/v = Kt / ((L s + R)(J s + b) + Kt Ke), b = c1 + 2 c2 ω0 + 3 c3 ω0².
  const model::Params p = model::builtin_rig();
  const double w0 = 150.0;
  const linsys::Tf g = linearise_rig(p, 0, w0, INFINITY);
  const model::Machine& m = p.motor;
  const auto& v = m.friction.viscous;
  const double b = v[0] + 2.0 * v[1] * w0 + 3.0 * v[2] * w0 * w0;
  for (const linsys::Complex s : {linsys::Complex(0.0, 0.0), linsys::Complex(0.0, 300.0), linsys::Complex(-20.0, 5000.0)}) {
    const linsys::Complex want = m.Kt_Nm_A / ((m.L_H * s + m.R_ohm) * (m.J_kg_m2 * s + b) + m.Kt_Nm_A * m.Ke_V_s_rad);
    EXPECT_NEAR(std::abs(g.eval(s) / want - 1.0), 0.0, 1e-12) << s;
  }
}

TEST(DesignRig, EngagedRigIsCloseToTheReportsIdentifiedPlant) {
  // The report identifies 16.557/((s/65+1)(s/950+1)) from a chirp of its Simulink model; the
  // linearised built-in rig at 1000 rpm, clutch engaged, load open, lands within a few percent.
  const linsys::Tf g = linearise_rig(model::builtin_rig(), 2, 1000.0 * 2.0 * std::numbers::pi / 60.0, INFINITY);
  EXPECT_NEAR(g.dc_gain() / 16.557, 1.0, 0.03);
  const auto poles = linsys::roots(g.den);
  ASSERT_EQ(poles.size(), 2u);
  EXPECT_NEAR(-poles[1].real() / 65.0, 1.0, 0.1);
  EXPECT_NEAR(-poles[0].real() / 950.0, 1.0, 0.1);
  // A generator load brakes the shaft: lower DC gain, one more state.
  const linsys::Tf loaded = linearise_rig(model::builtin_rig(), 2, 1000.0 * 2.0 * std::numbers::pi / 60.0, 5.6);
  EXPECT_LT(loaded.dc_gain(), g.dc_gain());
  EXPECT_EQ(linsys::degree(loaded.den), 3);
}

TEST(DesignRig, RejectsBadOperatingPoints) {
  EXPECT_THROW(linearise_rig(model::builtin_rig(), 3, 100.0, INFINITY), mcg::Error);
  EXPECT_THROW(linearise_rig(model::builtin_rig(), 2, 0.0, INFINITY), mcg::Error);
}

}  // namespace
}  // namespace mcg::design
