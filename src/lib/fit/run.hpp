// The mcg-fit subcommands friction, tf and model: files in, INI or CSV out.
#pragma once

#include "fit/friction.hpp"
#include "fit/tf.hpp"

#include <iosfwd>
#include <limits>
#include <string>
#include <vector>

namespace mcg::fit {

/// Options of `mcg-fit friction`.
struct FrictionRunOptions {
  std::vector<std::string> config;  ///< --config files: R, Ke, Kt, J, supply and the base frictions
  std::vector<std::string> files;   ///< runs ("-" = stdin)
  FrictionOptions fit;
  /// The axis is linear (a ball screw, a belt): position in m, speed in m/s, drive force in
  /// N. The results are then forces (N, N s/m, kg) in [fit.friction] only: the rig's model
  /// sections hold rotary parameters.
  bool linear = false;
};

/// Writes the stacked frictions as INI ([motor], [generator], [clutch_disengaged],
/// [clutch_engaged]; each value with its standard error as a comment) and the evidence per
/// clutch state in [fit.friction] (with the inertia and offset when estimated; on a linear
/// axis only [fit.friction], in N, N s/m and kg).
void run_friction(const FrictionRunOptions& options, std::ostream& out);

/// Options of `mcg-fit tf`.
struct TfRunOptions {
  std::string file = "-";
  /// What the response maps (`v -> rpm`, `rpm/V`, ...) when its metadata does not say; given
  /// with metadata, the two must agree.
  std::string units;
  TfFitOptions fit;
  /// A time-domain run (a table with t and no f_hz): its input and output columns (empty: v,
  /// and rpm or else omega) and a held-out run scored with the fit (empty: none).
  std::string in_column;
  std::string out_column;
  std::string validate;
  bool band_given = false;  ///< --f-min, --f-max or --no-coherence was given (frequency data only)
};

/// Writes [plant] (tf in the syntax mcg-design reads, num/den in descending powers of s,
/// domain = s, maps = the response's units, delay_s when a delay was fitted) and [fit.tf] (gain, corners and
/// dampings with standard errors, RMS errors). Without --delay, a fit that leaves more than
/// k_tf_phase_warn_deg of phase RMS is refitted with a delay and with one more pole; if either halves the
/// phase residual, `err` gets a warning naming the command that fits better (sampled data lag: a zero-order
/// hold alone by half a sample period, a speed from counts over one period by another half). A time-domain
/// run (t, no f_hz) is fitted by fit_tf_time instead: [plant] as above, maps = "IN -> OUT" of the columns,
/// and in [fit.tf] the operating point, fit %, RMS and the held-out run's fit %; the leading rows skipped are
/// noted on `err`.
void run_tf(const TfRunOptions& options, std::ostream& out, std::ostream& err);

/// Options of `mcg-fit model`.
struct ModelRunOptions {
  std::vector<std::string> config;
  std::vector<std::string> files;
  std::vector<std::string> free;     ///< empty: default_free() of the runs
  std::vector<std::string> fix;      ///< "NAME=VALUE": measured values, never fitted
  std::vector<std::string> tie;      ///< "FOLLOWER=LEADER": the follower takes the leader's value
  std::vector<std::string> outputs;  ///< empty: every measured column present
  bool batch = false;                ///< one fit per file, one CSV row each
  bool list = false;                 ///< print the parameter names and stop
  bool evaluate = false;             ///< score the given model on the runs, no fit
  double from_s = -std::numeric_limits<double>::infinity();  ///< rows with t >= from_s ...
  double to_s = std::numeric_limits<double>::infinity();     ///< ... and t <= to_s of each run
  double gear_ratio = 1.0;           ///< motor turns per turn of the measured shaft
  unsigned threads = 0;              ///< 0: every core
  double max_step_s = 2.5e-4;        ///< integrator step bound during the fit
  int max_evaluations = 4000;
};

/// Joint fit: the fitted model as INI (every parameter, the free ones with their standard
/// errors as comments) plus [fit.model] (convergence, correlations, fit % per file, the
/// warnings of FitResult, each also on `err` as "mcg-fit: warning: ..."; converged = yes
/// only when FitResult::trustworthy()). Evaluate: [fit.evaluate] with fit % and RMS per
/// file and output of the model as given, no fit. Batch:
/// a CSV with one row per file (file index, each free parameter and its standard error,
/// fit % per output, converged, iterations), files fitted in parallel, rows in input order,
/// progress on `err` when it is a terminal. Returns the exit status: 0, or 3 when a fit did
/// not converge or is not trustworthy (the result is still written, marked converged =
/// 0/no, and `err` says why).
int run_model(const ModelRunOptions& options, std::ostream& out, std::ostream& err);

}  // namespace mcg::fit
