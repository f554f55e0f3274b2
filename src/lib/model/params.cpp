// The rig's parameters: the report's values, the INI form, and named access for fitting.
#include "model/model.hpp"

#include <algorithm>
#include <cmath>

#include "boardunits/chain.hpp"
#include "common/error.hpp"
#include "config/ini.hpp"

namespace mcg::model {

namespace {

/// The report's motor (Pittman), used for the generator too ("the DC generator friction was
/// set equal to the motor's frictions, since these are equivalent systems").
Machine report_machine() {
  Machine m;
  m.R_ohm = 3.91;
  // The second-order plant fit has an electrical pole at 950 rad/s = R/L, so L = 3.91/950 =
  // 4.12 mH; 4.1 mH (R/L = 953.7 rad/s) is the value the independent reference simulator uses.
  m.L_H = 4.1e-3;
  m.Kt_Nm_A = 58.2e-3;
  m.Ke_V_s_rad = 58.2e-3;
  // The report labels 1/(7.06e-6 s) "motor, clutch and generator" and 1/(14.12e-6 s) "motor
  // and clutch": swapped. One rotor is 7.06e-6 kg m^2 (datasheet); coupled, two rotors make
  // 14.12e-6, and only that gives the coupled mechanical time constant near the measured one:
  // J R/(Kt Ke) = 14.12e-6 * 3.91 / 0.0582^2 = 16.3 ms (7.06e-6 would give 8.1 ms).
  m.J_kg_m2 = 7.06e-6;
  // Appendix V (Motor_Friction m-file), the TUNED values, not table 11-1's 5.17982e-3 /
  // 2.77e-3: "Ts = 0.0055872; % adjusted Ts", "Tc = 0.002541594; % adjusted (tuned) Tc",
  // viscous Tb = 58.2e-3 (1.8472e-10 w^3 - 3.048e-7 w^2 + 2.07e-4 w).
  m.friction.Ts_Nm = 5.5872e-3;
  m.friction.Tc_Nm = 2.541594e-3;
  m.friction.viscous = {58.2e-3 * 2.07e-4, 58.2e-3 * -3.048e-7, 58.2e-3 * 1.8472e-10};
  return m;
}

using Ref = double& (*)(Params&);

/// One nominal parameter: INI section and key ("section.key" is its fitting name).
struct NominalParam {
  const char* section;
  const char* key;
  const char* unit;
  /// The fitting range, relative to the model's own values so that any motor can be fitted:
  ///   relative      v / k_bound_factor .. v * k_bound_factor (machine constants, supply)
  ///   torque        0 .. T_stall = Kt supply_V / R of the machine (the motor's for a clutch):
  ///                 a friction above the stall torque would hold the shaft at every voltage
  ///   viscous_k     |c_k| <= T_stall / w_free^k, w_free = supply_V / Ke (the no-load speed):
  ///                 no viscous term alone exceeds the stall torque inside the speed range
  ///   absolute      [lower, upper] as given (a dead time is not relative to anything)
  enum class Bound { relative, torque, viscous1, viscous2, viscous3, absolute } bound;
  double lower;  ///< absolute bounds only
  double upper;
  enum class Check { positive, non_negative, finite } check;
  Ref ref;
};

/// Factor either way a machine constant may move from the given model's value in a fit.
constexpr double k_bound_factor = 10.0;
/// An effect's torque level may reach this multiple of the motor's stall torque in a fit
/// (its viscous coefficient this multiple of stall torque per no-load speed), whatever its
/// catalog range: a level above the stall torque holds the shaft at full supply, and the
/// factor leaves room for a supply the model understates.
constexpr double k_effect_stall_factor = 2.0;

#define MCG_MACHINE_PARAMS(SEC, M)                                                                            \
  NominalParam{SEC, "R_ohm", "ohm", NominalParam::Bound::relative, 0, 0, NominalParam::Check::positive,                                \
               [](Params& p) -> double& { return p.M.R_ohm; }},                                                \
      NominalParam{SEC, "L_H", "H", NominalParam::Bound::relative, 0, 0, NominalParam::Check::positive,                               \
                   [](Params& p) -> double& { return p.M.L_H; }},                                              \
      NominalParam{SEC, "Kt_Nm_A", "N m/A", NominalParam::Bound::relative, 0, 0, NominalParam::Check::positive,                       \
                   [](Params& p) -> double& { return p.M.Kt_Nm_A; }},                                          \
      NominalParam{SEC, "Ke_V_s_rad", "V s/rad", NominalParam::Bound::relative, 0, 0, NominalParam::Check::positive,                  \
                   [](Params& p) -> double& { return p.M.Ke_V_s_rad; }},                                       \
      NominalParam{SEC, "J_kg_m2", "kg m^2", NominalParam::Bound::relative, 0, 0, NominalParam::Check::positive,                      \
                   [](Params& p) -> double& { return p.M.J_kg_m2; }},                                          \
      MCG_FRICTION_PARAMS(SEC, M.friction)

#define MCG_FRICTION_PARAMS(SEC, F)                                                                           \
  NominalParam{SEC, "Ts_Nm", "N m", NominalParam::Bound::torque, 0, 0, NominalParam::Check::non_negative,                            \
               [](Params& p) -> double& { return p.F.Ts_Nm; }},                                                \
      NominalParam{SEC, "Tc_Nm", "N m", NominalParam::Bound::torque, 0, 0, NominalParam::Check::non_negative,                        \
                   [](Params& p) -> double& { return p.F.Tc_Nm; }},                                            \
      NominalParam{SEC, "visc1_Nm_s_rad", "N m s/rad", NominalParam::Bound::viscous1, 0, 0, NominalParam::Check::finite,             \
                   [](Params& p) -> double& { return p.F.viscous[0]; }},                                       \
      NominalParam{SEC, "visc2_Nm_s2_rad2", "N m s^2/rad^2", NominalParam::Bound::viscous2, 0, 0, NominalParam::Check::finite,       \
                   [](Params& p) -> double& { return p.F.viscous[1]; }},                                       \
      NominalParam{SEC, "visc3_Nm_s3_rad3", "N m s^3/rad^3", NominalParam::Bound::viscous3, 0, 0, NominalParam::Check::finite,       \
                   [](Params& p) -> double& { return p.F.viscous[2]; }}

const std::vector<NominalParam>& nominal_params() {
  static const std::vector<NominalParam> table = {
      MCG_MACHINE_PARAMS("motor", motor),
      MCG_MACHINE_PARAMS("generator", generator),
      MCG_FRICTION_PARAMS("clutch_disengaged", clutch_disengaged),
      MCG_FRICTION_PARAMS("clutch_engaged", clutch_engaged),
      NominalParam{"drive", "supply_V", "V", NominalParam::Bound::relative, 0, 0, NominalParam::Check::positive,
                   [](Params& p) -> double& { return p.supply_V; }},
      NominalParam{"drive", "dead_time_s", "s", NominalParam::Bound::absolute, 0.0, 0.05, NominalParam::Check::non_negative,
                   [](Params& p) -> double& { return p.dead_time_s; }},
  };
  return table;
}

#undef MCG_MACHINE_PARAMS
#undef MCG_FRICTION_PARAMS

bool is_model_section(std::string_view s) {
  return s == "motor" || s == "generator" || s == "clutch_disengaged" || s == "clutch_engaged" ||
         s == "drive";
}

const char* check_text(NominalParam::Check check) {
  switch (check) {
    case NominalParam::Check::positive:
      return "must be a finite number > 0";
    case NominalParam::Check::non_negative:
      return "must be a finite number >= 0";
    case NominalParam::Check::finite:
      return "must be finite";
  }
  return "";
}

bool passes(NominalParam::Check check, double v) {
  if (!std::isfinite(v)) return false;
  switch (check) {
    case NominalParam::Check::positive:
      return v > 0.0;
    case NominalParam::Check::non_negative:
      return v >= 0.0;
    case NominalParam::Check::finite:
      return true;
  }
  return false;
}

const NominalParam* find_nominal(std::string_view name) {
  for (const auto& np : nominal_params()) {
    const std::string_view sec = np.section;
    if (name.size() == sec.size() + 1 + std::string_view(np.key).size() && name.starts_with(sec) &&
        name[sec.size()] == '.' && name.substr(sec.size() + 1) == np.key) {
      return &np;
    }
  }
  return nullptr;
}

constexpr std::string_view k_effect_prefix = "effect.";

std::optional<std::string> effect_value_problem(const EffectParamSpec& spec, double v) {
  if (v >= spec.lower && v <= spec.upper) return std::nullopt;
  return fmt::format("out of range [{}, {}]", config::format_number(spec.lower), config::format_number(spec.upper));
}

}  // namespace

std::optional<std::string> parameter_problem(const Model& model, std::string_view name, double value) {
  if (const NominalParam* np = find_nominal(name)) {
    if (passes(np->check, value)) return std::nullopt;
    return std::string(check_text(np->check));
  }
  const auto dot = name.find('.');
  if (dot != std::string_view::npos && model.effect(name.substr(0, dot)) != nullptr) {
    if (const EffectSpec* spec = find_effect(std::string(name.substr(0, dot)))) {
      for (const auto& p : spec->params) {
        if (p.name == name.substr(dot + 1)) return effect_value_problem(p, value);
      }
    }
  }
  return std::nullopt;
}

DriveScale voltage_drive_scale(const Params& p) {
  return {p.motor.Kt_Nm_A * p.supply_V / p.motor.R_ohm, p.supply_V / p.motor.Ke_V_s_rad};
}

std::vector<double> builtin_grid_scale(std::string_view kind, const Params& nominal,
                                       const DriveScale& drive) {
  static const Params rig = builtin_rig();
  static const DriveScale reference = voltage_drive_scale(rig);
  std::vector<double> out;
  for (const char k : kind) {
    switch (k) {
      case 'T':
        out.push_back(drive.torque_Nm / reference.torque_Nm);
        break;
      case 'w':
        out.push_back(drive.speed_rad_s / reference.speed_rad_s);
        break;
      case 'V':
        out.push_back(nominal.supply_V / rig.supply_V);
        break;
      case 'R':
        out.push_back(nominal.motor.R_ohm / rig.motor.R_ohm);
        break;
      default:  // '1'
        out.push_back(1.0);
    }
  }
  return out;
}

Params builtin_rig() {
  Params p;
  p.motor = report_machine();
  p.generator = report_machine();
  // Tables 11-1 and 11-2 (clutch alone, the motor's share subtracted by the report); the
  // m-files carry the same numbers to 3-4 digits (58.2e-3 * 3.228e-5 = 1.8787e-6, ...).
  p.clutch_disengaged.Ts_Nm = 7.9152e-4;
  p.clutch_disengaged.Tc_Nm = 3.942e-4;
  p.clutch_disengaged.viscous = {1.8787e-6, -3.411e-9, 0.0};
  p.clutch_engaged.Ts_Nm = 6.8967e-3;
  p.clutch_engaged.Tc_Nm = 2.8518e-3;
  p.clutch_engaged.viscous = {-4.785e-6, 3.6899e-9, 0.0};
  p.supply_V = boardunits::k_supply_V;
  p.dead_time_s = 0.0;
  return p;
}

Params from_ini(const config::Ini& ini, Params base) {
  for (const auto& section : ini.sections()) {
    if (!is_model_section(section)) continue;
    for (const auto* entry : ini.entries(section)) {
      if (find_nominal(section + "." + entry->key) == nullptr) {
        ini.reject(section, entry->key, "unknown parameter");
      }
    }
  }
  for (const auto& np : nominal_params()) {
    if (auto v = ini.number(np.section, np.key)) {
      if (!passes(np.check, *v)) ini.reject(np.section, np.key, check_text(np.check));
      np.ref(base) = *v;
    }
  }
  return base;
}

void to_ini(const Params& params, config::Ini& ini) {
  Params copy = params;
  for (const auto& np : nominal_params()) {
    ini.set(np.section, np.key, np.ref(copy), np.unit);
  }
}

Model model_from_ini(const config::Ini& ini, Model base) {
  base.params = from_ini(ini, base.params);
  for (const auto& section : ini.sections()) {
    if (!std::string_view(section).starts_with(k_effect_prefix)) continue;
    const std::string name = section.substr(k_effect_prefix.size());
    const EffectSpec* spec = find_effect(name);
    if (spec == nullptr) {
      const auto entries = ini.entries(section);
      const std::string where = entries.empty() || entries.front()->origin.empty()
                                    ? std::string("config")
                                    : entries.front()->origin;
      fail("{}: [{}]: unknown effect {} ({})", where, section, quote(name), unknown_effect_hint(name));
    }
    Effect effect = default_effect(name);
    for (const auto& existing : base.effects) {
      if (existing.name == name) effect = existing;
    }
    for (const auto* entry : ini.entries(section)) {
      const auto* ps = [&]() -> const EffectParamSpec* {
        for (const auto& p : spec->params) {
          if (p.name == entry->key) return &p;
        }
        return nullptr;
      }();
      if (ps == nullptr) ini.reject(section, entry->key, "unknown parameter of effect '" + name + "'");
      const double v = *ini.number(section, entry->key);
      // A value beyond the effect's default range (another motor's size) stands when the
      // INI's [bounds] widens that range to hold it, as a fit's own output does.
      EffectParamSpec range = *ps;
      if (const auto b = ini.numbers("bounds", name + "." + entry->key); b && b->size() == 2) {
        range.lower = std::min(range.lower, (*b)[0]);
        range.upper = std::max(range.upper, (*b)[1]);
      }
      if (const auto problem = effect_value_problem(range, v)) {
        ini.reject(section, entry->key, *effect_value_problem(*ps, v));
      }
      effect.set(entry->key, v);
    }
    bool replaced = false;
    for (auto& existing : base.effects) {
      if (existing.name == name) {
        existing = effect;
        replaced = true;
      }
    }
    if (!replaced) base.effects.push_back(effect);
  }
  return base;
}

void model_to_ini(const Model& model, config::Ini& ini) {
  to_ini(model.params, ini);
  for (const auto& effect : model.effects) {
    const std::string section = std::string(k_effect_prefix) + effect.name;
    const EffectSpec* spec = find_effect(effect.name);
    for (const auto& [key, value] : effect.params) {
      std::string unit;
      if (spec != nullptr) {
        for (const auto& p : spec->params) {
          if (p.name == key) unit = p.unit;
        }
      }
      ini.set(section, key, value, unit);
      if (spec == nullptr) continue;
      const auto ps = std::find_if(spec->params.begin(), spec->params.end(),
                                   [&name = key](const auto& p) { return p.name == name; });
      if (ps != spec->params.end() && !(value >= ps->lower && value <= ps->upper)) {
        // Beyond the default range: the bounds that let it be read back.
        ini.set("bounds", effect.name + "." + key,
                config::format_number(std::min(ps->lower, value)) + " " +
                    config::format_number(std::max(ps->upper, value)));
      }
    }
  }
}

const Effect* Model::effect(std::string_view name) const {
  for (const auto& e : effects) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

std::vector<ParamInfo> parameters(const Model& model) {
  std::vector<ParamInfo> out;
  Params copy = model.params;
  for (const auto& np : nominal_params()) {
    const double v = np.ref(copy);
    const std::string_view section = np.section;
    const Machine& machine = section == "generator" ? copy.generator : copy.motor;
    const double stall_Nm = machine.Kt_Nm_A * copy.supply_V / machine.R_ohm;
    const double free_rad_s = copy.supply_V / machine.Ke_V_s_rad;
    double lower = np.lower;
    double upper = np.upper;
    switch (np.bound) {
      case NominalParam::Bound::relative:
        lower = v / k_bound_factor;
        upper = v * k_bound_factor;
        break;
      case NominalParam::Bound::torque:
        lower = 0.0;
        upper = std::max(stall_Nm, v);
        break;
      case NominalParam::Bound::viscous1:
      case NominalParam::Bound::viscous2:
      case NominalParam::Bound::viscous3: {
        const int k = static_cast<int>(np.bound) - static_cast<int>(NominalParam::Bound::viscous1) + 1;
        upper = std::max(stall_Nm / std::pow(free_rad_s, k), std::abs(v));
        lower = -upper;
        break;
      }
      case NominalParam::Bound::absolute:
        break;
    }
    out.push_back({std::string(section) + "." + np.key, v, lower, upper, np.unit});
  }
  // Effect levels in torque units are bounded by the motor's own size too, so that a larger
  // motor's friction fits: the catalog's range only widens (to k_effect_stall_factor stall
  // torques, per no-load speed for a viscous coefficient; either sign for a signed one).
  const double stall_Nm = copy.motor.Kt_Nm_A * copy.supply_V / copy.motor.R_ohm;
  const double free_rad_s = copy.supply_V / copy.motor.Ke_V_s_rad;
  for (const auto& effect : model.effects) {
    const EffectSpec* spec = find_effect(effect.name);
    for (const auto& [key, value] : effect.params) {
      ParamInfo info{effect.name + "." + key, value, value, value, ""};
      if (spec != nullptr) {
        for (const auto& p : spec->params) {
          if (p.name == key) {
            info.lower = p.lower;
            info.upper = p.upper;
            info.unit = p.unit;
            info.period = p.period;
          }
        }
      }
      const double size = info.unit == "N m"         ? k_effect_stall_factor * stall_Nm
                          : info.unit == "N m s/rad" ? k_effect_stall_factor * stall_Nm / free_rad_s
                                                     : 0.0;
      if (std::isfinite(size) && size > info.upper) {
        info.upper = size;
        if (info.lower < 0.0) info.lower = std::min(info.lower, -size);
      }
      out.push_back(std::move(info));
    }
  }
  return out;
}

namespace {

double* effect_slot(Model& model, std::string_view name) {
  const auto dot = name.find('.');
  if (dot == std::string_view::npos) return nullptr;
  const std::string_view effect_name = name.substr(0, dot);
  const std::string_view key = name.substr(dot + 1);
  for (auto& effect : model.effects) {
    if (effect.name != effect_name) continue;
    for (auto& [k, v] : effect.params) {
      if (k == key) return &v;
    }
  }
  return nullptr;
}

}  // namespace

void set_parameter(Model& model, std::string_view name, double value) {
  if (const auto* np = find_nominal(name)) {
    np->ref(model.params) = value;
    return;
  }
  if (double* slot = effect_slot(model, name)) {
    *slot = value;
    return;
  }
  fail("unknown model parameter {}", quote(name));
}

double get_parameter(const Model& model, std::string_view name) {
  if (const auto* np = find_nominal(name)) {
    Params copy = model.params;
    return np->ref(copy);
  }
  Model copy = model;
  if (double* slot = effect_slot(copy, name)) return *slot;
  fail("unknown model parameter {}", quote(name));
}

}  // namespace mcg::model
