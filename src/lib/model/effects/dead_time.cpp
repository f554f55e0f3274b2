// dead_time: a transport delay of the applied voltage. Default 2 ms, two samples of a 1 kHz
// loop; the diagnosis starts from half a sample to 16 samples (a slow PWM or filter chain).
#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

void compile(const Effect& e, Compiled& c) { c.delay_s += e.get("tau_d_s"); }

}  // namespace

EffectSpec dead_time() {
  return {"dead_time",
          "transport delay of the applied voltage (clutch and relay commands are not delayed)",
          "v_m(t) = v(t - tau_d), added to the nominal drive.dead_time_s",
          {{"tau_d_s", 0.002, 0.0, 0.05, "s", "delay"}},
          compile,
          EffectPlan::fit({"tau_d_s"}, {{0.0005, 0.001, 0.002, 0.004, 0.008, 0.016}})};
}

}  // namespace mcg::model::effects
