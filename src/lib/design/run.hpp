// mcg-design: the tool's logic behind its subcommands (the main only parses options).
#pragma once

#include "design/design.hpp"

#include <cmath>
#include <iosfwd>
#include <string>
#include <vector>

namespace mcg::design {

/// Every option of every subcommand; NaN (or empty) means "not given".
struct Options {
  std::string command;  ///< p, pi, pid, lead, lag, rlocus-design, tune, margins, bode, nyquist, rlocus, step, c2d, loop
  std::vector<std::string> configs;

  // The plant: text, coefficient lists, or the INI's [plant]; the report's loop by default.
  std::string plant;
  bool plant_given = false;  ///< --plant was on the command line (even if empty)
  std::string num;
  std::string den;
  std::string domain;  ///< for --num/--den: "s" (default) or "z"
  std::string plant_units;  ///< what --plant maps (rpm/V, ..., loop): boardunits/plant_units.hpp
  double delay_s = NAN;
  double dt_s = NAN;
  std::string method;  ///< controller discretisation (tustin), c2d's method (zoh)
  double prewarp_rad_s = NAN;
  bool zoh = false;   ///< sample the continuous plant through a zero-order hold at dt
  bool loop = false;  ///< wrap the plant in the chain of the report's Figure 17-1

  // The rig model (model INI sections of --config) linearised at an operating point.
  bool rig = false;
  int clutch = -1;          ///< 0, 1, 2; -1: [plant] clutch or 2
  double speed_rpm = NAN;
  double r_load_ohm = NAN;  ///< NaN: [plant] r_load_ohm or open (inf)

  // The chain (PWM, H-bridge, encoder, software conversion).
  double pwm_full_counts = NAN;
  double pwm_logic_v = NAN;
  double hbridge_gain = NAN;
  double counts_per_rev = NAN;

  // A controller to analyse (analysis commands): text, or the INI's [controller].
  std::string controller;

  // Design targets.
  double pm_deg = NAN;
  double zero_rad_s = NAN;
  double wc_rad_s = NAN;
  double ti_over_td = 4.0;
  double n = 10.0;
  std::string pid_form = "filtered";  ///< pid: "filtered" (C(s) with N, discretised) or "board" (the board's form)
  double k_dc = NAN;
  double ratio = 10.0;
  double zeta = NAN;
  std::string structure = "pi";
  TuneLimits limits;

  // Series.
  double f_min_hz = NAN;
  double f_max_hz = NAN;
  int points = 0;
  double t_end_s = NAN;
  double k_max = NAN;
  bool metrics = false;
  bool open_loop = false;    ///< step: the series C·G as typed, no feedback
  std::string rise_pct;      ///< step: "LOW,HIGH" rise-time limits, % of the final value
  double settling_pct = NAN;  ///< step: settling band, % (2)
};

/// Runs one subcommand, writing INI (designs, margins, c2d, loop) or CSV (bode, nyquist,
/// rlocus, step) to `out`. Bad input throws mcg::Error naming the option or file and line.
void run(const Options& options, std::ostream& out);

}  // namespace mcg::design
