// mcg-fit gap: the sim-to-real gap diagnosis. Where the model misses the measured runs,
// which unmodelled physical effect of the catalog explains it, and how far the gap shrinks
// on held-out data once that effect is added and refitted.
//
// Method (every fit is fit_model(), the grey-box Levenberg-Marquardt fit):
//   before          the model as given, simulated on the validation runs the way they were
//                   measured (rpm through the runs' `# rpm_estimator:`)
//   param_mismatch  the nominal parameters refitted on the training runs through the scale
//                   factors of the param_mismatch effect (Kt, J, Coulomb, static, viscous, R)
//   EFFECT          the refitted model plus one catalog effect, its parameters started from
//                   the best point of a coarse grid (on the refit and on the model as
//                   given), fitted alone, then refitted jointly with the nominal scales
//                   (only alone when the model as given misses by no more than the noise)
//   A+B, A+B+C      mixtures by forward selection: the best significant effect extended by
//                   one effect at a time from the best singles, refitted jointly; an
//                   extension joins when it is significant against the model it extends
// The refit is repeated from any effect fit's nominal scales that fit the training runs
// better, so that an effect never wins merely by a better nominal start.
// Each candidate is scored on the validation runs only, with the residual of every output
// normalised by its noise floor:
//   score = sum_outputs mean(r^2) / floor^2        (about 1 per output for a perfect model)
// and ranked by Akaike's final prediction error FPE = score (N + k) / (N - k) (k free
// parameters, N validation samples). A candidate is significant against a reference when
//   score_ref - score > max(k_abs, k_rel (score_ref - outputs))
// i.e. it removes a clear part of the gap above the noise that the reference leaves.
// The diagnosis: `none` unless the model as given misses by more than the noise allows;
// the largest accepted mixture, else the best significant effect over the refit; else `param_mismatch` if the
// refit alone is significant. That choice is accepted only when it explains the gap: its score is near the
// noise or it removes a stated share of the excess (k_gap_near_noise, k_gap_explained_share); otherwise, and
// when nothing is significant, `unexplained`, with the best candidate's residual analysed to say where what
// is left lies; but `none` when the excess is small and no candidate predicts the validation runs any better
// (k_gap_small_excess).
#pragma once

#include "common/diagnostics.hpp"
#include "fit/diag_residual.hpp"
#include "fit/greybox.hpp"
#include "model/model.hpp"

#include <chrono>
#include <functional>
#include <iosfwd>
#include <map>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mcg::fit {

/// A candidate must lower the validation score by at least this much (in noise units)...
inline constexpr double k_gap_abs_threshold = 0.25;
/// ... and by at least this fraction of the gap its reference leaves above the noise.
inline constexpr double k_gap_rel_threshold = 0.2;
/// A significant candidate is accepted as the explanation only when its validation score
/// is near the noise, score <= (1 + k_gap_near_noise) outputs (an RMS within about 22 % of
/// the floor per output), ...
inline constexpr double k_gap_near_noise = 0.5;
/// A model as given whose score is within (1 + this) outputs (an RMS within about 41 % of the
/// floor per output) and that no candidate, not even the refit of its nominal parameters,
/// predicts the validation runs better than, is `none`: the small excess is not a missing
/// effect (noise beyond the floor, a quantisation or timing the floor leaves out).
inline constexpr double k_gap_small_excess = 1.0;
/// ... or it removes at least this share of the score above the noise that the model as
/// given leaves (three quarters of the squared excess: half of its RMS). Otherwise the
/// verdict is `unexplained`.
inline constexpr double k_gap_explained_share = 0.75;
/// The data's own noise estimate replaces the stated measurement chain when it exceeds it
/// by more than this factor (the second-difference estimate carries some of a fast
/// excitation's signal, so a smaller excess is not trusted over the chain).
inline constexpr double k_gap_data_floor_factor = 2.0;

/// A correlated pair leaves a parameter undetermined when its standard error exceeds this
/// share of its value.
inline constexpr double k_gap_max_relative_error = 0.5;
/// A nominal scale the diagnosis leaves at a bound of its default range (J_scale 0.5 to 2: a
/// datasheet's rotor without the wheel it drives), with an error that determines it, is refitted
/// within that range widened by this factor each way (0.125 to 8), unless [bounds] names it.
inline constexpr double k_gap_scale_widening = 4.0;
/// Stretches of the linearised jackknife every candidate's standard errors take where it is
/// wider than the Jacobian's (FitProblem::jackknife_linearised).
inline constexpr std::size_t k_gap_jackknife_stretches = 10;

/// Most effects named together (A+B+C).
inline constexpr std::size_t k_gap_max_mixture = 3;

/// How the diagnosis runs.
struct GapSettings {
  unsigned threads = 0;                ///< threads of the diagnosis' one pool; 0 = all cores
  std::size_t pool_effects = 4;        ///< mixtures are formed from this many best single effects
  /// Simulation budget per candidate fit; 0 = by size. It counts the solver's evaluations: one
  /// the search's memo looks up (gap_detail::SimulationMemo) simulates nothing but is counted,
  /// so a fit stops where it would without the memo.
  int max_evaluations = 0;
  /// Nominal parameters pinned at measured values (--fix): the refit leaves the scale that
  /// would move them at 1 (motor.R_ohm: R_scale, motor.J_kg_m2: J_scale, Kt/Ke: Kt_scale,
  /// Tc: coulomb_scale, Ts: static_scale, visc*: viscous_scale).
  std::vector<std::string> fixed;
  std::vector<std::string> excluded;   ///< catalog effects not tried as candidates (--exclude)
  std::map<std::string, std::pair<double, double>> bounds;  ///< [bounds] of the INI
  std::function<void(const std::string&)> progress;  ///< progress lines (none when empty)
  bool discrepancy = false;            ///< fit the discrepancy whatever the verdict
  bool sensitivities = false;          ///< the fits' Jacobians by sensitivities (FitProblem::sensitivities)
  /// Reject a mixture whose added effect, fitted alone on the model it extends, removes almost
  /// nothing of its training cost before the joint refit (false: every one is refitted jointly).
  bool early_rejection = true;
  /// When the time budget runs out: fits under way stop at their next iteration, candidates
  /// not started are reported as not fitted, and the report is marked partial.
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
};

/// One measured validation run prepared for scoring: rows before `first_scored` only bring
/// the simulation to its state (their measured values are not scored).
struct ScoredRun {
  Run run;
  std::size_t first_scored = 0;
  /// The current measurement chain from `# i_measurement:` ("1 ohm shunt, 10-bit ADC over
  /// 0-5 V ..., noise sigma 0.003 A"): ADC step in A and noise sigma in A, NaN when not stated.
  double i_step_A = std::numeric_limits<double>::quiet_NaN();
  double i_sigma_A = std::numeric_limits<double>::quiet_NaN();
};

/// The unit the reports give speeds in: the data's own. The runs hold every speed in rpm
/// (with_rpm); a report multiplies by `per_rpm` (1 for rpm, pi/30 for rad/s).
struct SpeedUnit {
  std::string name = "rpm";    ///< as printed: "rpm", "rad/s"
  std::string key = "rpm";     ///< in column and metadata names: "rpm", "rad_s"
  std::string column = "rpm";  ///< the measured column it came from: "rpm", "omega"
  double per_rpm = 1.0;
};

/// The prepared data: training runs, validation runs, and how they were obtained.
struct GapData {
  std::vector<Run> train;
  std::vector<ScoredRun> validate;
  std::string split_note;  ///< empty unless a single file was split
  SpeedUnit speed_unit;    ///< the data's own, for the reports
};

/// An automatic split's training rows must hold, in each direction the scored rows drive, a
/// drive level at least this share of the largest the scored rows hold.
inline constexpr double k_split_level_share = 0.5;

/// Builds the training and validation sets from tables. With no validation table and one
/// training table, that table is split at the event (clutch or relay change, jump > 1 V)
/// nearest to split_fraction of its duration, within 40-80 %, else at split_fraction itself:
/// the rows before train; the whole file is simulated for validation but only the rows
/// after the split are scored. Unless the split was given (`split_given`: --split), training
/// must cover what is scored: every direction the scored rows drive and the motor turns, and
/// in each, a drive level of at least k_split_level_share of the scored rows' largest; when
/// that split does not, the nearest one in 40-80 % that does is taken (other events first,
/// then every 5 % of the duration), and when none does it throws, asking for --split or
/// --validate runs. A given split that does not cover says so in the split note.
/// Outputs compared: rpm and i where measured. Current samples at the ADC rails (from
/// `# i_measurement: ... range A..B A`) are dropped as not measured.
GapData prepare_gap_data(const std::vector<table::Table>& train, const std::vector<table::Table>& validate,
                         const model::Params& params, double split_fraction, bool split_given = false,
                         const DriveInput& drive = {});

/// Per validation output: the measured series (scored rows only, NaN elsewhere) and the
/// noise floor of its measurement chain.
struct OutputFloor {
  std::string output;       ///< "rpm" or "i"
  NoiseFloor noise;
  /// used for the score: the chain value when stated, unless the data's own estimate exceeds
  /// it by more than k_gap_data_floor_factor (then, and when no chain is stated, the data's)
  double floor = 0.0;
};

/// One candidate and its validation result.
struct GapCandidate {
  std::string name;                   ///< "none", "unexplained", "param_mismatch", "stribeck", "stribeck+dead_time"
  std::vector<std::string> effects;   ///< catalog effects added (param_mismatch excluded)
  std::string status;                 ///< "as given", "fitted", "not converged", "not excited: ..."
  model::Model model;                 ///< the fitted model
  std::vector<std::string> free;      ///< fitted parameter names
  /// Breakaway keys held at 0, not free: no start from rest in the training runs sets them.
  std::vector<std::string> unexcited;
  std::vector<double> values;
  std::vector<double> std_errors;
  std::size_t added_parameters = 0;   ///< parameters of the added effects
  double score = 0.0;                 ///< validation score (see top of file)
  double fpe = 0.0;                   ///< final prediction error, the ranking key
  std::vector<double> rms;            ///< validation RMS per output (order of GapReport::floors)
  double train_rms_rpm = 0.0;
  bool significant = false;
  bool evaluated = false;             ///< false when skipped (not excited)
  bool converged = true;              ///< its fit converged (false: the budget was spent first)
  /// The fit's honest-numbers findings (FitResult::warnings and ::flags): a parameter at a
  /// bound, not determined, with a standard error too small to be true, correlated beyond
  /// k_max_correlation with another, or physically impossible.
  std::vector<std::string> warnings;
  std::vector<FitFlag> flags;
  /// Parameters of the diagnosis' fit that the runs do not set, held once the verdict is drawn
  /// (pin_diagnosis()) and the rest refitted without them: not in `free`, printed as pinned.
  std::vector<PinnedParameter> pinned;
  /// False when the data do not determine what the candidate claims: a physically impossible
  /// value anywhere; on a parameter of an added effect, an infinite or too small standard
  /// error; a correlation beyond k_max_correlation that involves an added effect's parameter
  /// and leaves one of the pair with a standard error above k_gap_max_relative_error of its
  /// value (a correlated pair whose errors are both small is determined all the same: the
  /// errors already carry the correlation). Such a candidate is never significant, so it
  /// cannot be the diagnosis. Nominal scales correlated only among themselves (Coulomb,
  /// static and viscous on runs that do not separate them) are flagged on the row but
  /// disqualify nothing: the refit beside an effect is a nuisance, not the finding.
  bool determined() const;
};

/// One term of the catalog-free discrepancy fit (fit/discrepancy.hpp).
struct DiscrepancyTerm {
  std::string equation;      ///< "+0.00112 N m * sign(w)"
  std::string basis;         ///< "sign(w)"
  double coefficient = 0.0;  ///< in the unit of `unit`
  double std_error = 0.0;
  std::string unit;          ///< "N m", "N m s/rad", "kg m^2"
  std::string reading;       ///< what it is physically: "once per revolution: an imbalance, ..."
  double order = 0.0;        ///< cycles per revolution of an angle harmonic, else 0
  double phase_rad = 0.0;    ///< its phase (coefficient = amplitude), with its standard error
  double phase_se_rad = 0.0;
  /// Where it acts: "shaft" (a torque), "circuit" (a voltage in the armature circuit), "current
  /// reading" or "speed reading" (an error of the measured channel, not of the machine).
  std::string place = "shaft";
  /// What it does, whatever its text: the catalog effects whose plans name the shape start from it.
  model::TermShape shape = model::TermShape::none;
};

/// A catalog effect started from a discrepancy term's values, fitted and scored.
struct DiscrepancySeed {
  std::string effect;    ///< format_effect() of the fitted effect
  double rms_rpm = 0.0;  ///< validation speed RMS of the model with it (and the other terms)
  bool closes = false;   ///< it explains the gap (the decision's acceptance rule)
};

struct DiscrepancyResult {
  std::vector<DiscrepancyTerm> terms;  ///< the survivors, largest share first
  std::size_t library_size = 0;
  std::size_t train_windows = 0;
  std::size_t validation_windows = 0;
  /// Share of the torque residual the terms explain, %, 1 - ||y - Phi xi||^2 / ||y||^2.
  double train_explained_pct = 0.0;
  double validation_explained_pct = 0.0;
  /// The reference model with the terms, simulated on the validation runs.
  model::Model model;
  double rms_before_rpm = 0.0;   ///< validation speed RMS of the reference model
  double rms_after_rpm = 0.0;    ///< ... and with the terms
  double floor_rpm = 0.0;
  std::string note;              ///< why nothing was fitted, when `terms` is empty
  std::vector<std::string> dropped;    ///< terms selected but left out: the held-out runs did not gain
  std::vector<DiscrepancySeed> seeds;  ///< catalog effects seeded from the terms
  /// The joint refit of the shaft terms with the nominal scales: what it gave on the held-out runs.
  std::string joint;
  /// Beside the shaft, each in its own domain (NaN when nothing was kept there): the share of
  /// the armature circuit's voltage residual the circuit and current-reading terms explain on
  /// the validation runs, %, and the share of the validation torque residual that taking the
  /// current reading's errors out of the measured current removes, %.
  double circuit_validation_pct = std::numeric_limits<double>::quiet_NaN();
  double reading_torque_pct = std::numeric_limits<double>::quiet_NaN();
};

/// The diagnosis.
struct GapReport {
  std::string source;  ///< its outputs' `source` metadata ("mcg-fit gap"; none when empty)
  std::string split_note;
  SpeedUnit speed_unit;  ///< every speed reported (floors, RMS, regimes, series) is in it
  std::vector<OutputFloor> floors;
  std::size_t validation_samples = 0;
  std::vector<GapCandidate> candidates;  ///< diagnosis first, then the rest best first
  std::string diagnosis;                 ///< = candidates.front().name
  bool partial = false;                  ///< the time budget ran out before every candidate was fitted
  std::string reason;                    ///< one sentence: why this diagnosis
  /// The catalog-free discrepancy fit: for an unexplained gap, and on request (--discrepancy).
  std::optional<DiscrepancyResult> discrepancy;
  /// Where the gap lies before and after (the diagnosis' model), pooled over validation runs.
  std::vector<RegimeStat> regimes_before, regimes_after;
  std::vector<RegimeStat> bands_before, bands_after;
  std::vector<RegimeStat> current_regimes_before, current_regimes_after;
  Whiteness white_before, white_after;
  /// The drive's input the residual is checked for independence of (drive_name: "v", "i", the
  /// torque column).
  std::string drive_input = "v";
  /// Per validation run and output: simulated series of the model as given and of the diagnosis.
  std::vector<std::vector<std::vector<double>>> simulated_before, simulated_after;
};

/// Highest order of the motor angle searched, cycles per revolution.
inline constexpr std::size_t k_max_angle_order = 100;

/// Fewest samples that must show an order of the motor angle for it to be searched.
inline constexpr std::size_t k_min_order_samples = 32;

/// Cycles per revolution of the motor shaft of the strongest position-periodic components of
/// the speed residual (measured minus `model`, rpm or omega) over the runs: the periodogram
/// P(N) = |sum_n r_n exp(-i N theta_n)|^2 / n(N), theta the motor angle (the integral of the
/// measured speed times the gear ratio), N = 2..k_max_angle_order. A sample shows order N only
/// where the ripple moves less than pi between samples, N |w| dt < pi with w the motor's
/// measured speed: faster, the sampled speed aliases it or (counted over the sample) averages it
/// out. An order shown by fewer than k_min_order_samples samples is not searched, so on a
/// gearmotor logged at 100 Hz most orders are not. Returns the `keep` strongest N, strongest
/// first; none when no order is shown.
std::vector<double> angle_orders(const model::Model& model, const std::vector<Run>& runs, std::size_t keep);

/// Runs the diagnosis of `model` on `data`.
GapReport diagnose_gap(const model::Model& model, const GapData& data, const GapSettings& settings);

/// The CSV result, one row per candidate, diagnosis first: effect, rms_before_rpm,
/// rms_after_rpm, shrink_pct, gap_shrink_pct, rms_before_i_A, rms_after_i_A, score, fpe,
/// n_params, params, significant, status, flags.
void write_gap_csv(std::ostream& out, const GapReport& report);
/// The human summary (the same content with the regime tables and residual checks).
void write_gap_text(std::ostream& out, const GapReport& report);
/// The diagnosis' honest-numbers findings as warnings on `diag`, "NAME: warning", and its pins as
/// notes, "NAME: PARAMETER = VALUE pinned at ..." (with --format text, whose summary is on stdout).
void warn_flags(const GapReport& report, Diagnostics& diag);
/// The validation time series for plotting: run, t, inputs, measured, before, after and
/// both residuals per output.
void write_gap_residuals(std::ostream& out, const GapReport& report, const GapData& data);

/// Options of `mcg-fit gap`.
struct GapOptions {
  std::string tool;  ///< the tool that runs the diagnosis, for its outputs' `source` ("mcg-fit")
  std::vector<std::string> config;
  std::vector<std::string> train;
  std::vector<std::string> validate;
  std::string format = "csv";   ///< csv (summary on stderr) or text (summary on stdout)
  std::string residuals;        ///< path of the residual series, empty = none
  unsigned threads = 0;
  double split_fraction = 0.6;
  bool split_given = false;      ///< --split was given: the split is taken as it is
  std::vector<std::string> fix;  ///< "NAME=VALUE": measured, so never rescaled by a refit
  std::vector<std::string> exclude;  ///< catalog effects not tried
  double from_s = -std::numeric_limits<double>::infinity();  ///< time range of each run
  double to_s = std::numeric_limits<double>::infinity();
  /// Motor turns per turn of the measured shaft, over the captures' `# gear_ratio:` and the
  /// INI's `[measurement] gear_ratio` (unset: theirs, else 1).
  std::optional<double> gear_ratio;
  /// The measured omega is a linear axis' speed, m/s (the gear ratio then the motor's rad per m
  /// of travel, 2 pi / lead): the reports say m/s.
  bool linear = false;
  DriveInput drive;              ///< --current, --torque: what drives the rig (voltage by default)
  std::string position_column;   ///< --position: speed from this position column (with_speed_from_position)
  double budget_s = 120.0;       ///< wall-clock budget of the diagnosis (partial results after it)
  bool progress = false;         ///< progress report lines on the diagnostics
  bool discrepancy = false;      ///< the catalog-free discrepancy fit whatever the verdict
  bool sensitivities = false;    ///< --jacobian sensitivities (GapSettings::sensitivities)
};

/// Exit status of `mcg-fit gap` when the time budget ran out (the results so far are written).
inline constexpr int k_gap_partial_exit = 4;

/// The whole subcommand: reads the files, diagnoses, writes `out` (the CSV or text) and the
/// summary (with --format csv) and progress on `diag` (and the residuals).
/// Returns 0, or k_gap_partial_exit when the budget ran out.
int run_gap(const GapOptions& options, std::ostream& out, Diagnostics& diag);

}  // namespace mcg::fit
