// supply_sag: the bridge fed through a source resistance. Default 1 ohm, a bench supply's
// leads and sense resistor; the diagnosis starts from 0.3 ohm (leads) to a small battery's 3
// against the rig's armature, scaled by the given motor's R over it (what sags is their ratio).
// It acts in the bridge: a current-driven drive's loop overrides it, the diagnosis does not try it there.
#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

void compile(const Effect& e, Compiled& c) { c.circuit.R_duty_ohm = e.get("R_s_ohm"); }

std::vector<double> grid_scale(const Params& nominal, const DriveScale& drive) {
  return builtin_grid_scale("R", nominal, drive);
}

}  // namespace

EffectSpec supply_sag() {
  return {"supply_sag",
          "the bridge is fed through a source resistance, its output drops with current and duty",
          "v_m = v - |d| R_s i, d = v / supply_V (average over the PWM period, no bulk capacitor)",
          {{"R_s_ohm", 1.0, 0.0, 20.0, "ohm", "source resistance"}},
          compile,
          EffectPlan::fit({"R_s_ohm"}, {{0.3, 1.0, 3.0}})
              .scaled_by(grid_scale)
              .acting_in(EffectPlan::Acts::motor_circuit)};
}

}  // namespace mcg::model::effects
