// The [controller] section: parse, write, and the board's registers for it.
#include "boardunits/controller.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "common/checked.hpp"
#include "common/error.hpp"
#include "config/ini.hpp"
#include "mcg_protocol.h"  // MCG_COEF_FRAC_BITS_MAX, MCG_MODE_*

namespace mcg::boardunits {

namespace {

constexpr const char* k_section = "controller";
constexpr const char* k_fixed = "fixed_point";

std::string list_text(const std::vector<double>& v) {
  std::string s;
  for (double x : v) {
    if (!s.empty()) s += ' ';
    s += config::format_number(x);
  }
  return s;
}

/// The [fixed_point] registers of `ini`, checked: F in 0..12, mode p/pi/pid, 16-bit integers.
BoardFixedPoint fixed_point_from_ini(const config::Ini& ini, const Controller& c) {
  const double frac = *ini.number(k_fixed, "coef_frac");
  if (frac < 0 || frac > MCG_COEF_FRAC_BITS_MAX || frac != std::floor(frac)) {
    ini.reject(k_fixed, "coef_frac", fmt::format("not 0..{}", MCG_COEF_FRAC_BITS_MAX));
  }
  BoardFixedPoint q;
  q.mode = ini.get(k_fixed, "mode").value_or("");
  const std::optional<std::int16_t> mode = board_mode(q.mode);
  if (!mode || *mode == MCG_MODE_OPEN) ini.reject(k_fixed, "mode", "not p, pi or pid");
  q.coef_frac = *to_integer(frac, 0, static_cast<int>(MCG_COEF_FRAC_BITS_MAX));
  q.factor = c.units().factor();
  const auto reg = [&](const char* key) {
    const double v = ini.number_or(k_fixed, key, 0.0);
    if (v != std::floor(v) || v < -32768.0 || v > 32767.0) ini.reject(k_fixed, key, "not a 16-bit integer");
    q.regs.push_back(*to_integer(v, std::int32_t{-32768}, std::int32_t{32767}));
    q.wanted.push_back(std::ldexp(v, -q.coef_frac));
    q.b.push_back(std::ldexp(v, -q.coef_frac) / q.factor);
  };
  if (*mode == MCG_MODE_P) {
    reg("kp");
    q.a = {1.0};
  } else {
    for (const char* key : {"b0", "b1", "b2"}) reg(key);
    if (*mode == MCG_MODE_PI) q.b.pop_back();
    q.a = {1.0, -1.0};
  }
  return q;
}

}  // namespace

Controller report_pi() { return Controller{}; }

std::optional<Controller> controller_from_ini(const config::Ini& ini) {
  if (!ini.has_section(k_section)) return std::nullopt;
  Controller c;
  static const char* const known[] = {"type",        "b",      "a",
                                      "dt_s",        "input_scale", "output",
                                      "duty_full_scale", "round_output", "duty_resolution"};
  for (const auto* e : ini.entries(k_section)) {
    if (std::find_if(std::begin(known), std::end(known), [&](const char* k) { return e->key == k; }) ==
        std::end(known)) {
      ini.reject(k_section, e->key, "unknown key");
    }
  }
  if (auto v = ini.get(k_section, "type")) c.type = *v;
  const std::string output = ini.get(k_section, "output").value_or("duty_counts");
  if (output == "duty") {
    c.duty_full_scale = 1.0;
    c.round_output = false;
  } else if (output != "duty_counts") {
    ini.reject(k_section, "output", "must be 'duty_counts' or 'duty', got '" + output + "'");
  }
  if (auto b = ini.numbers(k_section, "b")) c.b = *b;
  if (auto a = ini.numbers(k_section, "a")) c.a = *a;
  if (c.b.empty()) ini.reject(k_section, "b", "needs at least one coefficient");
  if (c.a.empty() || c.a[0] == 0.0) ini.reject(k_section, "a", "needs a_0 != 0");
  for (double x : c.b) {
    if (!std::isfinite(x)) ini.reject(k_section, "b", "coefficients must be finite");
  }
  for (double x : c.a) {
    if (!std::isfinite(x)) ini.reject(k_section, "a", "coefficients must be finite");
  }
  c.dt_s = ini.number_or(k_section, "dt_s", c.dt_s);
  if (!(c.dt_s > 0.0) || !std::isfinite(c.dt_s)) ini.reject(k_section, "dt_s", "must be > 0");
  c.input_scale = ini.number_or(k_section, "input_scale", c.input_scale);
  if (!(c.input_scale > 0.0) || !std::isfinite(c.input_scale)) ini.reject(k_section, "input_scale", "must be > 0");
  if (output == "duty_counts") {
    c.duty_full_scale = ini.number_or(k_section, "duty_full_scale", c.duty_full_scale);
    if (!(c.duty_full_scale > 0.0) || !std::isfinite(c.duty_full_scale)) {
      ini.reject(k_section, "duty_full_scale", "must be > 0");
    }
  }
  // factor() scales every coefficient onto the board (and the equation's output onto duty):
  // finite both ways, or a gain becomes 0 x inf, a nan that no register can hold.
  const double factor = c.units().factor();
  if (!(std::isfinite(factor) && std::isfinite(1.0 / factor))) {
    ini.reject(
        k_section, ini.has(k_section, "duty_full_scale") ? "duty_full_scale" : "input_scale",
        fmt::format("input_scale x (60000/2048) x (1000/duty_full_scale) = {} is not a finite, nonzero scale",
                    config::format_number(factor)));
  }
  const double round = ini.number_or(k_section, "round_output", c.round_output ? 1.0 : 0.0);
  if (round != 0.0 && round != 1.0) ini.reject(k_section, "round_output", "must be 0 or 1");
  c.round_output = round == 1.0;
  c.duty_resolution = ini.number_or(k_section, "duty_resolution", c.duty_resolution);
  if (!(c.duty_resolution >= 0.0 && c.duty_resolution < 1.0)) {
    ini.reject(k_section, "duty_resolution", "must be in [0, 1)");
  }
  return c;
}

void controller_to_ini(const Controller& c, config::Ini& ini) {
  ini.set(k_section, "type", c.type);
  ini.set(k_section, "b", list_text(c.b), "numerator on e, b_0 first");
  ini.set(k_section, "a", list_text(c.a), "denominator on y, a_0 first");
  ini.set(k_section, "dt_s", c.dt_s, "s");
  ini.set(k_section, "input_scale", c.input_scale, "counts per sample per rpm");
  ini.set(k_section, "output", "duty_counts");
  ini.set(k_section, "duty_full_scale", c.duty_full_scale, "duty counts at 100 %");
  ini.set(k_section, "round_output", c.round_output ? 1.0 : 0.0,
          c.round_output ? "y in whole counts" : "the board keeps an exact accumulator");
  if (c.duty_resolution != Controller{}.duty_resolution) {
    ini.set(k_section, "duty_resolution", c.duty_resolution, "fraction of full scale");
  }
}

void fixed_point_to_ini(const BoardFixedPoint& q, double counts_per_rev, double duty_full_scale,
                        config::Ini& ini) {
  const double lsb = std::ldexp(1.0, -q.coef_frac);
  ini.set(k_fixed, "mode", q.mode);
  ini.set(k_fixed, "coef_frac", static_cast<double>(q.coef_frac),
          fmt::format("F: c_q = round(c_board * 2^F), Q{}.{}", 15 - q.coef_frac, q.coef_frac));
  ini.set(k_fixed, "unit_factor", q.factor,
          fmt::format("c_board = c * ({}/2048) * (1000/{}) in 1/1000 duty per pulse/ms",
                      config::format_number(counts_per_rev), config::format_number(duty_full_scale)));
  static constexpr const char* k_names[] = {"b0", "b1", "b2"};
  for (std::size_t k = 0; k < q.regs.size(); ++k) {
    const double v = static_cast<double>(q.regs[k]);
    const std::string note = fmt::format("{} /1000 per pulse/ms", config::format_number(v * lsb));
    ini.set(k_fixed, q.mode == "p" ? std::string("kp") : std::string(k_names[k]), v, note);
  }
  ini.set(k_fixed, "acc_max", q.acc_max, "worst case 1000 * 2^(F+8) + 8191 * sum |c_q| <= 2^31 - 1");
}

std::optional<BoardFixedPoint> board_controller(const config::Ini& ini) {
  const std::optional<Controller> c = controller_from_ini(ini);
  if (!c) return std::nullopt;
  if (ini.number(k_fixed, "coef_frac")) return fixed_point_from_ini(ini, *c);
  if (std::fabs(c->dt_s - k_tick_s) > 1e-12) {
    ini.reject(k_section, "dt_s", fmt::format("the board's controller runs every 0.001 s; {}", k_board_forms));
  }
  std::optional<BoardFixedPoint> q;
  try {
    q = board_fixed_point(c->b, c->a, c->units());
  } catch (const Error& e) {
    ini.reject(k_section, "b", e.what());
  }
  if (!q) {
    const bool incremental = c->a.size() == 2 && c->a[1] == -c->a[0];
    std::string what = ini.has(k_section, "type") ? fmt::format("a {} controller; ", c->type) : std::string();
    if (c->type == "pid") what = "a PID with a derivative filter (mcg-design pid --form board designs the board's PID); ";
    ini.reject(k_section, incremental || c->a.size() == 1 ? "b" : "a", what + k_board_forms);
  }
  return q;
}

}  // namespace mcg::boardunits
