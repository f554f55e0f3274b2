// friction_load: friction that grows with the torque the motor's shaft transmits (gear teeth
// and bearings pressed harder under load; a gearmotor's efficiency below 1). Moving, the
// kinetic level is F(w) + mu |Kt i|; at rest the shaft holds up to Ts + mu |Kt i|, so it breaks
// away when |Kt i| (1 - mu) leaves the static level. Default 0.05, a good spur stage's loss;
// the diagnosis starts from 1 % (ball bearings) to 30 % (a worm or a multi-stage gearbox).
#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

/// mu |Kt i|, k = {mu}: the same on the kinetic and the breakaway level.
template <class S>
S kinetic(const std::array<S, 4>& k, const BasicFriction<S>& /*f*/, S /*x*/, S load_Nm) {
  return k[0] * load_Nm;
}
template <class S>
S breakaway(const std::array<S, 4>& k, S load_Nm) {
  return k[0] * load_Nm;
}

void compile(const Effect& e, Compiled& c) {
  c.friction_terms.push_back(
      {kinetic<double>, breakaway<double>, {e.get("mu"), 0.0, 0.0, 0.0}, kinetic<Dual>, breakaway<Dual>});
}

/// A torque c |i| sign(w) against the motion (c < 0) is mu |Kt i|: mu = -c / Kt.
std::vector<std::pair<std::string, double>> from_current_level(const TermValues& t, const Params& nominal) {
  if (!(t.coefficient < 0.0)) return {};
  return {{"mu", -t.coefficient / nominal.motor.Kt_Nm_A}};
}

}  // namespace

EffectSpec friction_load() {
  return {"friction_load",
          "the motor shaft's friction grows with the torque it transmits (gears, loaded bearings)",
          "moving F = sign(w) (Tc + P(|w|) + mu |Kt i|); at rest held up to Ts + mu |Kt i|",
          {{"mu", 0.05, 0.0, 0.5, "1", "friction per newton metre of motor torque"}},
          compile,
          EffectPlan::fit({"mu"}, {{0.01, 0.03, 0.1, 0.3}})
              .as_friction()
              .seeded_by_terms({{TermShape::abs_current_sign, from_current_level}})};
}

}  // namespace mcg::model::effects
