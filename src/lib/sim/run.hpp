// mcg-sim: the rig simulated on a table of inputs (see man/mcg-sim.1).
#pragma once

#include <cstdint>
#include <iosfwd>
#include <limits>
#include <string>
#include <vector>

#include "boardunits/chain.hpp"  // k_board_counts_per_rev
#include "common/diagnostics.hpp"

namespace mcg::sim {

struct RunOptions {
  std::vector<std::string> configs;   ///< INI files (model parameters, effects, [controller])
  std::vector<std::string> effects;   ///< "NAME:key=value,..."
  int clutch = 2;                     ///< when the input has no 'clutch' column
  double r_load_ohm = std::numeric_limits<double>::infinity();   ///< when it has no 'r_load' column
  bool encoder = false;               ///< rpm as the board measures it; true speed in rpm_true
  double window_s = 0.005;            ///< encoder count window
  double counts_per_rev = boardunits::k_board_counts_per_rev;  ///< 512 lines, x4 quadrature
  bool open_loop = false;             ///< ignore an 'rpm_cmd' column, drive with v/duty
  /// The closed loop's controller: "board" (the firmware's core on the board's registers, as the
  /// emulated board runs it) or "equation" (the [controller] difference equation in double).
  std::string loop = "board";
  double noise_i_A = 0.0;             ///< Gaussian noise on i, standard deviation
  double noise_v_gen_V = 0.0;         ///< Gaussian noise on v_gen, standard deviation
  bool adc = false;                   ///< i through the board's 10-bit ADC (1 ohm shunt, 2.5 V offset)
  std::uint64_t seed = 1;
  double max_step_s = 1e-3;           ///< largest integration step (see model::SimOptions)
  /// The input is a measured run (a capture): its rpm (and i) stay beside the model's as
  /// rpm_measured (i_measured), with rpm_residual = rpm_measured - rpm (i_residual) and the
  /// running RMS of the residual in the row's regime; the per-regime RMS goes to `report` at
  /// the end. The model's rpm goes through the capture's own rpm_estimator when it states one.
  bool compare = false;
  /// The tool that runs the simulation, for the output's `source` metadata ("mcg-sim").
  std::string tool;
};

/// Reads the input table from `in` (named `source` in messages), simulates, writes the
/// output table to `out`, row by row: each output row is written as soon as its input row is
/// in, in memory that does not grow with the run. When `in` reads through an FdInput, the
/// output is flushed whenever the input pauses (a live pipe sees each row at once). Throws
/// mcg::Error for bad input, after writing the rows before it. With --compare, the RMS of the
/// residuals per regime goes to `diag` (when given) as report lines at the end.
void run(const RunOptions& options, std::istream& in, const std::string& source, std::ostream& out,
         Diagnostics* diag = nullptr);

/// run() on the standard input and output, live.
void run_stdio(const RunOptions& options, Diagnostics& diag);

}  // namespace mcg::sim
