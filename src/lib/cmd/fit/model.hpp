// mcg-fit model: the grey-box fit of the nonlinear model to measured runs.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "cmd/command.hpp"
#include "fit/greybox.hpp"

namespace mcg::cmd {

/// Options of `mcg-fit model`.
struct FitModelOptions {
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
  /// Motor turns per turn of the measured shaft, over the captures' `# gear_ratio:` and the
  /// INI's `[measurement] gear_ratio` (unset: theirs, else 1).
  std::optional<double> gear_ratio;
  fit::DriveInput drive;                                     ///< --current, --torque: what drives the rig
  std::string position_column;                               ///< --position: speed from this position column
  unsigned threads = 0;                                      ///< 0: every core
  double max_step_s = 2.5e-4;                                ///< integrator step bound during the fit
  int max_evaluations = 4000;
  /// Stretches of the delete-one-stretch jackknife of the standard errors (a joint fit; 0: none).
  std::size_t jackknife = 10;
  /// --jacobian sensitivities: the solver's Jacobians by sensitivities (FitProblem::sensitivities).
  bool sensitivities = false;
};

/// Joint fit: the fitted model as INI (every parameter, the free ones with their standard
/// errors as comments) plus [fit.model] (convergence, correlations, fit % per file, the
/// warnings of FitResult, each also a warning on the diagnostics; converged = yes only when
/// FitResult::trustworthy()). Evaluate: [fit.evaluate] with fit % and RMS per file and output
/// of the model as given, no fit. Batch: a CSV with one row per file (file index, each free
/// parameter and its standard error, fit % per output, converged, iterations), files fitted in
/// parallel, rows in input order, progress when stderr is a terminal. A fit that did not
/// converge or is not trustworthy is still written, marked converged = 0/no, and reported as
/// an error of status k_untrustworthy_status; a batch file that cannot be read, of status 1.
/// --jacobian differences|sensitivities on a fitting subcommand; sets `sensitivities` for the latter.
void add_jacobian_option(CLI::App* app, bool& sensitivities);

class FitModel final : public Command {
 public:
  FitModelOptions options;
  std::string name() const override { return "model"; }
  std::string help() const override { return "grey-box fit of the nonlinear model to time series"; }
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

}  // namespace mcg::cmd
