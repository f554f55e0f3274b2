// The firmware core's host layer, stepped against the plant.
#include "board/board.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include "host_board.h"    // host_board_*
#include "mcg_protocol.h"  // MCG_COUNTS_PER_REV, MCG_DUTY_FULL

namespace mcg::board {

namespace {

constexpr double k_tick_s = MCG_TICK_US * 1e-6;

double encoder_position(double theta_rad) {
  return std::floor(theta_rad * MCG_COUNTS_PER_REV / (2.0 * std::numbers::pi));
}

}  // namespace

EmulatedBoard::EmulatedBoard(const BoardOptions& options)
    : m_options(options), m_core(options.baud), m_plant(options.model, model::SimOptions{options.max_step_s}, 1) {
  m_state = m_plant.state();
  m_count = encoder_position(m_state.theta_rad);
}

EmulatedBoard::~EmulatedBoard() = default;

std::size_t EmulatedBoard::rx(std::span<const std::uint8_t> bytes) {
  return host_board_rx(bytes.data(), bytes.size());
}

std::size_t EmulatedBoard::tx(std::span<std::uint8_t> out) { return host_board_tx(out.data(), out.size()); }

std::int16_t EmulatedBoard::duty_permille() const { return m_core.duty_permille(); }

double EmulatedBoard::time_s() const { return host_board_time_ms() * 1e-3; }

void EmulatedBoard::tick() {
  model::Drive drive;
  drive.v_V = static_cast<double>(m_core.tick(m_pulses)) / MCG_DUTY_FULL * m_options.model.params.supply_V;
  drive.clutch = m_core.clutch_engaged() ? 2 : 1;
  drive.r_load_ohm = m_core.load_closed() ? m_options.r_load_ohm : model::k_open_circuit;
  m_plant.step(k_tick_s, drive);
  m_state = m_plant.state();
  const double count = encoder_position(m_state.theta_rad);
  const double pulses = std::fabs(count - m_count);
  m_pulses = static_cast<std::uint16_t>(std::fmin(pulses, std::numeric_limits<std::uint16_t>::max()));
  m_count = count;
}

}  // namespace mcg::board
