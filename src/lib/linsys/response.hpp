// Time responses: simulation of discrete transfer functions, closed-loop steps and their metrics.
#pragma once

#include "linsys/tf.hpp"

#include <optional>
#include <string>
#include <vector>

namespace mcg::linsys {

/// Output of a proper discrete H for an input sequence (zero initial state), by the transposed
/// direct form II of den[0]·y[k] = Σ num_i·u[k−i] − Σ_{i>0} den_i·y[k−i]. A delay in H must be
/// whole samples.
std::vector<double> simulate(const Tf& h, const std::vector<double>& input);

/// The unit step of r → y and r → u: closed (e = r − y, u = C·e, y = G·u) or open (u = C·r).
struct StepResponse {
  std::vector<double> t_s;
  std::vector<double> y;
  std::vector<double> u;
  double final_value = 0.0;  ///< T(0) or T(1): the exact steady state of y (inf/nan if unstable)
  std::string note;          ///< how a continuous delay was simulated, if there was one
  bool sampled = false;      ///< a discrete loop: y exists only at the sample instants
  /// For a continuous response known in closed form: y(t) = step of `rational` at t − shift_s
  /// (no delay, or an open loop with its delay as the shift); absent for a closed loop with delay.
  std::optional<Tf> rational;
  double shift_s = 0.0;
};

/// Simulates the unit step of the loop G·C (C = 1 if absent), closed by unit feedback or,
/// with open_loop, the series C·G as typed. Discrete loops run at their sample period,
/// exactly. Continuous loops are sampled at h = t_end/points through the ZOH-discretised
/// response, exact at the samples since the step is constant between them; with a delay τ in
/// a closed loop, h is set to τ/m and the loop is closed around the ZOH plant with z^−m.
/// t_end_s <= 0 picks 10 time constants of the slowest pole.
StepResponse step_response(const Tf& plant, const std::optional<Tf>& controller, double t_end_s, int points,
                           bool open_loop = false);

/// The levels of the metrics, as MATLAB's stepinfo options: RiseTimeLimits and
/// SettlingTimeThreshold (fractions).
struct StepLimits {
  double rise_low = 0.1;
  double rise_high = 0.9;
  double settling = 0.02;
};

/// MATLAB's stepinfo set for a step from rest of size r, y_f the exact final value, and the
/// error from the final value d(t) = y(t) − y_f:
///  rise_time_s        t(y·sgn first reaches high·|y_f|) − t(... low·|y_f|)
///  transient_time_s   the first time after which |d| stays within settling·max|d|
///                     (MATLAB's TransientTime, its SettlingTime before R2021b)
///  settling_time_s    the first time after which |d| stays within settling·|y_f|
///  settling_min/_max  min and max of y once it has risen (from the time of high·|y_f| on)
///  overshoot_pct      100 (max y·sgn − |y_f|)/|y_f|, 0 without overshoot
///  undershoot_pct     100 max(−y·sgn)/|y_f|, 0 if y never goes the wrong way
///  peak, peak_time_s  max |y| and its time
///  steady_state_error r − y_f
/// Continuous responses (sampled = false) interpolate times between samples; discrete ones are
/// measured at their sample instants, as MATLAB and python-control do. A response that has not
/// settled by its last sample has NaN settling and transient times.
struct StepMetrics {
  double final_value = 0.0;
  double rise_time_s = 0.0;
  double transient_time_s = 0.0;
  double settling_time_s = 0.0;
  double settling_min = 0.0;
  double settling_max = 0.0;
  double overshoot_pct = 0.0;
  double undershoot_pct = 0.0;
  double peak = 0.0;
  double peak_time_s = 0.0;
  double steady_state_error = 0.0;
};

StepMetrics step_metrics(const std::vector<double>& t_s, const std::vector<double>& y, double final_value,
                         double reference, const StepLimits& limits = {}, bool sampled = false);

/// step_metrics of a simulated response, with a continuous peak located exactly where the
/// response is known in closed form: the root of y'(t) = C(A x(t) + B) next to the largest sample.
StepMetrics step_info(const StepResponse& s, double reference, const StepLimits& limits = {});

}  // namespace mcg::linsys
