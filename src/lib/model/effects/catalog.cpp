// The effect catalog: the registry of the effect modules (one file each in this directory,
// with its parameters, equations, compile hook and diagnosis plan), the plant's compilation
// of a model's effects, and the parser of "NAME:key=value,..." specifications.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <ostream>

#include "common/edit_distance.hpp"
#include "common/error.hpp"
#include "common/text.hpp"
#include "config/ini.hpp"
#include "model/effects/compiled.hpp"
#include "model/model.hpp"
#include "table/table.hpp"

namespace mcg::model {

// The registry: one line per effect module (model/effects/<name>.cpp defines EffectSpec
// <name>()), in the order the catalog lists and compiles them.
#define MCG_EFFECT_MODULES(X) \
  X(stribeck)                 \
  X(dead_time)                \
  X(supply_sag)               \
  X(hbridge)                  \
  X(pwm_coast)                \
  X(brush_drop)               \
  X(clutch_compliance)        \
  X(clutch_engage_lag)        \
  X(cogging)                  \
  X(thermal)                  \
  X(friction_levels)          \
  X(friction_asymmetry)       \
  X(friction_load)            \
  X(param_mismatch)

namespace effects {
#define MCG_DECLARE_EFFECT(name) EffectSpec name();
MCG_EFFECT_MODULES(MCG_DECLARE_EFFECT)
#undef MCG_DECLARE_EFFECT
}  // namespace effects

const std::vector<EffectSpec>& effect_catalog() {
#define MCG_LIST_EFFECT(name) effects::name(),
  static const std::vector<EffectSpec> catalog = {MCG_EFFECT_MODULES(MCG_LIST_EFFECT)};
#undef MCG_LIST_EFFECT
  return catalog;
}

Compiled::Compiled(const Model& model) {
  p = model.params;
  delay_s = model.params.dead_time_s;
  for (const EffectSpec& spec : effect_catalog()) {
    if (const Effect* e = model.effect(spec.name)) spec.compile(*e, *this);
  }
  for (const ShaftTerm& term : model.shaft_terms) motor_torque.push_back({term.basis, term.k, term.basis_it});
  motor_side[0] = p.motor.friction;
  motor_side[1] = p.motor.friction + p.clutch_disengaged;
  motor_side[2] = p.motor.friction + p.clutch_engaged;
  gen = p.generator.friction;
  rigid = motor_side[2] + gen;
  J_total = p.motor.J_kg_m2 + p.generator.J_kg_m2;
  c_spring = 2.0 * coupling.zeta *
             std::sqrt(coupling.spring_k_Nm_rad * p.motor.J_kg_m2 * p.generator.J_kg_m2 / J_total);
  friction_needs_load = std::any_of(friction_terms.begin(), friction_terms.end(),
                                    [](const FrictionTerm& t) { return t.breakaway != nullptr; });
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

namespace {

/// Text safe inside a roff paragraph: backslashes and minus signs escaped.
std::string roff(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (c == '\\') {
      out += "\\e";
    } else if (c == '-') {
      out += "\\-";
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace

void write_effect_catalog_roff(std::ostream& out) {
  for (const EffectSpec& e : effect_catalog()) {
    out << ".TP\n.B " << roff(e.name) << "\n";
    std::string params;
    for (const EffectParamSpec& p : e.params) {
      if (!params.empty()) params += "; ";
      params += fmt::format("{} ({}, {}..{}{}{}): {}", p.name, config::format_number(p.default_value),
                            config::format_number(p.lower), config::format_number(p.upper),
                            p.unit == "1" ? "" : " ", p.unit == "1" ? "" : p.unit, p.doc);
      if (p.period > 0.0) params += ", periodic (a fit wraps it into its range)";
    }
    // Each sentence on its own line: roff starts no line with a control character here.
    std::string summary = e.summary;
    if (!summary.empty() && summary[0] >= 'a' && summary[0] <= 'z')
      summary[0] = static_cast<char>(summary[0] - 'a' + 'A');
    out << "\\&" << roff(params) << ".\n\\&" << roff(summary) << ":\n\\&" << roff(e.equation) << ".\n";
  }
}

const EffectSpec* find_effect(std::string_view name) {
  for (const auto& spec : effect_catalog()) {
    if (spec.name == name) return &spec;
  }
  return nullptr;
}

std::string unknown_effect_hint(std::string_view name, bool candidates_only) {
  // The nearest names: every name `name` begins (a prefix names a family), else the closest.
  std::vector<std::string> nearest;
  std::size_t best_distance = std::numeric_limits<std::size_t>::max();
  for (const auto& spec : effect_catalog()) {
    if (candidates_only && !spec.plan.candidate) continue;
    const std::size_t d = spec.name.starts_with(name) && !name.empty() ? 1 : edit_distance(name, spec.name);
    if (d < best_distance) {
      best_distance = d;
      nearest.clear();
    }
    if (d == best_distance) nearest.push_back(quote(spec.name));
  }
  const std::string all = "mcg-sim --list-effects lists them all";
  if (nearest.empty() || best_distance > std::max<std::size_t>(2, name.size() / 4)) return all;
  std::string names = nearest.front();
  for (std::size_t k = 1; k < nearest.size(); ++k)
    names += (k + 1 == nearest.size() ? " or " : ", ") + nearest[k];
  return fmt::format("did you mean {}? {}", names, all);
}

namespace {

std::string known_keys(const EffectSpec& spec) {
  std::string out;
  for (const auto& p : spec.params) {
    if (!out.empty()) out += ", ";
    out += p.name;
  }
  return out;
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
  if (spec == nullptr) fail("unknown effect {} ({})", quote(name), unknown_effect_hint(name));
  Effect e;
  e.name = spec->name;
  for (const auto& p : spec->params) e.params.emplace_back(p.name, p.default_value);
  return e;
}

Effect parse_effect(std::string_view text, std::string_view where) {
  const auto colon = text.find(':');
  const std::string_view name = trim(text.substr(0, colon));
  const EffectSpec* spec = find_effect(name);
  if (spec == nullptr) fail("{}: unknown effect {} ({})", where, quote(name), unknown_effect_hint(name));
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
      fail("{}: effect {} has no parameter {} (has: {})", where, quote(spec->name), quote(key),
           known_keys(*spec));
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
