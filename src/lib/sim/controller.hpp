// The closed loop's speed controller: the board's firmware core itself, or a difference
// equation in double for designs the board cannot run.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "boardunits/controller.hpp"  // Controller, the [controller] section
#include "common/units.hpp"           // rpm_from_rad_s, rad_s_from_rpm
#include "model/model.hpp"
#include "sim/encoder.hpp"

namespace mcg::sim {

using boardunits::Controller;
using boardunits::controller_from_ini;
using boardunits::controller_to_ini;
using boardunits::report_pi;

/// The difference equation with its state; step() is one sampling instant.
class ControllerState {
 public:
  explicit ControllerState(const Controller& controller);
  /// Takes the speed error in rpm, returns the duty (-1..1) to hold until the next tick.
  double step(double error_rpm);
  /// Before the first step: every past output at `duty` (-1..1), every past error 0, as a
  /// loop that has settled there (bumpless for the incremental forms).
  void preset(double duty);

 private:
  Controller m_c;
  std::vector<double> m_e;   ///< e_n, e_{n-1}, ...
  std::vector<double> m_y;   ///< y_{n-1}, y_{n-2}, ...
};

/// The controller of a closed loop, sampled every dt_s(): at each tick it reads the shaft angle
/// through the board's encoder (512 lines x4, 2048 counts/rev) and returns the duty to hold.
class LoopController {
 public:
  virtual ~LoopController() = default;
  /// The tick: the shaft at theta_rad, the command rpm_cmd in force; returns the duty (-1..1)
  /// applied from now until the next tick.
  virtual double tick(double theta_rad, double rpm_cmd) = 0;
  virtual double dt_s() const = 0;
  /// Before the first tick: the shaft turning at omega_rad_s (its angle 0 at the first tick),
  /// the controller's output at `duty` (-1..1), as a loop found running.
  virtual void start_at(double omega_rad_s, double duty) = 0;
};

/// The board's own controller: the firmware's C core (host board layer, as the emulated board
/// runs it) holding `registers` (coef_frac, kp or b0, b1, b2; the rest at power-on), fed the
/// encoder pulses of each 1 ms tick without direction. A command (board_takes_command,
/// MCG_DEMAND: the caller checks its input) is written to rpm_cmd with the registers' mode on, as
/// `mcg-serial set` would; a command of 0 sets mode open at duty 0 (the board at rest).
/// Its duty is the core's, in 1/1000. Uses the process's one firmware core while it lives.
std::unique_ptr<LoopController> board_loop_controller(const boardunits::BoardFixedPoint& registers);
/// The same core with raw registers (id, value) written at power-on, as a capture's
/// board_config states them, run in `mode` (MCG_MODE_P, _PI or _PID) while a command is in force.
std::unique_ptr<LoopController> board_loop_controller(std::int16_t mode,
                                                      const std::vector<std::pair<std::uint8_t, std::int16_t>>& registers);

/// The difference equation in double (ControllerState) on the signed encoder counts of each
/// sample: rpm = (count(t) - count(t - dt_s)) / 2048 / dt_s * 60. Runs any [controller] (lead,
/// lag, filtered PID, any dt_s) and any command, for designs the board cannot run.
std::unique_ptr<LoopController> equation_loop_controller(const Controller& controller);

/// Whether `rpm_cmd` is a command the board runs: 0 (controller off) or what its rpm_cmd register
/// holds (a whole rpm, 120..720).
bool board_takes_command(double rpm_cmd);
/// The range of board_takes_command's whole rpm for messages, from the protocol's table: "120..720".
std::string board_command_range_text();

/// The closed loop advanced one row at a time, as the rows arrive (row n acts over
/// [t_n, t_{n+1}); its end is known only when row n+1 comes). Ticks at t_0 + k dt_s; at each
/// tick the controller reads the encoder and applies its duty at once (no computation delay),
/// as the board's core does within its tick. Its memory does not grow with the run.
class ClosedLoop {
 public:
  ClosedLoop(const model::Model& model, std::unique_ptr<LoopController> controller,
             const model::SimOptions& options, int initial_clutch);

  /// Takes row n: runs the plant over [t_{n-1}, t_s) under row n-1 (the ticks inside it
  /// with row n-1's command), then ticks at t_s if one is due there with `rpm_cmd`.
  /// t_s must increase from row to row (MCG_DEMAND; the caller checks its input).
  void row(double t_s, double rpm_cmd, int clutch, double r_load_ohm);
  /// Before the first row: the shaft turning at omega_rad_s and the controller at `duty`, as
  /// a capture that starts mid-run found the loop (Plant::start_at, LoopController::start_at).
  void start_at(double omega_rad_s, double duty);
  /// The plant at the last row's time, before that row's inputs act.
  model::State state() const { return m_plant.state(); }
  /// The duty in effect from the last row's time on (the controller's last output).
  double duty() const { return m_duty; }

 private:
  void tick(double t_s, double rpm_cmd);
  double tick_time(long k) const { return m_t0_s + static_cast<double>(k) * m_dt_s; }

  model::Plant m_plant;
  std::unique_ptr<LoopController> m_ctl;
  double m_dt_s;
  double m_tol_s;
  double m_supply_V;
  double m_t0_s = 0.0;
  /// Ticks are counted, not accumulated, so that they stay exactly on t0 + k dt.
  long m_tick = 0;
  double m_duty = 0.0;
  bool m_started = false;
  double m_t_s = 0.0;          ///< the last row's time
  double m_rpm_cmd = 0.0;      ///< the last row's inputs
  model::Drive m_drive;
};

/// Inputs of a closed-loop run, one entry per row (row n acts over [t_n, t_{n+1})).
struct ClosedLoopInputs {
  std::vector<double> t_s;
  std::vector<double> rpm_cmd;
  std::vector<double> clutch;
  std::vector<double> r_load_ohm;
};

struct ClosedLoopOutputs {
  model::Outputs plant;        ///< state at each row time
  std::vector<double> duty;    ///< duty in effect over [t_n, t_{n+1}) (the controller's last output)
  std::vector<double> v_V;     ///< duty * supply_V
};

/// Runs the plant under the controller over a whole record (ClosedLoop row by row).
ClosedLoopOutputs simulate_closed_loop(const model::Model& model, std::unique_ptr<LoopController> controller,
                                       const ClosedLoopInputs& inputs, const model::SimOptions& options = {});

}  // namespace mcg::sim
