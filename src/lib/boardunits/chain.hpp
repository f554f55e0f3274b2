// The loop chain of the rig and its board, defined once: PWM, H-bridge, encoder, sample period.
//
// Everything that converts between the board's counts and physical units derives from here
// (design's loop, the [controller] defaults, the fixed-point scale, the emulated board), and the
// protocol's own constants (mcg_protocol.h) are checked against it at compile time.
#pragma once

#include <numbers>

#include "mcg_protocol.h"  // MCG_TICK_US, MCG_COUNTS_PER_REV, MCG_DUTY_FULL

namespace mcg::boardunits {

/// Control sample period, s: the board's 1 ms tick.
inline constexpr double k_tick_s = MCG_TICK_US * 1e-6;
/// Milliseconds per minute: rpm = counts per ms / counts_per_rev * 60000.
inline constexpr double k_ms_per_min = 60000.0;
/// Encoder lines per revolution, and the board's x4 quadrature decoding of them.
inline constexpr int k_encoder_lines = 512;
inline constexpr int k_quadrature = 4;
/// Pulses per revolution the board counts (2048).
inline constexpr int k_board_counts_per_rev = k_encoder_lines * k_quadrature;
static_assert(k_board_counts_per_rev == MCG_COUNTS_PER_REV, "mcg_protocol.h and the encoder disagree");
/// The board's encoder in mcg-csv(5)'s `encoder` metadata (a test checks it against the numbers above).
inline constexpr const char* k_board_encoder_text = "512 lines, x4 quadrature decoding = 2048 counts/rev";
/// The board's duty unit: 1/1000 of full scale.
inline constexpr double k_board_duty_full = MCG_DUTY_FULL;
/// The resistor the rig's load relay switches across the generator, ohm (the report's 5.6 ohm).
inline constexpr double k_load_resistor_ohm = 5.6;

/// The report's chain (Figure 17-1), in which its controllers are written: duty in PWM counts
/// (922 at 100 %), PWM logic level 5 V, H-bridge gain 4 (so the supply is 20 V), and the error
/// in encoder counts per 1 ms sample at 512 counts/rev (lines, without quadrature).
inline constexpr double k_pwm_full_counts = 922.0;
inline constexpr double k_pwm_logic_v = 5.0;
inline constexpr double k_hbridge_gain = 4.0;
/// H-bridge supply, V: duty 1 applies supply_V to the motor.
inline constexpr double k_supply_V = k_pwm_logic_v * k_hbridge_gain;
inline constexpr double k_report_counts_per_rev = k_encoder_lines;

/// The chain around a physical plant G(s) (omega in rad/s per V in volts):
/// duty counts --PWM--> logic volts --H-bridge--> motor volts --G--> rad/s --encoder--> counts/rad
/// --software conversion (counts over one period T)--> counts per sample.
struct LoopChain {
  double pwm_full_counts = k_pwm_full_counts;      ///< duty counts at 100 % duty
  double pwm_logic_v = k_pwm_logic_v;              ///< PWM output at 100 % duty, V (report: .00542 = 5/922 V per count)
  double hbridge_gain = k_hbridge_gain;            ///< V/V
  double counts_per_rev = k_report_counts_per_rev; ///< encoder counts per revolution (report: 81.5 = 512/2π per rad)
  double dt_s = k_tick_s;                          ///< sample period: counts are summed over one period

  double pwm_v_per_count() const { return pwm_logic_v / pwm_full_counts; }
  double counts_per_rad() const { return counts_per_rev / (2.0 * std::numbers::pi); }
  /// K = (V_logic/N_full)·K_hb·(N_rev/2π)·T: counts per sample per (rad/s) per duty count.
  double gain() const { return pwm_v_per_count() * hbridge_gain * counts_per_rad() * dt_s; }
  /// The controller's input scale: e (counts per sample) per rpm of error, N_rev·T/60 s.
  double input_scale() const { return counts_per_rev * dt_s / 60.0; }
};

}  // namespace mcg::boardunits
