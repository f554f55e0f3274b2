// thermal: winding resistance rises as the winding heats. Default 10 K/W and 30 s, a small
// can motor's winding; the diagnosis starts R_th from 5 to 60 K/W and tau_th from 5 to 60 s.
// Under a current-driven motor only the generator's circuit shows it, when that feeds a load.
#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

/// d(dT)/dt = (P - dT/R_th) / C_th, k = {R_th, C_th = tau_th / R_th}.
template <class S>
S heating(const std::array<S, 4>& k, S P_W, S dT_K) {
  return (P_W - dT_K / k[0]) / k[1];
}

void compile(const Effect& e, Compiled& c) {
  const double R_th = e.get("R_th_K_W");
  c.winding.rate = heating<double>;
  c.winding.rate_dual = heating<Dual>;
  c.winding.k = {R_th, e.get("tau_th_s") / R_th, 0.0, 0.0};
  c.winding.R_per_x = e.get("alpha_per_K");
  c.winding.x0 = e.get("dT0_K");
}

}  // namespace

EffectSpec thermal() {
  return {"thermal",
          "winding resistance rises as the winding heats (motor and generator, each its own winding)",
          "R = R0 (1 + alpha dT); (tau_th/R_th) d(dT)/dt = i^2 R - dT/R_th, dT(0) = dT0_K",
          {{"R_th_K_W", 10.0, 0.1, 200.0, "K/W", "thermal resistance winding to ambient"},
           {"tau_th_s", 30.0, 0.1, 3600.0, "s", "thermal time constant"},
           {"alpha_per_K", 0.00393, 0.0, 0.01, "1/K", "temperature coefficient (copper 0.00393)"},
           {"dT0_K", 0.0, 0.0, 150.0, "K", "initial temperature rise"}},
          compile,
          EffectPlan::fit({"R_th_K_W", "tau_th_s"}, {{5.0, 20.0, 60.0}, {5.0, 60.0}})
              .acting_in(EffectPlan::Acts::circuits)};
}

}  // namespace mcg::model::effects
