// Grey-box fit of the nonlinear rig model to measured time series (mcg-fit model), and the
// pieces other fits build on: reading a measured run, simulating the model the way the run
// was measured, residual series and the NRMSE fit percentage.
#pragma once

#include <algorithm>
#include <cstddef>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "config/ini.hpp"
#include "fit/nls.hpp"
#include "measurement/measurement.hpp"
#include "model/model.hpp"
#include "table/table.hpp"

namespace mcg::fit {

/// How `rpm` was measured: encoder counts over a trailing window (window_s, counts_per_rev).
using RpmEstimator = measurement::CountEstimator;

/// The run's encoder estimator (measurement::CountEstimator, from `# rpm_estimator:`) applied to a
/// simulated shaft angle theta(t) without the count quantisation:
///   rpm(t_n) = (theta(t_n) - theta(t_n - W)) / W * 60 / (2 pi),
/// theta interpolated linearly between samples and held at theta(t_0) before the start.
/// Quantising would make the fit's cost piecewise constant in the parameters (useless for
/// a Jacobian); the quantisation error is left to the residual as measurement noise.
std::vector<double> window_average_rpm(const std::vector<double>& t_s, const std::vector<double>& theta_rad,
                                       const measurement::CountEstimator& estimator);

/// Measured columns a fit can compare with the model.
/// rpm (rev/min), i (A), i_gen (A), v_gen (V), omega (rad/s).
const std::vector<std::string>& measurable_columns();

/// What drives the rig in a run, as `mcg-fit model`, `gap` and `friction` read it (--current,
/// --torque): the bridge voltage (v, or duty * supply_V) by default; else an ideal current
/// loop whose command is the run's `i` column, A (i_A = i, the circuit's drop not integrated);
/// else the drive torque itself from a column: N m at the measured shaft (N of force on a
/// linear axis), the motor's torque T = column / gear_ratio (rad per m on a linear axis).
struct DriveInput {
  bool current = false;       ///< `i` is the current loop's command, not a measured output
  std::string torque_column;  ///< the drive torque (force) column; empty: not torque-driven
  bool voltage() const { return !current && torque_column.empty(); }
};

/// One measured run: the inputs that drive the model and the measured outputs.
struct Run {
  std::string source;
  std::size_t first_line = 1;
  model::Inputs inputs;
  std::vector<std::string> outputs;             ///< measured columns compared, e.g. {"rpm", "i"}
  std::vector<std::vector<double>> measured;    ///< per output, one value per row (NaN = not measured)
  std::optional<RpmEstimator> rpm_estimator;    ///< from `# rpm_estimator:`, if present
  /// Motor shaft turns per turn of the shaft whose speed was measured (a gearbox between
  /// them): the measured rpm/omega = motor speed / gear_ratio.
  double gear_ratio = 1.0;
  /// The filter the measured speed passed (`# speed_filter:`), applied to the simulated speed.
  measurement::SpeedFilter speed_filter;
  /// What the capture's own metadata states (`# gear_ratio:`, `# speed_filter:`), so that
  /// apply_speed_path() can tell a capture's statement from the default.
  measurement::SpeedPath stated;
  /// A torque-driven run's torque column as logged (DriveInput): inputs.T_cmd_Nm is it over
  /// the gear ratio, set again whenever the ratio is settled.
  std::vector<double> drive_torque;
  std::string torque_column;  ///< its name (DriveInput::torque_column)
};

/// rad/s per unit of a run's measured output `name` (rpm: pi / 30, omega: 1), 0 for an output that
/// is not a speed; times Run::gear_ratio, the motor's.
double rad_s_per_unit(std::string_view name);

/// Settles how the run's speed was measured: `gear_override` (a command's --gear-ratio) wins;
/// else the capture's metadata; else the model INI's `[measurement]` (`ini`); else a ratio of 1
/// and no filter. A capture and an INI that state different values throw mcg::Error naming the
/// file and both values.
void apply_speed_path(Run& run, const measurement::SpeedPath& ini, std::optional<double> gear_override = {});

/// Builds a run from a table with columns t, v (or duty, then v = duty * supply_V; neither for a
/// current- or torque-driven `drive`, whose inputs are `i` or the torque column), clutch,
/// r_load (both optional: without them the run is the motor alone, clutch 0 and relay open)
/// and the measured `outputs` (empty: rpm, or omega when there is no rpm, and each of
/// i, i_gen, v_gen that is present and not constant, the generator's two only when the
/// clutch is not 0 throughout). `# gear_ratio:` and `# speed_filter:` (mcg-csv(5)) set the
/// run's gear ratio and speed filter. When the
/// `# i_measurement:` metadata (mcg-csv(5)) names the ADC range, current samples
/// at its rails (CurrentChain::at_rail) are saturated and count as not measured. Throws mcg::Error naming the
/// file (and line) for a missing column, a bad input value, or fewer than `min_rows` rows ("too short").
Run make_run(const table::Table& table, const std::vector<std::string>& outputs, const model::Params& params,
             std::size_t min_rows = 50, const DriveInput& drive = {});

/// The rows of `table` with from_s <= t <= to_s (a time range of a run: start-up rows
/// skipped, a window taken). Throws mcg::Error naming the file when no row is left.
table::Table select_time(const table::Table& table, double from_s, double to_s);

/// A table with a speed column `rpm`: as it is, or converted from `omega` (rad/s) when it has
/// no rpm, so that every consumer of measured speed accepts either.
table::Table with_rpm(table::Table table);

/// A table whose speed is measured as a position (`column`: rad, or m on a linear axis): its
/// central difference (one-sided at the ends) added as `omega` (rad/s; m/s), as mcg-fit friction,
/// model and gap read --position. `column` empty: the table as it is. Throws mcg::Error naming
/// the file for a missing or non-finite column, or a table that already has omega or rpm.
table::Table with_speed_from_position(table::Table table, const std::string& column);

/// The command that drives a run (DriveInput): the current loop's current (A), else the drive
/// torque as logged, else the bridge voltage (V); what a direction or a drive level is read from.
const std::vector<double>& drive_command(const Run& run);
/// What drives the run: the kind of drive_command(run).
model::DriveKind drive_kind(const Run& run);
/// How reports name drive_command(run): "v", "i" or the torque column.
std::string drive_name(const Run& run);

/// The command of `inputs` (what drive_command() reads off a run): the current loop's command
/// i_cmd_A (A), else the drive torque T_cmd_Nm (N m at the motor shaft), else v_V (V).
const std::vector<double>& drive_command(const model::Inputs& inputs);
/// The kind of drive_command(inputs).
model::DriveKind drive_kind(const model::Inputs& inputs);

/// A current or torque command's change between two rows counts as a jump only beyond this
/// multiple of its 90th-percentile row-to-row change: a logged reading's noise, or a feedback
/// controller's work, moves it every row; a step of the command moves it far more.
inline constexpr double k_jump_over_typical = 10.0;

/// The change of a drive command between two rows that counts as a jump (an input event), in
/// the command's unit: `jump_V` on a voltage drive; on a current or torque drive, whose size no
/// volt describes, the larger of `share` of the command's largest magnitude and
/// k_jump_over_typical times the 90th percentile of its row-to-row changes (finite rows only):
///   jump = max(share max|u|, 10 q90(|u(n) - u(n-1)|)).
double drive_jump(std::span<const double> command, model::DriveKind kind, double jump_V, double share);

/// Pins parameters at measured values: each "NAME=VALUE" (names as model::parameters()
/// spells them) is set in `model`; returns the names. Throws mcg::Error "--fix: ..." for a
/// malformed item, an unknown name or a value the INI form refuses (model::parameter_problem).
std::vector<std::string> fix_parameters(model::Model& model, const std::vector<std::string>& items);

/// Simulates `model` on the run's inputs and returns, per output of the run, the series as
/// it was measured (rpm through the run's estimator when it has one).
std::vector<std::vector<double>> simulate_as_measured(const model::Model& model, const Run& run,
                                                      const model::SimOptions& options = {});

/// |y - mean(y)| over the finite samples of y: the spread a fit divides a measured channel's
/// residuals by (0 when fewer than two samples are finite, or all are equal).
double deviation_norm(const std::vector<double>& y);

/// MATLAB compare's fit: 100 (1 - |y - y_sim| / |y - mean(y)|) over the finite samples of y.
/// -inf when y is constant and y_sim differs from it, 100 when both agree.
double fit_percent(const std::vector<double>& measured, const std::vector<double>& simulated);

/// RMS over the finite values of `x` (NaN when there are none).
double rms_finite(std::span<const double> x);

/// The residual series of one run under a model: measured - simulated, per output.
struct RunResiduals {
  std::vector<std::string> outputs;
  std::vector<std::vector<double>> simulated;
  std::vector<std::vector<double>> residual;
  std::vector<double> fit_percent;  ///< per output
};
RunResiduals residuals(const model::Model& model, const Run& run, const model::SimOptions& options = {});

/// A grey-box identification problem: the model (initial values of the free parameters,
/// values of everything else), the runs fitted jointly, and the names of the free
/// parameters as model::parameters() spells them ("motor.R_ohm", "clutch_engaged.Tc_Nm").
struct FitProblem {
  model::Model model;
  std::vector<Run> runs;
  std::vector<std::string> free;
  NlsOptions nls;
  model::SimOptions sim;
  /// Parameters tied to a free one, {follower, leader}: the follower takes the leader's
  /// value (Ke = Kt in SI units: one constant of the machine).
  std::vector<std::pair<std::string, std::string>> ties;
  /// Bounds that replace model::parameters()' (relative to the given model) for a name.
  std::map<std::string, std::pair<double, double>> bounds;
  /// Contiguous stretches of the runs the delete-one-stretch jackknife leaves out in turn
  /// (FitResult::se_jackknife); 0: no jackknife (each stretch costs a refit).
  std::size_t jackknife_stretches = 0;
  /// The jackknife by one Gauss-Newton step per stretch left out, from the optimum on the fit's
  /// own Jacobian, instead of a refit: the same spread to first order, at no simulation, also
  /// for a fit that spent its budget. A search that fits many candidates takes it.
  bool jackknife_linearised = false;
  /// Simulate the runs once more at the optimum for FitResult::runs (a caller that only needs
  /// the model and its statistics saves that simulation).
  bool evaluate_runs = true;
  /// The solver's Jacobians by sensitivities along the simulation (model/sensitivity.hpp)
  /// rather than by finite differences, where the model has them (NlsOptions::sensitivities).
  bool sensitivities = false;
  /// How the residuals simulate run `run` (an index into runs) of a model: when set, instead
  /// of simulate_as_measured(model, runs[run], options), whose numbers it must return (the gap
  /// search looks up a model it simulated before). Called concurrently.
  std::function<std::vector<std::vector<double>>(const model::Model& model, std::size_t run,
                                                 const model::SimOptions& options)>
      simulate;
};

/// The constant bias of a drive, N m at the motor shaft (N on a linear axis): the part of the
/// logged drive torque (or of Kt times a current command or reading) that does not act on the
/// shaft, T_acting = T_logged - bias; a constant load (gravity on an axis) reads the same. It is
/// friction_asymmetry's dT_Nm, whose equation is exactly this constant torque -dT on the shaft,
/// and the `offset` a friction fit estimates (tau = J dw/dt + F(w) + offset), sign included.
inline constexpr std::string_view k_drive_offset = "friction_asymmetry.dT_Nm";

/// Adds to `model` each catalog effect that a name of `free` ("EFFECT.key") belongs to and the
/// model lacks, with its defaults; a signed parameter (lower bound below 0) of it starts at 0,
/// the effect absent in all but name. Unknown names are left for fit_model() to refuse.
void add_free_effects(model::Model& model, const std::vector<std::string>& free);

/// The [bounds] section of an INI: "NAME = LOWER UPPER" per parameter name as
/// model::parameters() spells it (or any catalog effect's "EFFECT.key"). Throws mcg::Error naming the file
/// and line for an unknown name, not two numbers, or lower >= upper.
std::map<std::string, std::pair<double, double>> read_bounds(const config::Ini& ini,
                                                             const model::Model& model);

/// The parameters a fit frees by default, chosen from what the runs excite:
///   a measured current: J, R, Kt, Ke and Tc of the motor (the current separates R from Kt);
///   speed only: J, Kt and Tc with Ke tied to Kt (speed alone fixes only the ratios R/Kt and
///   J R/(Kt Ke): freeing R and Kt together is degenerate, so R stays at its given value);
///   a current- or torque-driven run (DriveInput): J, Tc and the viscous visc1 (Kt would
///   only scale J and the friction, and no back-EMF damps the shaft); the drive's constant
///   bias k_drive_offset only when asked for (add_free_effects() brings its effect in).
/// Names in `fixed` are left out. `ties` receives the ties the set needs.
std::vector<std::string> default_free(const std::vector<Run>& runs, const std::vector<std::string>& fixed,
                                      std::vector<std::pair<std::string, std::string>>& ties);

/// Per-run quality of a fit.
struct RunFit {
  std::string source;
  std::vector<std::string> outputs;
  std::vector<double> fit_percent;  ///< per output, NRMSE as fit_percent() defines it
  std::vector<double> rms;          ///< per output, RMS of measured - simulated, output units
};

/// One finding of the honest-numbers checks (FitResult::warnings says it in words).
struct FitFlag {
  enum class Kind {
    at_bound,      ///< the value sits at (within k_at_bound of) a bound of its range
    undetermined,  ///< infinite standard error, or one beyond half its range: the data do not determine it
    too_precise,   ///< a standard error too small to be true (the residual is not smooth in it)
    correlated,    ///< two parameters correlated beyond k_max_correlation
    impossible,    ///< a physically impossible value (negative viscous, inertia, resistance, ...)
  } kind;
  std::vector<std::string> names;  ///< the parameters involved (two for `correlated`)
  /// For `at_bound`: the bound the value sits at (NaN for the other kinds).
  double bound = std::numeric_limits<double>::quiet_NaN();
  /// The data do not determine the parameters (every kind but at_bound): a fit carrying such a
  /// flag cannot stand as a result.
  bool undetermined() const { return kind != Kind::at_bound; }
};

/// A parameter a fit was asked to free but that the runs do not set, held at a value and refitted
/// without it, the way a measured parameter is held (--fix): printed as pinned, not as a number
/// with an infinite or meaningless standard error.
struct PinnedParameter {
  std::string name;
  double value = 0.0;
  std::string why;  ///< k_pinned_given, k_pinned_bound or k_pinned_left
};

/// Why a parameter is pinned: an infinite standard error (the runs leave it where it started)...
inline constexpr std::string_view k_pinned_given = "pinned at the given value: not set by these runs";
/// ... or a value the fit drove to a lower bound of 0 that is physical (a resistance, a friction
/// level, a dead band, a delay cannot be negative): in log coordinates it only nears 0 by orders of
/// magnitude (R_on = 1e-15 +- inf), so the number printed would be the solver's, not the data's.
inline constexpr std::string_view k_pinned_bound = "pinned at its bound: the fit drove it there";
/// ... or, with an infinite error where the given value would cost fit (a static level anywhere
/// below the Coulomb level acts alike, but not above it), the value the fit left it at.
inline constexpr std::string_view k_pinned_left = "pinned at the value the fit left: not set by these runs";

/// FitResult::se_widening of `residuals` laid out as a fit of `runs` lays them out (run by run,
/// output by output, sample by sample): sqrt((1 + rho) / (1 - rho)), rho the lag-1
/// autocorrelation within each (run, output) block, pooled, clamped to [0, 0.9999].
double ar1_widening(const Eigen::VectorXd& residuals, const std::vector<Run>& runs);

/// "NAME = VALUE why": how the reports say a pin (six significant digits, never -0).
std::string pinned_text(const PinnedParameter& pin);

/// The parameters the runs do not set, each with the value it is pinned at: one `flags` put at a
/// lower bound of 0 (FitFlag::bound) at 0; one without a finite standard error (`undetermined`,
/// or at another bound it drifted to with an infinite error in `std_errors`, per name of
/// `names`) at `given(name)`, unless that has no value (then it stays free and flagged). The
/// caller pins nothing on a fit the time budget cut short (its errors are missing, not infinite).
std::vector<PinnedParameter> undetermined_pins(
    const std::vector<FitFlag>& flags, const std::vector<std::string>& names,
    const std::vector<double>& std_errors,
    const std::function<std::optional<double>(const std::string&)>& given);

/// The outcome: the fitted model (free parameters replaced) and the solver's statistics
/// (nls.names = free parameter names, values, std_errors, correlation, converged, reason,
/// iterations, evaluations).
struct FitResult {
  model::Model model;
  NlsResult nls;
  std::vector<RunFit> runs;
  /// What makes the numbers untrustworthy, one sentence each: a parameter at a bound, a
  /// correlation beyond k_max_correlation, a standard error that is infinite or too small to
  /// be true (the residual is not smooth in the parameter: it sits on a discontinuity of the
  /// data, e.g. a static friction level at a breakaway), a physically impossible value.
  std::vector<std::string> warnings;
  /// The same findings, one per warning (same order), for code that decides on them.
  std::vector<FitFlag> flags;
  /// Free parameters the runs did not set, held and refitted without (fit_model_pinned()); the
  /// solver's statistics (nls) are those of the refit, which no longer names them.
  std::vector<PinnedParameter> pinned;
  /// The solver met a convergence test and nothing above was found.
  bool trustworthy() const { return nls.converged && warnings.empty(); }
  /// Factor the solver's standard errors are widened by in the reports of mcg-fit model: a
  /// simulation error is strongly autocorrelated, so the samples are far fewer independent
  /// errors than rows. With rho the lag-1 autocorrelation of the residuals (pooled over the
  /// runs and outputs), the AR(1) variance inflation sqrt((1 + rho) / (1 - rho)) (1 for
  /// white residuals).
  double se_widening = 1.0;
  /// nls.std_errors times se_widening.
  double widened_se(std::size_t k) const {
    return se_widening * nls.std_errors[static_cast<Eigen::Index>(k)];
  }
  /// Per free parameter, the delete-one-stretch jackknife's standard error (empty when
  /// FitProblem::jackknife_stretches is 0 or a refit failed): the fit repeated with each of g
  /// contiguous stretches of the runs left out of the residual (still simulated through),
  /// se^2 = (g - 1) / g sum_i (p_(i) - mean)^2. A stretch's samples err together (the simulation
  /// error is autocorrelated), which the Jacobian's error, taking the samples as independent,
  /// does not see; leaving out whole stretches does, and it needs no model of the correlation.
  std::vector<double> se_jackknife;
  std::size_t jackknife_stretches = 0;  ///< g, the stretches the jackknife used
  /// The standard error the reports state: the larger of the jackknife's (when there is one)
  /// and the widened Jacobian's (widened_se), as a friction fit takes the larger of its two:
  /// neither sees a bias the model's own error leaves, and each misses what the other sees.
  double reported_se(std::size_t k) const {
    return k < se_jackknife.size() ? std::max(se_jackknife[k], widened_se(k)) : widened_se(k);
  }
};

/// |correlation| beyond which two parameters are reported as not told apart by the data.
inline constexpr double k_max_correlation = 0.99;
/// A parameter within this fraction of its range (log range for positive ones) of a bound is at it.
inline constexpr double k_at_bound = 1e-3;
/// ... or within this fraction of it when the bound lies less than k_bound_within_se of a
/// standard error away (in the same coordinates): a J_scale of 0.5009 +- 0.14 is at its 0.5.
inline constexpr double k_near_bound = 1e-2;
inline constexpr double k_bound_within_se = 0.1;

enum class BoundSide { none, lower, upper };
/// Which bound of [lo, hi] a fitted value v of standard error se is at (FitFlag::Kind::at_bound):
/// within k_at_bound of the range (in log coordinates for a positive range), or pressed
/// against it as above; a positive value bounded by 0 only when it is 0 in all but name
/// (1e-6 of its log range) and its standard error is at least its size.
BoundSide bound_reached(double v, double se, double lo, double hi);

/// The runs' fit % and RMS under `model` without fitting (an evaluate-only score).
std::vector<RunFit> evaluate_model(const model::Model& model, const std::vector<Run>& runs,
                                   const model::SimOptions& options = {});

/// Minimises the simulation error. The residual vector stacks, for every run and output,
///   r = (y_sim - y) / (std(y) sqrt(N_finite)),
/// so each (run, output) weighs like its squared NRMSE (1 - fit/100)^2 and the cost is
/// independent of units and lengths. Parameters whose lower bound is >= 0 are
/// log-parameterised (kept positive); the others move linearly. Never returns the initial
/// guess silently: result.nls.converged says whether a convergence test was met.
/// Throws mcg::Error for an unknown parameter name, a parameter listed twice, a free
/// parameter whose initial value is outside its bounds, or runs with no excitation of the
/// outputs (a constant measured series).
FitResult fit_model(const FitProblem& problem);

/// True when `held` (a refit with some parameters pinned) fits no worse than `free` by more than
/// one standard error's worth of cost (as a profile likelihood counts it: cost / M for M residuals,
/// times the AR(1) widening squared). A parameter with an infinite error may still act away from
/// where the fit left it (a static level below every start's drive, that sticks at the given
/// value): then the runs do set it, and it is not pinned.
bool pin_costs_nothing(const FitResult& free, const FitResult& held);

/// Given `first`, a fit_model() of `problem`: each free parameter undetermined_pins() finds in it
/// pinned (at `given(name)`, or at its bound 0) and the rest refitted once without them, from
/// where `first` left them; the result lists them in FitResult::pinned. `first` as it came when
/// nothing is pinned, every parameter would be, the budget stopped it, or the pins cost
/// (pin_costs_nothing()).
FitResult pin_undetermined(const FitProblem& problem, FitResult first,
                           const std::function<std::optional<double>(const std::string&)>& given);

/// pin_undetermined() of fit_model(problem), each parameter given at its value in problem.model.
FitResult fit_model_pinned(const FitProblem& problem);

}  // namespace mcg::fit
