// clutch_engage_lag: the clutch's torque capacity builds up after an engage command. Default
// 0.05 N m, ten times the rig's friction, with a 20 ms build-up; the diagnosis starts from
// capacities below the friction to ten times it, and from a relay's 5 ms to a slow solenoid's
// 100 ms.
#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

/// T_cap = T_max (1 - exp(-age/tau)), k = {T_max, tau}.
template <class S>
S capacity(const std::array<S, 4>& k, S age_s) {
  using std::exp;
  return k[0] * (1.0 - exp(-age_s / k[1]));
}

void compile(const Effect& e, Compiled& c) {
  c.coupling.capacity = capacity<double>;
  c.coupling.capacity_dual = capacity<Dual>;
  c.coupling.capacity_k = {e.get("T_max_Nm"), e.get("tau_s"), 0.0, 0.0};
}

}  // namespace

EffectSpec clutch_engage_lag() {
  return {
      "clutch_engage_lag",
      "the clutch torque capacity builds up after an engage command; the plates slip until they lock",
      "T_cap(t) = T_max (1 - exp(-(t - t_e)/tau)); slipping: T = T_cap sign(w_m - w_g); lock when the "
      "slip speed reaches 0 and the torque needed to stay locked is <= T_cap (and slip when it exceeds it)",
      {{"T_max_Nm", 0.05, 1e-3, 1.0, "N m", "full torque capacity"},
       {"tau_s", 0.02, 1e-4, 0.5, "s", "build-up time constant"}},
      compile,
      EffectPlan::fit({"T_max_Nm", "tau_s"}, {{0.01, 0.05, 0.2}, {0.005, 0.03, 0.1}},
                      EffectPlan::Needs::clutch_engagement)};
}

}  // namespace mcg::model::effects
