// param_mismatch: no new structure, the nominal parameters off by factors. The diagnosis uses
// it as the refit of the nominal parameters every candidate starts from, not as a candidate.
#include <map>

#include "model/effects/compiled.hpp"

namespace mcg::model::effects {

namespace {

void compile(const Effect& e, Compiled& c) {
  for (Machine* m : {&c.p.motor, &c.p.generator}) {
    m->Kt_Nm_A *= e.get("Kt_scale");
    m->Ke_V_s_rad *= e.get("Kt_scale");
    m->J_kg_m2 *= e.get("J_scale");
    m->R_ohm *= e.get("R_scale");
    m->L_H *= e.get("L_scale");
  }
  for (Friction* f :
       {&c.p.motor.friction, &c.p.generator.friction, &c.p.clutch_disengaged, &c.p.clutch_engaged}) {
    f->Tc_Nm *= e.get("coulomb_scale");
    f->Ts_Nm *= e.get("static_scale");
    for (double& v : f->viscous) v *= e.get("viscous_scale");
  }
}

}  // namespace

EffectSpec param_mismatch() {
  return {"param_mismatch",
          "no new structure: the nominal parameters are off by factors",
          "Kt, Ke (motor and generator) *= Kt_scale; both J *= J_scale; every Tc *= coulomb_scale; every Ts "
          "*= static_scale; every viscous polynomial *= viscous_scale; both R *= R_scale; both L *= L_scale",
          {{"Kt_scale", 1.0, 0.5, 2.0, "1", "torque and EMF constants"},
           {"J_scale", 1.0, 0.5, 2.0, "1", "rotor inertias"},
           {"coulomb_scale", 1.0, 0.2, 5.0, "1", "Coulomb levels"},
           {"static_scale", 1.0, 0.2, 5.0, "1", "static levels"},
           {"viscous_scale", 1.0, 0.0, 5.0, "1", "viscous polynomials"},
           {"R_scale", 1.0, 0.5, 2.0, "1", "armature resistances"},
           {"L_scale", 1.0, 0.2, 5.0, "1", "armature inductances"}},
          compile,
          EffectPlan::not_a_candidate()};
}

}  // namespace mcg::model::effects

namespace mcg::model {

std::string mismatch_scale_of(std::string_view name) {
  // Read off compile: the scale whose change moves the parameter, on a probe model whose every
  // nominal parameter is 1 (a level the built-in rig leaves at 0 must still show its scale).
  static const std::map<std::string, std::string, std::less<>> moved_by = [] {
    std::map<std::string, std::string, std::less<>> out;
    Model probe;
    const std::vector<ParamInfo> nominal = parameters(probe);
    for (const ParamInfo& info : nominal) set_parameter(probe, info.name, 1.0);
    for (const EffectParamSpec& scale : effects::param_mismatch().params) {
      Model scaled = probe;
      scaled.effects = {default_effect("param_mismatch")};
      scaled.effects.front().set(scale.name, 2.0);
      Model moved = probe;
      moved.params = Compiled(scaled).p;
      for (const ParamInfo& info : nominal) {
        if (get_parameter(moved, info.name) != get_parameter(probe, info.name)) out[info.name] = scale.name;
      }
    }
    return out;
  }();
  const auto it = moved_by.find(name);
  return it == moved_by.end() ? std::string() : it->second;
}

}  // namespace mcg::model
