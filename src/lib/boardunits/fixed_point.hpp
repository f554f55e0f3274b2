// The board's controller registers for a designed difference equation (man/mcg-protocol.7,
// CONTROLLER AND FIXED POINT; docs/formats.md, [fixed_point]).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "boardunits/chain.hpp"

namespace mcg::boardunits {

/// The board's controller modes by name: k_board_modes[MCG_MODE_x] is mode x's name (the mode
/// register's values, checked against mcg_protocol.h in fixed_point.cpp).
inline constexpr std::array<std::string_view, MCG_MODE_COUNT> k_board_modes{"open", "p", "pi", "pid"};
/// The MCG_MODE_* value of a mode's name; nullopt for a name that is no mode.
std::optional<std::int16_t> board_mode(std::string_view name);

/// A controller's units: e = input_scale · rpm error (counts per sample), y in duty counts with
/// duty_full_scale counts at 100 %. The defaults are the report's chain.
struct ControllerUnits {
  double input_scale = LoopChain{}.input_scale();  ///< counts per sample per rpm (512 counts/rev, 1 ms)
  double duty_full_scale = k_pwm_full_counts;      ///< duty counts at 100 %
  double dt_s = k_tick_s;                          ///< sample period, s

  /// c_board = c · factor(): the board counts e in pulses per 1 ms at 2048 pulses/rev and u in
  /// 1/1000 duty, so factor = input_scale · (60000/2048) · (1000/duty_full_scale)
  /// (the report's units: (512/2048) · (1000/922) = 0.27115).
  double factor() const;
};

/// What the board holds and runs each 1 ms tick n (e in Q8 pulses per tick, -8191 <= e <= r):
///   P:   U[n] = duty_bias·2^(F+8) + kp·e[n]
///   PI:  U[n] = sat(U[n−1] + b0·e[n] + b1·e[n−1])
///   PID: U[n] = sat(U[n−1] + b0·e[n] + b1·e[n−1] + b2·e[n−2])
///   u[n] = (U[n] + 2^(F+7)) >> (F+8)   (1/1000 duty, rounded half up)
/// with int16 coefficients c_q = round(c_board·2^F) and an int32 accumulator U.
struct BoardFixedPoint {
  int coef_frac = 0;                ///< F, fractional bits of the coefficients (0..12)
  std::string mode;                 ///< "p", "pi" or "pid"
  std::vector<std::int32_t> regs;   ///< kp (P) or b0, b1, b2 (PI, PID; b2 = 0 for PI): int16 values
  std::vector<double> wanted;       ///< c_board before rounding, as regs (what regs 2^-F approximates)
  double factor = 0.0;              ///< c_board = c_design · factor
  std::vector<double> b;            ///< the coefficients the board runs, in the design's units: c_q 2^−F / factor
  std::vector<double> a;            ///< (1) for P, (1, −1) for PI and PID
  double acc_max = 0.0;             ///< worst-case |U[n−1] + Σ c_q e|: 1000·2^(F+8) + 8191·Σ|c_q|
};

/// One register value of a controller on the board: its id (MCG_REG_*), the int16 it holds, and
/// the value before rounding (BoardFixedPoint::wanted for a gain, or raw 2^-F without it; the
/// same number otherwise).
struct BoardRegisterValue {
  std::uint8_t id;
  std::int16_t raw;
  double wanted;
};

/// The registers that hold `q` on the board, in the order a load writes them: coef_frac, kp (mode
/// p) or b0, b1, b2 (pi, pid), then mode, written last because it switches the controller on.
std::vector<BoardRegisterValue> board_registers(const BoardFixedPoint& q);

/// The registers for the difference equation Σ a_k y[n−k] = Σ b_k e[n−k] in `units`: F is the
/// largest F <= 12 keeping every |c_q| <= 32767 (as mcg-serial chooses it). Returns nullopt
/// for a form the board does not run (dt_s other than 1 ms; a other than (1) with one b, or
/// (1, −1) with two or three b). Throws mcg::Error when a coefficient exceeds 16 bits even at
/// F = 0, when a non-zero coefficient rounds to 0 (the controller would change structure),
/// or when the worst-case accumulator exceeds 2^31 − 1.
std::optional<BoardFixedPoint> board_fixed_point(const std::vector<double>& b, const std::vector<double>& a,
                                                 const ControllerUnits& units);

}  // namespace mcg::boardunits
