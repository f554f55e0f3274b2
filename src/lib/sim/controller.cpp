// Emulation of the board's digital controller and the closed loop around the plant.
#include "sim/controller.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "board/core.hpp"  // FirmwareCore
#include "common/checked.hpp"
#include "common/demand.hpp"
#include "common/error.hpp"
#include "config/ini.hpp"
#include "mcg_protocol.h"  // MCG_REG_*, MCG_MODE_*

namespace mcg::sim {

ControllerState::ControllerState(const Controller& controller)
    : m_c(controller), m_e(controller.b.size(), 0.0), m_y(controller.a.size() > 1 ? controller.a.size() - 1 : 0, 0.0) {
  MCG_DEMAND(!m_c.b.empty() && !m_c.a.empty() && m_c.a[0] != 0.0);
}

double ControllerState::step(double error_rpm) {
  std::rotate(m_e.rbegin(), m_e.rbegin() + 1, m_e.rend());
  m_e[0] = m_c.input_scale * error_rpm;
  double acc = 0.0;
  for (std::size_t k = 0; k < m_e.size(); ++k) acc += m_c.b[k] * m_e[k];
  for (std::size_t k = 0; k < m_y.size(); ++k) acc -= m_c.a[k + 1] * m_y[k];
  double y = acc / m_c.a[0];
  if (m_c.round_output) y = std::round(y);
  y = std::clamp(y, -m_c.duty_full_scale, m_c.duty_full_scale);
  if (!m_y.empty()) {
    std::rotate(m_y.rbegin(), m_y.rbegin() + 1, m_y.rend());
    m_y[0] = y;
  }
  double duty = y / m_c.duty_full_scale;
  if (m_c.duty_resolution > 0.0) duty = std::round(duty / m_c.duty_resolution) * m_c.duty_resolution;
  return std::clamp(duty, -1.0, 1.0);
}

void ControllerState::preset(double duty) {
  std::fill(m_e.begin(), m_e.end(), 0.0);
  std::fill(m_y.begin(), m_y.end(), duty * m_c.duty_full_scale);
}

namespace {

/// The encoder count a tick before the first one of a shaft turning at omega_rad_s whose angle
/// is 0 at the first tick.
double count_a_tick_before(double omega_rad_s, double dt_s) {
  return encoder_count(-omega_rad_s * dt_s, boardunits::k_board_counts_per_rev);
}

/// The board's encoder input: the pulses between two ticks, without direction.
class BoardController final : public LoopController {
 public:
  BoardController(std::int16_t mode, const std::vector<std::pair<std::uint8_t, std::int16_t>>& registers)
      : m_mode(mode) {
    for (const auto& [id, raw] : registers) m_core.write(id, raw);
    // The board refuses a closed-loop mode whose gains are all zero: say so before the run, not
    // at its first command.
    if (m_core.apply(MCG_REG_MODE, m_mode) != MCG_ST_OK) {
      fail("the board refuses mode {} with every gain zero (it would hold its duty whatever the speed)",
           static_cast<std::uint16_t>(m_mode) < MCG_MODE_COUNT
               ? boardunits::k_board_modes[static_cast<std::size_t>(m_mode)]
               : std::string_view("unknown"));
    }
    m_core.write(MCG_REG_MODE, MCG_MODE_OPEN);
  }

  double tick(double theta_rad, double rpm_cmd) override {
    MCG_DEMAND(board_takes_command(rpm_cmd));
    const double count = encoder_count(theta_rad, boardunits::k_board_counts_per_rev);
    if (!m_started) {
      m_started = true;
      m_count = count;
    }
    const double pulses = std::fmin(std::fabs(count - m_count), std::numeric_limits<std::uint16_t>::max());
    m_count = count;
    // A command switches the controller on (bumpless, from duty 0) as `set rpm_cmd`, `set mode`
    // would; 0 switches it off as `set mode open`, `set duty 0` would (open loop keeps the last
    // duty otherwise).
    const auto cmd = static_cast<std::int16_t>(rpm_cmd);
    if (cmd != 0 && cmd != m_rpm_cmd) m_core.write(MCG_REG_RPM_CMD, cmd);
    if (cmd != 0 && m_rpm_cmd == 0) m_core.write(MCG_REG_MODE, m_mode);
    if (cmd == 0 && m_rpm_cmd != 0) {
      m_core.write(MCG_REG_MODE, MCG_MODE_OPEN);
      m_core.write(MCG_REG_DUTY, 0);
    }
    m_rpm_cmd = cmd;
    return static_cast<double>(m_core.tick(static_cast<std::uint16_t>(pulses))) / boardunits::k_board_duty_full;
  }

  double dt_s() const override { return boardunits::k_tick_s; }

  void start_at(double omega_rad_s, double duty) override {
    // The duty set in open mode, then three ticks at the speed's pulses (the PID's history):
    // the first tick with a command switches the mode, bumpless from that duty.
    const double per_tick = std::fabs(omega_rad_s) * dt_s() * boardunits::k_board_counts_per_rev / (2.0 * std::numbers::pi);
    const auto pulses =
        clamp_to_integer(std::round(per_tick), std::uint16_t{0}, std::numeric_limits<std::uint16_t>::max());
    const auto raw = clamp_to_integer(std::round(duty * boardunits::k_board_duty_full),
                                      m_core.read(MCG_REG_DUTY_MIN), m_core.read(MCG_REG_DUTY_MAX));
    m_core.write(MCG_REG_DUTY, raw);
    for (int k = 0; k < 3; ++k) m_core.tick(pulses);
    m_started = true;
    m_count = count_a_tick_before(omega_rad_s, dt_s());
  }

 private:
  board::FirmwareCore m_core;
  std::int16_t m_mode;          ///< the controller's mode register while a command is in force
  bool m_started = false;
  double m_count = 0.0;
  std::int16_t m_rpm_cmd = 0;   ///< 0: controller off (mode open, duty 0)
};

/// Signed counts over one sample period, the difference equation in double.
class EquationController final : public LoopController {
 public:
  explicit EquationController(const Controller& c) : m_state(c), m_dt_s(c.dt_s) {}

  double tick(double theta_rad, double rpm_cmd) override {
    const double count = encoder_count(theta_rad, boardunits::k_board_counts_per_rev);
    if (!m_started) {
      m_started = true;
      m_count = count;
    }
    const double rpm = (count - m_count) / boardunits::k_board_counts_per_rev / m_dt_s * 60.0;
    m_count = count;
    return m_state.step(rpm_cmd - rpm);
  }

  double dt_s() const override { return m_dt_s; }

  void start_at(double omega_rad_s, double duty) override {
    m_state.preset(duty);
    m_started = true;
    m_count = count_a_tick_before(omega_rad_s, m_dt_s);
  }

 private:
  ControllerState m_state;
  double m_dt_s;
  bool m_started = false;
  double m_count = 0.0;
};

}  // namespace

namespace {

/// The rpm_cmd register's range from its row of the protocol's one table.
struct RegisterRange {
  unsigned id;
  double lo, hi;
};
#define MCG_RANGE_ROW(NAME, name, access, lo, hi, ...) RegisterRange{MCG_REG_##NAME, lo, hi},
constexpr RegisterRange k_register_ranges[] = {MCG_REGISTERS(MCG_RANGE_ROW)};
#undef MCG_RANGE_ROW
constexpr RegisterRange k_command_range = k_register_ranges[MCG_REG_RPM_CMD - 1u];
static_assert(k_command_range.id == MCG_REG_RPM_CMD);

}  // namespace

bool board_takes_command(double rpm_cmd) {
  const RegisterRange& r = k_command_range;
  return rpm_cmd == 0.0 || (rpm_cmd == std::floor(rpm_cmd) && rpm_cmd >= r.lo && rpm_cmd <= r.hi);
}

std::string board_command_range_text() {
  return fmt::format("{}..{}", k_command_range.lo, k_command_range.hi);
}

std::unique_ptr<LoopController> board_loop_controller(const boardunits::BoardFixedPoint& q) {
  std::vector<std::pair<std::uint8_t, std::int16_t>> registers;
  std::int16_t mode = MCG_MODE_OPEN;
  for (const boardunits::BoardRegisterValue& r : boardunits::board_registers(q)) {
    if (r.id == MCG_REG_MODE) {
      mode = r.raw;
    } else {
      registers.emplace_back(r.id, r.raw);
    }
  }
  return std::make_unique<BoardController>(mode, registers);
}

std::unique_ptr<LoopController> board_loop_controller(std::int16_t mode,
                                                      const std::vector<std::pair<std::uint8_t, std::int16_t>>& registers) {
  MCG_DEMAND(mode != MCG_MODE_OPEN);
  return std::make_unique<BoardController>(mode, registers);
}

std::unique_ptr<LoopController> equation_loop_controller(const Controller& controller) {
  return std::make_unique<EquationController>(controller);
}

ClosedLoop::ClosedLoop(const model::Model& model, std::unique_ptr<LoopController> controller,
                       const model::SimOptions& options, int initial_clutch)
    : m_plant(model, options, initial_clutch),
      m_ctl(std::move(controller)),
      m_dt_s(m_ctl->dt_s()),
      m_tol_s(1e-9 * m_dt_s),
      m_supply_V(model.params.supply_V) {}

void ClosedLoop::start_at(double omega_rad_s, double duty) {
  MCG_DEMAND(!m_started);
  m_plant.start_at(omega_rad_s);
  m_ctl->start_at(omega_rad_s, duty);
}

void ClosedLoop::tick(double t_s, double rpm_cmd) {
  (void)t_s;
  m_duty = m_ctl->tick(m_plant.state().theta_rad, rpm_cmd);
  ++m_tick;
}

void ClosedLoop::row(double t_s, double rpm_cmd, int clutch, double r_load_ohm) {
  if (!m_started) {
    m_started = true;
    m_t0_s = t_s;
  } else {
    MCG_DEMAND(t_s > m_t_s);
    // The previous row's interval: step to each tick inside it, tick there with its command.
    double t = m_t_s;
    bool first = true;
    while (true) {
      if (!first && std::abs(tick_time(m_tick) - t) <= m_tol_s) tick(t, m_rpm_cmd);
      first = false;
      const double t_next = std::min(t_s, tick_time(m_tick));
      if (t_next - t <= m_tol_s) {
        if (t_s - t <= m_tol_s) break;
        continue;
      }
      model::Drive drive = m_drive;
      drive.v_V = m_duty * m_supply_V;
      m_plant.step(t_next - t, drive);
      t = t_next;
      if (t_s - t <= m_tol_s) break;
    }
  }
  if (std::abs(tick_time(m_tick) - t_s) <= m_tol_s) tick(t_s, rpm_cmd);
  m_t_s = t_s;
  m_rpm_cmd = rpm_cmd;
  m_drive = model::Drive{0.0, clutch, r_load_ohm};
}

ClosedLoopOutputs simulate_closed_loop(const model::Model& model, std::unique_ptr<LoopController> controller,
                                       const ClosedLoopInputs& in, const model::SimOptions& options) {
  const std::size_t n = in.t_s.size();
  MCG_DEMAND(in.rpm_cmd.size() == n && in.clutch.size() == n && in.r_load_ohm.size() == n);
  ClosedLoopOutputs out;
  out.plant.resize(n);
  out.duty.assign(n, 0.0);
  out.v_V.assign(n, 0.0);
  if (n == 0) return out;
  ClosedLoop loop(model, std::move(controller), options, static_cast<int>(in.clutch[0]));
  for (std::size_t row = 0; row < n; ++row) {
    loop.row(in.t_s[row], in.rpm_cmd[row], static_cast<int>(in.clutch[row]), in.r_load_ohm[row]);
    out.plant.store(row, loop.state());
    out.duty[row] = loop.duty();
    out.v_V[row] = loop.duty() * model.params.supply_V;
  }
  return out;
}

}  // namespace mcg::sim
