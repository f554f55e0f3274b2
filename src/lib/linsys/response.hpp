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

/// The closed-loop unit step of r → y and r → u for e = r − y, u = C·e, y = G·u.
struct StepResponse {
  std::vector<double> t_s;
  std::vector<double> y;
  std::vector<double> u;
  double final_value = 0.0;  ///< T(0) or T(1): the exact steady state of y (inf/nan if unstable)
  std::string note;          ///< how a continuous delay was simulated, if there was one
};

/// Simulates the unit step of the loop G·C (C = 1 if absent). Discrete loops run at their
/// sample period, exactly. Continuous loops are sampled at h = t_end/points through the
/// ZOH-discretised closed loop, exact at the samples since the step is constant between them;
/// with a delay τ, h is set to τ/m and the loop is closed around the ZOH plant with z^−m.
/// t_end_s <= 0 picks 10 time constants of the slowest closed-loop pole.
StepResponse step_response(const Tf& plant, const std::optional<Tf>& controller, double t_end_s, int points);

/// Step metrics of y(t) for a step of size r, with y_f the exact final value:
///  rise_time_s       t(y first reaches 0.9 y_f) − t(y first reaches 0.1 y_f), interpolated
///  peak, peak_time_s max of y·sign(y_f) and its time
///  overshoot_pct     100 (peak − y_f)/|y_f|, 0 without overshoot
///  steady_state_error r − y_f
///  settling_time_s   the last time |y − y_f| leaves 2 % of |y_f|
///  transient_time_s  the older "2 % of the peak error" time: the last time |e − e_f| leaves
///                    2 % of max|e|, e = r − y (from rest max|e| = r, the step itself)
struct StepMetrics {
  double final_value = 0.0;
  double rise_time_s = 0.0;
  double peak = 0.0;
  double peak_time_s = 0.0;
  double overshoot_pct = 0.0;
  double steady_state_error = 0.0;
  double settling_time_s = 0.0;
  double transient_time_s = 0.0;
};

StepMetrics step_metrics(const std::vector<double>& t_s, const std::vector<double>& y, double final_value,
                         double reference);

}  // namespace mcg::linsys
