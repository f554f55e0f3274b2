// [controller] sections of mcg-design and mcg-sim as board registers.
#include <cmath>

#include <fmt/format.h>

#include "common/error.hpp"     // mcg::fail
#include "config/ini.hpp"       // Ini
#include "link/connection.hpp"  // controller_registers
#include "mcg_protocol.h"       // MCG_COUNTS_PER_REV, MCG_COEF_FRAC_BITS_MAX

namespace mcg::link {

std::vector<std::pair<const RegisterInfo*, double>> controller_registers(const config::Ini& ini) {
  std::vector<std::pair<const RegisterInfo*, double>> out;
  if (!ini.has_section("controller")) return out;
  if (const auto frac = ini.number("fixed_point", "coef_frac")) {
    // mcg-design's [fixed_point]: the board's registers themselves, the coefficients its
    // [margins_quantised] analysed; written bit for bit.
    if (*frac < 0 || *frac > MCG_COEF_FRAC_BITS_MAX || *frac != std::floor(*frac)) {
      ini.reject("fixed_point", "coef_frac", fmt::format("not 0..{}", MCG_COEF_FRAC_BITS_MAX));
    }
    const std::string mode = ini.get("fixed_point", "mode").value_or("");
    if (mode != "p" && mode != "pi" && mode != "pid") ini.reject("fixed_point", "mode", "not p, pi or pid");
    const auto raw = [&](std::string_view key) {
      const double v = ini.number_or("fixed_point", key, 0.0);
      if (v != std::floor(v) || v < -32768.0 || v > 32767.0) ini.reject("fixed_point", key, "not a 16-bit integer");
      return std::ldexp(v, -static_cast<int>(*frac));
    };
    out.emplace_back(&require_register("coef_frac"), *frac);
    if (mode == "p") {
      out.emplace_back(&require_register("kp"), raw("kp"));
      out.emplace_back(&require_register("mode"), MCG_MODE_P);
      return out;
    }
    for (const char* name : {"b0", "b1", "b2"}) out.emplace_back(&require_register(name), raw(name));
    out.emplace_back(&require_register("mode"), mode == "pid" ? MCG_MODE_PID : MCG_MODE_PI);
    return out;
  }
  auto b = ini.numbers("controller", "b");
  if (!b) return out;
  std::vector<double> a = ini.numbers("controller", "a").value_or(std::vector<double>{1.0});
  if (a.empty() || a[0] == 0.0) ini.reject("controller", "a", "a_0 must not be 0");
  const double dt_s = ini.number_or("controller", "dt_s", 1e-3);
  if (std::fabs(dt_s - MCG_TICK_US * 1e-6) > 1e-12) {
    ini.reject("controller", "dt_s", "the board's controller runs every 0.001 s");
  }
  const double input_scale = ini.number_or("controller", "input_scale", 512.0 / 60000.0);
  const std::string output = ini.get("controller", "output").value_or("duty_counts");
  if (output != "duty_counts" && output != "duty") ini.reject("controller", "output", "not duty_counts or duty");
  // output = duty: y is the duty itself, full scale 1.
  const double duty_full_scale = output == "duty" ? 1.0 : ini.number_or("controller", "duty_full_scale", 922.0);
  if (!(input_scale > 0.0) || !std::isfinite(input_scale)) ini.reject("controller", "input_scale", "must be > 0");
  if (!(duty_full_scale > 0.0) || !std::isfinite(duty_full_scale)) {
    ini.reject("controller", "duty_full_scale", "must be > 0");
  }
  const bool incremental = a.size() == 2 && a[1] == -a[0];
  if (!(a.size() == 1 || incremental)) {
    ini.reject("controller", "a", "the board runs a = 1 (P) or a = 1 -1 (incremental PI, PID)");
  }
  if (b->empty() || (!incremental && b->size() != 1) || b->size() > 3) {
    ini.reject("controller", "b", incremental ? "PI/PID on the board: 2 or 3 coefficients" : "P on the board: 1 coefficient");
  }
  const double scale = input_scale * (60000.0 / MCG_COUNTS_PER_REV) * (MCG_DUTY_FULL / duty_full_scale) / a[0];
  std::vector<double> g;
  double largest = 0.0;
  for (const double bk : *b) {
    g.push_back(bk * scale);
    largest = std::fmax(largest, std::fabs(bk * scale));
  }
  int frac = static_cast<int>(MCG_COEF_FRAC_BITS_MAX);
  while (frac >= 0 && std::round(std::ldexp(largest, frac)) > 32767.0) --frac;
  if (frac < 0) ini.reject("controller", "b", "a coefficient exceeds the board's 16-bit range even with F = 0");

  out.emplace_back(&require_register("coef_frac"), frac);
  if (!incremental) {
    out.emplace_back(&require_register("kp"), g[0]);
    out.emplace_back(&require_register("mode"), MCG_MODE_P);
    return out;
  }
  static constexpr const char* k_names[] = {"b0", "b1", "b2"};
  for (std::size_t k = 0; k < 3; ++k) out.emplace_back(&require_register(k_names[k]), k < g.size() ? g[k] : 0.0);
  out.emplace_back(&require_register("mode"), g.size() == 3 ? MCG_MODE_PID : MCG_MODE_PI);
  return out;
}

}  // namespace mcg::link
