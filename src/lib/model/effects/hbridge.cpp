// hbridge: switch on-resistance and a duty deadband. Default 0.2 ohm per switch and 2 % of
// the PWM period lost to dead time; the diagnosis starts from MOSFET to bipolar on-resistance
// (against the rig's armature; scaled by the given motor's R over it) and deadbands of 0.5-6 %
// of the period.
// It acts in the bridge: a current-driven drive's loop overrides it, the diagnosis does not try it there.
#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

void compile(const Effect& e, Compiled& c) {
  c.circuit.R_series_ohm = 2.0 * e.get("R_on_ohm");
  c.circuit.deadband = e.get("deadband");
}

/// A voltage V_d lost from the drive's output in its direction: the deadband is the duty it
/// loses, V_d / supply.
std::vector<std::pair<std::string, double>> from_dead_band(const TermValues& t, const Params& nominal) {
  if (!(t.coefficient > 0.0)) return {};
  return {{"deadband", t.coefficient / nominal.supply_V}};
}

std::vector<double> grid_scale(const Params& nominal, const DriveScale& drive) {
  return builtin_grid_scale("R1", nominal, drive);
}

}  // namespace

EffectSpec hbridge() {
  return {"hbridge",
          "H-bridge switch on-resistance and a duty deadband (switching blanking time)",
          "d' = sign(d) max(0, |d| - deadband); v_m = d' supply_V - 2 R_on i (two conducting switches)",
          {{"R_on_ohm", 0.2, 0.0, 5.0, "ohm", "on-resistance of one switch"},
           {"deadband", 0.02, 0.0, 0.3, "1", "duty lost per PWM period"}},
          compile,
          EffectPlan::fit({"R_on_ohm", "deadband"}, {{0.1, 0.5}, {0.005, 0.02, 0.06}})
              .scaled_by(grid_scale)
              .acting_in(EffectPlan::Acts::motor_circuit)
              .in_series({"R_on_ohm"})
              .seeded_by_terms({{TermShape::drive_dead_band, from_dead_band}})};
}

}  // namespace mcg::model::effects
