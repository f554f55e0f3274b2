// The board's digital speed controller, emulated: a difference equation on encoder counts,
// sampled every dt_s, with the PWM's saturation, anti-windup and duty resolution.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "model/model.hpp"
#include "sim/encoder.hpp"

namespace mcg::config {
class Ini;
}

namespace mcg::sim {

/// The [controller] section of an INI parameter set (docs/formats.md):
///   sum_{k=0}^{na} a_k y_{n-k} = sum_{k=0}^{nb} b_k e_{n-k},  a_0 != 0,
///   e_n = input_scale (rpm_cmd_n - rpm_n)        (rpm_n: the encoder estimate at tick n)
///   y_n clamped to [-duty_full_scale, duty_full_scale], rounded to whole counts when
///   round_output, and stored clamped (anti-windup: the recursion sees the applied value);
///   duty = y_n / duty_full_scale, quantised to duty_resolution; v = duty supply_V.
/// The report's PI: b = 11.645 -6.987, a = 1 -1, input_scale = 512/60000 counts per rpm
/// (the error in encoder counts per 1 ms at 512 counts/rev), duty_full_scale = 922.
struct Controller {
  std::string type = "pi";                 ///< informational (p, pi, pid, lead, ...)
  std::vector<double> b{11.645, -6.987};   ///< numerator on e, b_0 first
  std::vector<double> a{1.0, -1.0};        ///< denominator on y, a_0 first
  double dt_s = 0.001;                     ///< sampling period
  double input_scale = 512.0 / 60000.0;    ///< error units per rpm
  double duty_full_scale = 922.0;          ///< output units at 100 % duty
  bool round_output = true;                ///< y in whole counts, as the firmware holds it
  double duty_resolution = 0.002;          ///< PWM duty step (fraction of full scale), 0 = none
};

/// The report's PI controller (section "Proportional-Integral Controller").
Controller report_pi();

/// The [controller] section of `ini`, or nullopt when there is none. Throws mcg::Error
/// naming file, line and key for a bad value (a_0 = 0, dt_s <= 0, unknown output, ...).
std::optional<Controller> controller_from_ini(const config::Ini& ini);
void controller_to_ini(const Controller& controller, config::Ini& ini);

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
