// brush_drop: a constant contact voltage drop of the brushes. Default 0.5 V for a pair of
// metal-graphite brushes; the diagnosis starts from 0.2 V to carbon brushes' 2 V (on the rig's
// supply; scaled by the given supply over it).
// Under a current-driven motor only the generator's circuit shows it, when that feeds a load.
#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

void compile(const Effect& e, Compiled& c) {
  c.circuit.V_sat_V = e.get("V_b_V");
  c.circuit.i_sat_A = k_brush_smooth_i_A;
}

/// A voltage against the current in the motor circuit is the drop itself.
std::vector<std::pair<std::string, double>> from_drop(const TermValues& t, const Params& /*nominal*/) {
  if (!(t.coefficient > 0.0)) return {};
  return {{"V_b_V", t.coefficient}};
}

std::vector<double> grid_scale(const Params& nominal, const DriveScale& drive) {
  return builtin_grid_scale("V", nominal, drive);
}

}  // namespace

EffectSpec brush_drop() {
  return {"brush_drop",
          "constant brush contact voltage drop against the current, motor and generator",
          "L di/dt = ... - V_b tanh(i / 0.01 A) in both armature circuits",
          {{"V_b_V", 0.5, 0.0, 3.0, "V", "contact drop"}},
          compile,
          EffectPlan::fit({"V_b_V"}, {{0.2, 0.5, 1.0, 2.0}})
              .scaled_by(grid_scale)
              .acting_in(EffectPlan::Acts::circuits)
              .seeded_by_terms({{TermShape::current_drop, from_drop}})};
}

}  // namespace mcg::model::effects
