// [controller] sections of mcg-design and mcg-sim as board registers.
#include <cmath>

#include "boardunits/controller.hpp"  // board_controller
#include "config/ini.hpp"             // Ini
#include "link/connection.hpp"        // controller_registers
#include "mcg_protocol.h"             // MCG_MODE_*

namespace mcg::link {

std::vector<std::pair<const RegisterInfo*, double>> controller_registers(const config::Ini& ini) {
  std::vector<std::pair<const RegisterInfo*, double>> out;
  const std::optional<boardunits::BoardFixedPoint> q = boardunits::board_controller(ini);
  if (!q) return out;
  // The unrounded board gains: writing them at 2^-F rounds to q->regs, and load notes each rounding.
  const auto gain = [&](std::size_t k) { return q->wanted[k]; };
  out.emplace_back(&require_register("coef_frac"), q->coef_frac);
  if (q->mode == "p") {
    out.emplace_back(&require_register("kp"), gain(0));
    out.emplace_back(&require_register("mode"), MCG_MODE_P);
    return out;
  }
  static constexpr const char* k_names[] = {"b0", "b1", "b2"};
  for (std::size_t k = 0; k < 3; ++k) out.emplace_back(&require_register(k_names[k]), gain(k));
  out.emplace_back(&require_register("mode"), q->mode == "pid" ? MCG_MODE_PID : MCG_MODE_PI);
  return out;
}

}  // namespace mcg::link
