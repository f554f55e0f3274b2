// clutch_compliance: a torsional spring and damper between motor and generator when engaged.
// Default k 0.1 N m/rad: the two rotors' mode at 27 Hz, between the 16 ms mechanical pole and
// the 1 kHz sampling; zeta 0.1, a lightly damped coupling. The diagnosis starts from modes of
// 4 to 60 Hz with the rig's rotors and zeta from a bare steel spring (0.03) to an elastomer (0.3).
#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

void compile(const Effect& e, Compiled& c) {
  c.coupling.spring_k_Nm_rad = e.get("k_Nm_per_rad");
  c.coupling.zeta = e.get("zeta");
}

}  // namespace

EffectSpec clutch_compliance() {
  return {"clutch_compliance",
          "a torsional spring and damper between motor and generator when engaged",
          "T_s = k phi + c (w_m - w_g), c = 2 zeta sqrt(k Jm Jg/(Jm + Jg)); phi = 0 at engagement; engaged "
          "clutch friction on the motor side, generator friction and load on the far side",
          {{"k_Nm_per_rad", 0.1, 1e-3, 10.0, "N m/rad", "spring stiffness"},
           {"zeta", 0.1, 0.0, 2.0, "1", "damping ratio of the two-rotor mode"}},
          compile,
          EffectPlan::fit({"k_Nm_per_rad", "zeta"}, {{0.01, 0.03, 0.1, 0.3, 1.0}, {0.03, 0.1, 0.3}},
                          EffectPlan::Needs::clutch_engaged)};
}

}  // namespace mcg::model::effects
