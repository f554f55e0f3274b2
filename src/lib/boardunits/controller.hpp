// The [controller] section (docs/formats.md): its one parser and writer, and what the board
// runs for it. mcg-design writes it, mcg-sim runs it, mcg-serial loads it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "boardunits/chain.hpp"
#include "boardunits/fixed_point.hpp"

namespace mcg::config {
class Ini;
}

namespace mcg::boardunits {

/// A digital speed controller as a difference equation:
///   sum_{k=0}^{na} a_k y_{n-k} = sum_{k=0}^{nb} b_k e_{n-k},  a_0 != 0,
///   e_n = input_scale (rpm_cmd_n - rpm_n),  duty = y_n / duty_full_scale.
/// The report's PI: b = 11.645 -6.987, a = 1 -1, input_scale = 512/60000 counts per rpm
/// (the error in encoder counts per 1 ms at 512 counts/rev), duty_full_scale = 922.
struct Controller {
  std::string type = "pi";                        ///< informational (p, pi, pid, lead, ...)
  std::vector<double> b{11.645, -6.987};          ///< numerator on e, b_0 first
  std::vector<double> a{1.0, -1.0};               ///< denominator on y, a_0 first
  double dt_s = k_tick_s;                         ///< sampling period
  double input_scale = LoopChain{}.input_scale(); ///< error units per rpm
  double duty_full_scale = k_pwm_full_counts;     ///< output units at 100 % duty
  bool round_output = true;     ///< difference mode: y in whole counts, as the report's firmware held it
  double duty_resolution = 0.002;  ///< difference mode: PWM duty step (fraction of full scale), 0 = none

  ControllerUnits units() const { return {input_scale, duty_full_scale, dt_s}; }
};

/// The report's PI controller (section "Proportional-Integral Controller").
Controller report_pi();

/// The [controller] section of `ini`, or nullopt when there is none. Throws mcg::Error
/// naming file, line and key for an unknown key or a bad value (a_0 = 0, dt_s <= 0, ...).
std::optional<Controller> controller_from_ini(const config::Ini& ini);
/// Writes `controller` as the [controller] section of `ini`: the one writer of the keys
/// controller_from_ini() reads (duty_resolution only when not the default).
void controller_to_ini(const Controller& controller, config::Ini& ini);

/// Writes `q` as the [fixed_point] section of `ini` (mode, coef_frac, unit_factor, the
/// registers, acc_max), each with the equation it follows; `counts_per_rev` and
/// `duty_full_scale` are the chain's, quoted in unit_factor's comment.
void fixed_point_to_ini(const BoardFixedPoint& q, double counts_per_rev, double duty_full_scale,
                        config::Ini& ini);

/// One line naming what the board can run, for refusals.
inline constexpr const char* k_board_forms =
    "the board runs P (a = 1, one b), PI or PID in incremental form without a derivative filter "
    "(a = 1 -1, two or three b), every 0.001 s";

/// What the board runs for the [controller] of `ini` (nullopt when there is none): the
/// registers of its [fixed_point] section bit for bit when present (mcg-design's integer form,
/// the one its [margins_quantised] analysed), else the [controller] quantised by
/// board_fixed_point. Throws mcg::Error naming the file and key, with k_board_forms, for a
/// form the board cannot run (lead, lag, filtered PID, another dt_s) or coefficients it cannot
/// hold.
std::optional<BoardFixedPoint> board_controller(const config::Ini& ini);

}  // namespace mcg::boardunits
