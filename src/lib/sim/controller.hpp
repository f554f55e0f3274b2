// The board's digital speed controller, emulated: a difference equation on encoder counts,
// sampled every dt_s, with the PWM's saturation, anti-windup and duty resolution.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "boardunits/controller.hpp"  // Controller, the [controller] section
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

 private:
  Controller m_c;
  std::vector<double> m_e;   ///< e_n, e_{n-1}, ...
  std::vector<double> m_y;   ///< y_{n-1}, y_{n-2}, ...
};

/// Incremental form of the count estimator for a running loop: feed (t, theta) at each
/// tick, read the rpm over the trailing window.
class WindowCounter {
 public:
  explicit WindowCounter(const CountEstimator& estimator) : m_e(estimator) {}
  double push(double t_s, double theta_rad);

 private:
  CountEstimator m_e;
  std::vector<std::pair<double, double>> m_hist;   ///< (t, theta), trimmed to the window
};

/// The closed loop advanced one row at a time, as the rows arrive (row n acts over
/// [t_n, t_{n+1}); its end is known only when row n+1 comes). Ticks at t_0 + k dt_s; at each
/// tick the controller reads the encoder estimate and applies its duty at once (no
/// computation delay). Its memory does not grow with the run.
class ClosedLoop {
 public:
  ClosedLoop(const model::Model& model, const Controller& controller, const CountEstimator& estimator,
             const model::SimOptions& options, int initial_clutch);

  /// Takes row n: runs the plant over [t_{n-1}, t_s) under row n-1 (the ticks inside it
  /// with row n-1's command), then ticks at t_s if one is due there with `rpm_cmd`.
  /// t_s must increase from row to row (MCG_DEMAND; the caller checks its input).
  void row(double t_s, double rpm_cmd, int clutch, double r_load_ohm);
  /// The plant at the last row's time, before that row's inputs act.
  model::State state() const { return m_plant.state(); }
  /// The duty in effect from the last row's time on (the controller's last output).
  double duty() const { return m_duty; }

 private:
  void tick(double t_s, double rpm_cmd);
  double tick_time(long k) const { return m_t0_s + static_cast<double>(k) * m_dt_s; }

  model::Plant m_plant;
  ControllerState m_ctl;
  WindowCounter m_counter;
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
ClosedLoopOutputs simulate_closed_loop(const model::Model& model, const Controller& controller,
                                       const CountEstimator& estimator, const ClosedLoopInputs& inputs,
                                       const model::SimOptions& options = {});

}  // namespace mcg::sim
