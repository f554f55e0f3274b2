// The effect catalog: names, parameters with units, defaults and bounds, and the physics of each.
// The dynamics of every effect live in model/plant.cpp; this file is their documentation and
// the parser of "NAME:key=value,..." specifications.
#include <algorithm>
#include <cmath>
#include <ostream>

#include "common/error.hpp"
#include "config/ini.hpp"
#include "model/model.hpp"
#include "table/table.hpp"

namespace mcg::model {

// Defaults are typical values for a small brushed DC motor, not any example's:
//   stribeck        v_s 10 rad/s (about 3 % of the rig's no-load speed), shape 1.5 between
//                   Tustin's exponential (1) and the Gaussian form (2)
//   dead_time       2 ms: two samples of a 1 kHz loop
//   supply_sag      1 ohm: a bench supply's leads and sense resistor
//   hbridge         0.2 ohm per switch, 2 % of the PWM period lost to dead time
//   brush_drop      0.5 V for the pair of metal-graphite brushes
//   clutch_compliance k 0.1 N m/rad: the two rotors' mode at 27 Hz, between the 16 ms
//                   mechanical pole and the 1 kHz sampling; zeta 0.1, a lightly damped coupling
//   clutch_engage_lag 0.05 N m: ten times the rig's friction; 20 ms build-up
//   cogging         1 mN m, 14 per revolution: the least common multiple of 7 slots and 2
//                   poles, the usual small-motor armature
//   thermal         10 K/W and 30 s: a small can motor's winding
const std::vector<EffectSpec>& effect_catalog() {
  static const std::vector<EffectSpec> catalog = {
      {"stribeck",
       "kinetic friction falls from the static level to the Coulomb level over a velocity scale",
       "every friction element: F(w) = sign(w) [Tc + (Ts - Tc) exp(-(|w|/v_s)^shape_exp) + P(|w|)]; "
       "breakaway level Ts unchanged",
       {{"v_s_rad_s", 10.0, 0.1, 200.0, "rad/s", "Stribeck velocity"},
        {"shape_exp", 1.5, 0.5, 3.0, "1", "exponent of the Stribeck curve"}}},
      {"dead_time",
       "transport delay of the applied voltage (clutch and relay commands are not delayed)",
       "v_m(t) = v(t - tau_d), added to the nominal drive.dead_time_s",
       {{"tau_d_s", 0.002, 0.0, 0.05, "s", "delay"}}},
      {"supply_sag",
       "the bridge is fed through a source resistance, its output drops with current and duty",
       "v_m = v - |d| R_s i, d = v / supply_V (average over the PWM period, no bulk capacitor)",
       {{"R_s_ohm", 1.0, 0.0, 20.0, "ohm", "source resistance"}}},
      {"hbridge",
       "H-bridge switch on-resistance and a duty deadband (switching blanking time)",
       "d' = sign(d) max(0, |d| - deadband); v_m = d' supply_V - 2 R_on i (two conducting switches)",
       {{"R_on_ohm", 0.2, 0.0, 5.0, "ohm", "on-resistance of one switch"},
        {"deadband", 0.02, 0.0, 0.3, "1", "duty lost per PWM period"}}},
      {"brush_drop",
       "constant brush contact voltage drop against the current, motor and generator",
       "L di/dt = ... - V_b tanh(i / 0.01 A) in both armature circuits",
       {{"V_b_V", 0.5, 0.0, 3.0, "V", "contact drop"}}},
      {"clutch_compliance",
       "a torsional spring and damper between motor and generator when engaged",
       "T_s = k phi + c (w_m - w_g), c = 2 zeta sqrt(k Jm Jg/(Jm + Jg)); phi = 0 at engagement; engaged "
       "clutch friction on the motor side, generator friction and load on the far side",
       {{"k_Nm_per_rad", 0.1, 1e-3, 10.0, "N m/rad", "spring stiffness"},
        {"zeta", 0.1, 0.0, 2.0, "1", "damping ratio of the two-rotor mode"}}},
      {"clutch_engage_lag",
       "the clutch torque capacity builds up after an engage command; the plates slip until they lock",
       "T_cap(t) = T_max (1 - exp(-(t - t_e)/tau)); slipping: T = T_cap sign(w_m - w_g); lock when the "
       "slip speed reaches 0 and the torque needed to stay locked is <= T_cap (and slip when it exceeds it)",
       {{"T_max_Nm", 0.05, 1e-3, 1.0, "N m", "full torque capacity"},
        {"tau_s", 0.02, 1e-4, 0.5, "s", "build-up time constant"}}},
      {"cogging",
       "position-dependent torque ripple on the motor shaft",
       "T_cog = T_c sin(N theta + phase), theta = motor angle since the start; shifts breakaway too",
       {{"T_c_Nm", 1e-3, 0.0, 0.02, "N m", "amplitude"},
        {"N_per_rev", 14.0, 1.0, 200.0, "1/rev", "cycles per revolution"},
        {"phase_rad", 0.0, -3.141592653589793, 3.141592653589793, "rad", "phase at theta = 0"}}},
      {"thermal",
       "winding resistance rises as the winding heats (motor and generator, each its own winding)",
       "R = R0 (1 + alpha dT); (tau_th/R_th) d(dT)/dt = i^2 R - dT/R_th, dT(0) = dT0_K",
       {{"R_th_K_W", 10.0, 0.1, 200.0, "K/W", "thermal resistance winding to ambient"},
        {"tau_th_s", 30.0, 0.1, 3600.0, "s", "thermal time constant"},
        {"alpha_per_K", 0.00393, 0.0, 0.01, "1/K", "temperature coefficient (copper 0.00393)"},
        {"dT0_K", 0.0, 0.0, 150.0, "K", "initial temperature rise"}}},
      {"param_mismatch",
       "no new structure: the nominal parameters are off by factors",
       "Kt, Ke (motor and generator) *= Kt_scale; both J *= J_scale; every Tc *= coulomb_scale; every Ts "
       "*= static_scale; every viscous polynomial *= viscous_scale; both R *= R_scale; both L *= L_scale",
       {{"Kt_scale", 1.0, 0.5, 2.0, "1", "torque and EMF constants"},
        {"J_scale", 1.0, 0.5, 2.0, "1", "rotor inertias"},
        {"coulomb_scale", 1.0, 0.2, 5.0, "1", "Coulomb levels"},
        {"static_scale", 1.0, 0.2, 5.0, "1", "static levels"},
        {"viscous_scale", 1.0, 0.0, 5.0, "1", "viscous polynomials"},
        {"R_scale", 1.0, 0.5, 2.0, "1", "armature resistances"},
        {"L_scale", 1.0, 0.2, 5.0, "1", "armature inductances"}}},
  };
  return catalog;
}

void write_effect_catalog(std::ostream& out) {
  out << "effect\tparameter\tunit\tdefault\tmin\tmax\tmeaning\n";
  for (const EffectSpec& e : effect_catalog()) {
    out << "# " << e.name << ": " << e.summary << "\n#   " << e.equation << "\n";
    for (const EffectParamSpec& p : e.params) {
      out << e.name << '\t' << p.name << '\t' << (p.unit.empty() ? "1" : p.unit) << '\t'
          << config::format_number(p.default_value) << '\t' << config::format_number(p.lower) << '\t'
          << config::format_number(p.upper) << '\t' << p.doc << '\n';
    }
  }
}

const EffectSpec* find_effect(std::string_view name) {
  for (const auto& spec : effect_catalog()) {
    if (spec.name == name) return &spec;
  }
  return nullptr;
}

namespace {

std::string known_names() {
  std::string out;
  for (const auto& spec : effect_catalog()) {
    if (!out.empty()) out += ", ";
    out += spec.name;
  }
  return out;
}

std::string known_keys(const EffectSpec& spec) {
  std::string out;
  for (const auto& p : spec.params) {
    if (!out.empty()) out += ", ";
    out += p.name;
  }
  return out;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

}  // namespace

double Effect::get(std::string_view key) const {
  for (const auto& [k, v] : params) {
    if (k == key) return v;
  }
  // Not set: the catalog's default (an Effect built by hand may list only some parameters).
  const EffectSpec* spec = find_effect(name);
  if (spec == nullptr) fail("unknown effect {}", quote(name));
  for (const auto& p : spec->params) {
    if (p.name == key) return p.default_value;
  }
  fail("effect {} has no parameter {}", quote(name), quote(key));
}

void Effect::set(std::string_view key, double value) {
  for (auto& [k, v] : params) {
    if (k == key) {
      v = value;
      return;
    }
  }
  const EffectSpec* spec = find_effect(name);
  if (spec == nullptr) fail("unknown effect {}", quote(name));
  if (std::none_of(spec->params.begin(), spec->params.end(), [&](const auto& p) { return p.name == key; })) {
    fail("effect {} has no parameter {}", quote(name), quote(key));
  }
  params.emplace_back(std::string(key), value);
}

Effect default_effect(std::string_view name) {
  const EffectSpec* spec = find_effect(name);
  if (spec == nullptr) fail("unknown effect {} (known: {})", quote(name), known_names());
  Effect e;
  e.name = spec->name;
  for (const auto& p : spec->params) e.params.emplace_back(p.name, p.default_value);
  return e;
}

Effect parse_effect(std::string_view text, std::string_view where) {
  const auto colon = text.find(':');
  const std::string_view name = trim(text.substr(0, colon));
  const EffectSpec* spec = find_effect(name);
  if (spec == nullptr) fail("{}: unknown effect {} (known: {})", where, quote(name), known_names());
  Effect effect = default_effect(name);
  if (colon == std::string_view::npos) return effect;
  std::string_view rest = text.substr(colon + 1);
  if (trim(rest).empty()) fail("{}: no parameters after ':' in {}", where, quote(text));
  std::vector<std::string_view> seen;
  while (true) {
    const auto comma = rest.find(',');
    const std::string_view item = trim(rest.substr(0, comma));
    const auto eq = item.find('=');
    if (eq == std::string_view::npos) fail("{}: expected key=value, got {}", where, quote(item));
    const std::string_view key = trim(item.substr(0, eq));
    const std::string_view value_text = trim(item.substr(eq + 1));
    const EffectParamSpec* ps = nullptr;
    for (const auto& p : spec->params) {
      if (p.name == key) ps = &p;
    }
    if (ps == nullptr) {
      fail("{}: effect {} has no parameter {} (has: {})", where, quote(spec->name), quote(key), known_keys(*spec));
    }
    for (auto s : seen) {
      if (s == key) fail("{}: parameter {} given twice", where, quote(key));
    }
    seen.push_back(key);
    double value = 0.0;
    if (value_text.empty() || !table::parse_number(value_text, value) || !std::isfinite(value)) {
      fail("{}: {}.{}: invalid number {}", where, spec->name, key, quote(value_text));
    }
    if (value < ps->lower || value > ps->upper) {
      fail("{}: {}.{} = {} is out of range [{}, {}] {}", where, spec->name, key, value_text,
           config::format_number(ps->lower), config::format_number(ps->upper), ps->unit);
    }
    effect.set(key, value);
    if (comma == std::string_view::npos) break;
    rest = rest.substr(comma + 1);
  }
  return effect;
}

std::string format_effect(const Effect& effect) {
  std::string out = effect.name;
  char sep = ':';
  for (const auto& [k, v] : effect.params) {
    out += sep;
    out += k;
    out += '=';
    out += config::format_number(v);
    sep = ',';
  }
  return out;
}

}  // namespace mcg::model
