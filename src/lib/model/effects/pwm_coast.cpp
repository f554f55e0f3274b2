// pwm_coast: a driver that lets the motor coast in the PWM off-time (fast decay: all switches
// open, or discontinuous conduction): once the current has died out, the open terminals carry
// the back-emf and no current, so the back-emf opposes the drive only while the current flows.
// With L/R far below the PWM period (a small motor behind a DRV8833 or L298 in coast mode) the
// current dies at once (coast = 1) and the mean current is |d| (sign(d) supply_V - Ke w) / R:
// at low duty the speed rises much faster than linearly with it. Default 1 for that case; the
// diagnosis starts from half and from full discontinuous conduction. The current is the mean
// over a period (what a shunt or a driver's current sense reads); against the motion (w
// opposing d) the on-time current only grows, so the form holds while |Ke w| < supply_V (beyond,
// the body diodes would feed the supply in the off-time). Behind an ideal current loop it does
// nothing: it acts in the motor's circuit only.
#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

void compile(const Effect& e, Compiled& c) { c.circuit.coast = e.get("coast"); }

}  // namespace

EffectSpec pwm_coast() {
  return {"pwm_coast",
          "driver coasting in the PWM off-time: back-emf acts only while the current flows",
          "L di/dt = d' supply_V - R i - Ke w (1 - coast (1 - |d'|)); coast = 0 a braking "
          "(slow-decay) drive, 1 zero current over the whole off-time (for |Ke w| < supply_V)",
          {{"coast", 1.0, 0.0, 1.0, "1", "share of the PWM off-time with zero motor current"}},
          compile,
          EffectPlan::fit({"coast"}, {{0.5, 1.0}}).acting_in(EffectPlan::Acts::motor_circuit)};
}

}  // namespace mcg::model::effects
