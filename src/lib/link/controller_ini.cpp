// [controller] sections of mcg-design and mcg-sim as board registers.
#include "boardunits/controller.hpp"  // board_controller
#include "boardunits/fixed_point.hpp"  // board_registers
#include "common/demand.hpp"
#include "config/ini.hpp"             // Ini
#include "link/connection.hpp"        // controller_registers

namespace mcg::link {

std::vector<std::pair<const RegisterInfo*, double>> controller_registers(const config::Ini& ini) {
  std::vector<std::pair<const RegisterInfo*, double>> out;
  const std::optional<boardunits::BoardFixedPoint> q = boardunits::board_controller(ini);
  if (!q) return out;
  // The unrounded board gains: writing them at 2^-F rounds to q->regs, and load notes each rounding.
  for (const boardunits::BoardRegisterValue& r : boardunits::board_registers(*q)) {
    const RegisterInfo* reg = find_register(r.id);
    MCG_DEMAND(reg != nullptr);
    out.emplace_back(reg, r.wanted);
  }
  return out;
}

}  // namespace mcg::link
