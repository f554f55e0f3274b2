// The firmware core's host layer, one per process.
#include "board/core.hpp"

#include "common/demand.hpp"
#include "host_board.h"    // host_board_*
#include "mcg_protocol.h"  // MCG_ST_OK

namespace mcg::board {

namespace {

bool g_core_alive = false;

}  // namespace

FirmwareCore::FirmwareCore(std::uint32_t baud) {
  MCG_DEMAND(!g_core_alive);
  g_core_alive = true;
  host_board_reset();
  host_board_set_baud(baud);
}

FirmwareCore::~FirmwareCore() { g_core_alive = false; }

std::uint8_t FirmwareCore::apply(std::uint8_t reg, std::int16_t raw) {
  return host_board_reg_apply(reg, raw);
}

void FirmwareCore::write(std::uint8_t reg, std::int16_t raw) { MCG_DEMAND(apply(reg, raw) == MCG_ST_OK); }

std::int16_t FirmwareCore::read(std::uint8_t reg) const {
  std::int16_t value = 0;
  MCG_DEMAND(host_board_reg_read(reg, &value) == MCG_ST_OK);
  return value;
}

std::int16_t FirmwareCore::tick(std::uint16_t pulses) {
  host_board_tick(pulses);
  return host_board_duty();
}

std::int16_t FirmwareCore::duty_permille() const { return host_board_duty(); }

bool FirmwareCore::clutch_engaged() const { return host_board_clutch() != 0; }

bool FirmwareCore::load_closed() const { return host_board_load() != 0; }

}  // namespace mcg::board
