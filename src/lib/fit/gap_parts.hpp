// The parts of the gap diagnosis (see gap.hpp for the method), shared between its files:
//   gap_data.cpp      the measured runs: split, measurement metadata, noise floors
//   gap_search.cpp    scoring of a model, the candidates and their fits (refits, singles, mixtures)
//   gap_decision.cpp  significance, ranking and the verdict
//   gap_report.cpp    where the residual lies, and the CSV / text / residual outputs
//   gap.cpp           diagnose_gap() from those parts, and the subcommand
// Internal to the fit library: tools and tests use gap.hpp.
#pragma once

#include <cstddef>
#include <limits>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fit/gap.hpp"

namespace mcg::fit::gap_detail {

inline constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
/// Status of a candidate the time budget cut short (the start of its status text).
inline constexpr std::string_view k_out_of_time = "time budget spent";
/// Status of a candidate whose fit spent its simulation budget before it converged (the start of
/// its status text; converge_diagnosis() goes on with the diagnosis').
inline constexpr std::string_view k_fitted_budget_spent = "fitted; budget spent";
/// Fits, each of the search's budget, that converge_diagnosis() spends at most.
inline constexpr int k_converge_rounds = 4;
/// Status of a mixture rejected early (the start of its status text): the effect (not a
/// friction effect) it adds to the current best model, fitted alone, lowered that model's
/// training cost by less than k_gap_reject_gain of it, so the joint refit was not run and the
/// mixture is never significant.
inline constexpr std::string_view k_rejected_early = "rejected early";
/// Status of a single effect fitted alone on the refitted nominal model and not jointly with it
/// (the start of its status text): the model as given matches the validation runs within the
/// noise, so no candidate can be significant and the joint fit could not change the verdict.
inline constexpr std::string_view k_no_gap_alone = "fitted alone: no gap to close";
/// Share of the training cost an added effect, fitted alone, must remove to be refitted jointly
/// (a tenth of the smallest share a significant candidate removes from a score near the noise).
inline constexpr double k_gap_reject_gain = 0.01;

// --- data ------------------------------------------------------------------------------

/// Noise floors of the compared outputs (rpm, i), pooled over the scored validation rows.
/// Throws when neither output has a floor.
std::vector<OutputFloor> noise_floors(const GapData& data);

/// Without a stated `# rpm_estimator:` the speed's resolution is unknown (a tachometer, a
/// drive's own estimate, a linear axis in its own unit): a sample moves when its magnitude
/// exceeds this share of the run's largest, whatever the unit.
inline constexpr double k_unstated_moving_share = 0.01;
/// The speed resolution of a run in its measured unit: one count of its stated estimator
/// (RpmEstimator::rpm_per_count), else twice k_unstated_moving_share of its largest |speed|.
/// A speed below half of it is at rest ("stuck").
double speed_resolution(const Run& run);
/// Scored validation rows.
std::size_t validation_count(const GapData& data);
/// A current or torque drive's runs command a few times the friction they must overcome, a
/// voltage drive's stall torque some 25 times it (the grids' Coulomb starts are 0.2-4 % of it):
/// the torque such a drive can apply is taken as this multiple of the largest it commands.
inline constexpr double k_command_headroom = 5.0;
/// The size of the runs' drive (model::DriveScale), which the effects' starting grids scale
/// with: a voltage drive's stall torque and no-load speed (model::voltage_drive_scale); on a
/// current drive k_command_headroom times the torque Kt max|i| of its largest command, on a
/// torque drive times its largest torque at the motor shaft, and for both the fastest the motor
/// shaft turns in the runs (the voltage drive's figures where the runs give none).
model::DriveScale drive_scale(const model::Params& p, const std::vector<Run>& runs);
/// Index of output `name` in `floors`, or npos.
std::size_t floor_index(const std::vector<OutputFloor>& floors, const std::string& name);

// --- search ----------------------------------------------------------------------------

/// The search's simulations of its runs at the models simulated last, so that a model simulated
/// again is looked up instead: a fit starts at the optimum of the fit before it (stage 1, the
/// joint fit, its further rounds), and a candidate's score simulates its fit's optimum once more.
/// Keyed on the exact model (every parameter's bits, its effects and terms), the simulation
/// options and the run by address (the runs stay put while the memo lives: one search), so a
/// look-up returns the very numbers the simulation would. It holds the k_entries most recently
/// used (a repeat comes within a few dozen simulations), fewer when their series pass k_bytes.
class SimulationMemo {
 public:
  using Series = std::vector<std::vector<double>>;
  static constexpr std::size_t k_entries = 64;
  /// The series held at most, bytes (and never fewer than one entry).
  static constexpr std::size_t k_bytes = std::size_t{64} << 20;

  /// simulate_as_measured(model, run, options), looked up when held.
  Series simulate(const model::Model& model, const Run& run, const model::SimOptions& options = {});
  /// Simulations run and simulations looked up so far.
  std::size_t simulations() const;
  std::size_t hits() const;

 private:
  struct Entry {
    const Run* run;
    std::string key;
    Series series;
    std::size_t bytes;
  };
  mutable std::mutex m_mutex;
  std::list<Entry> m_entries;  ///< most recently used first
  std::size_t m_bytes = 0;
  std::size_t m_simulations = 0;
  std::size_t m_hits = 0;
};

/// Validation evaluation of one model: per run, per output (in the run's order) the
/// simulated series, and per floor output the pooled squared error and count.
struct Evaluation {
  std::vector<std::vector<std::vector<double>>> simulated;
  std::vector<double> sum_sq;
  std::vector<std::size_t> count;
  double score = 0.0;
  std::vector<double> rms;
};
/// `memo`: the search's, or none.
Evaluation evaluate(const model::Model& model, const GapData& data, const std::vector<OutputFloor>& floors,
                    SimulationMemo* memo = nullptr);

/// The measurement noise of `output` seen in the residual of `ev` (the model as given): the
/// RMS of the residual's second difference over the scored validation rows, divided by
/// sqrt(6) (exact for white noise). The model removes the excitation's steps that the
/// measured signal's own estimate catches, and a gap is slow beside the sampling, so it adds
/// little: an estimate near the residual's RMS says the residual is white. 0 when the runs
/// do not measure `output`.
double residual_noise(const GapData& data, const Evaluation& ev, const std::string& output);

/// True when some run measures the motor current (the only output that tells R from Kt).
bool measures_current(const std::vector<Run>& runs);

/// The free keys of `spec`'s plan a fit on `runs` moves: all but its series resistances
/// (EffectPlan::series_resistance) when no run measures the current.
std::vector<std::string> fitted_keys(const model::EffectSpec& spec, const std::vector<Run>& runs);

/// Effect `e` with every series resistance that `runs` do not fit (fitted_keys) at 0.
void hold_unfitted(model::Effect& e, const std::vector<Run>& runs);

/// Effect `name` as the search adds it to a model fitted on `runs`: at its catalog defaults, its
/// unfitted series resistances at 0 (hold_unfitted). An effect of the model as given keeps its
/// values: the search only adds what the model lacks.
model::Effect searched_effect(std::string_view name, const std::vector<Run>& runs);

/// The nominal scales of param_mismatch a refit moves ("param_mismatch.Kt_scale", ...): those
/// --fix does not pin (`fixed`), that multiply something in `p` that acts in `runs` (a friction
/// element the runs' clutch states put on a turning shaft: the generator's and the clutch's act
/// only with the clutch attached or engaged; a model without friction has no Coulomb level to
/// scale: its scale is undetermined) and that none of `effects` supersedes (friction_levels adds
/// to the levels they scale). Without a measured current R_scale is left at 1: speed alone
/// fixes only Kt and the ratios R Tc/Kt, R c/Kt and R J/Kt (the motor equation divided by Kt/R),
/// so R_scale with the inertia and friction scales is a degenerate set (mcg-fit model leaves R
/// alone likewise). On a current- or torque-driven run Kt_scale is left at 1 unless the
/// generator's load current or EMF shows it: the drive sets the torque, and Kt would only scale
/// J and the friction with it. Throws when --fix pins them all.
std::vector<std::string> mismatch_free(const std::vector<std::string>& fixed, const model::Params& p,
                                       const std::vector<Run>& runs,
                                       const std::vector<std::string>& effects = {});

/// Starting points of the friction candidates from the training runs themselves: the friction
/// that mcg-fit friction's quasi-steady windows and starts from rest (order 1, a constant bias
/// when the shaft turns both ways) find in the measured runs, minus what they find in the
/// model's own simulation of the same runs. friction_levels gets {Tc, Ts excess, c1} (kept
/// positive and in range), friction_asymmetry {dT} from the bias when the shaft turns both
/// ways. Empty when the runs hold no quasi-steady stretch.
std::map<std::string, std::vector<double>> data_friction_starts(const model::Model& model,
                                                                const std::vector<Run>& runs);

/// Why the effect of `plan` cannot show in `runs` whatever its parameters (empty: it can): it
/// acts where their drive overrides it (EffectPlan::applies_to), "not applicable to a
/// current-driven drive". Such a candidate is reported, never fitted (it could only come out
/// undetermined).
std::string not_applicable(const model::EffectPlan& plan, const std::vector<Run>& runs);

/// The steady-state offset an effect puts on a turning shaft, by its plan's seeding shape: a
/// drive's dead band (drive_dead_band), a brush drop (current_drop) or, with `with_sign`, a
/// Coulomb level (sign); none for any other effect. Offsets of different shapes are one constant
/// torque while the shaft turns: only the coasts at zero drive, the reversals and a measured
/// current (which a Coulomb level does not move) tell them apart.
model::TermShape offset_shape(std::string_view name, bool with_sign = true);

/// Model `m` (which holds `added` and the members `effects`) with the steady offset its members
/// of another offset shape hold, in volts on its motor, shared: a fraction `share` moved to
/// `added`, the rest left with them. A dead band added beside a Coulomb level that holds the whole
/// offset starts at 0 there and trades along a long valley; a start on that valley at each share
/// lets the joint fit begin near the split the data hold. Returns nothing when no member holds an
/// offset of another shape.
std::optional<model::Model> split_offset(const model::Model& m, const std::vector<std::string>& effects,
                                         const std::string& added, double share);

/// Throws unless every name is a candidate effect of the catalog (--exclude).
void check_excluded(const std::vector<std::string>& excluded);

/// The training residuals the fit objective sums: (simulated - measured) / the measured
/// channel's spread (root of its sum of squared deviations), run by run, output by output,
/// sample by sample (0 where the measurement is missing or the channel constant), simulated
/// with `options`. `memo`: the search's, or none.
Eigen::VectorXd training_residuals(const model::Model& model, const std::vector<Run>& runs,
                                   const model::SimOptions& options = {}, SimulationMemo* memo = nullptr);
/// The fit objective on the training runs (sum over runs and outputs of the squared NRMSE),
/// used to pick a starting point on a grid; simulated with `options` (a fit's, to compare with
/// its cost). `memo`: the search's, or none.
double training_cost(const model::Model& model, const std::vector<Run>& runs, SimulationMemo* memo = nullptr,
                     const model::SimOptions& options = {});
/// RMS of the speed residual over the training runs, in their measured unit (rpm or omega; the
/// diagnosis holds every speed in rpm, its report converts), simulated with `options`: those of
/// the fit the model came from (the regularised stick for friction), so that it is the error that
/// fit minimised. `memo`: the search's, or none.
double training_speed_rms(const model::Model& model, const std::vector<Run>& runs,
                          const model::SimOptions& options = {}, SimulationMemo* memo = nullptr);

/// The candidates of one diagnosis, before the decision orders them.
struct Candidates {
  GapCandidate none;                    ///< the model as given
  GapCandidate pm;                      ///< the refit of the nominal parameters
  std::vector<GapCandidate> singles;    ///< one effect each, best FPE first
  std::vector<GapCandidate> mixtures;   ///< every extension forward selection fitted, best FPE first
  std::vector<GapCandidate> skipped;    ///< effects the training runs do not excite
  std::string best_single;              ///< the best significant single effect, empty if none
  std::string best_mixture;             ///< the largest mixture forward selection accepted, empty if none
};

/// Fits every candidate. `gap`: the model as given misses by more than the noise (singles
/// are significant only then); `before`: its validation evaluation.
Candidates search_candidates(const model::Model& model, const GapData& data, const std::vector<OutputFloor>& floors,
                             const Evaluation& before, bool gap, const GapSettings& settings);

/// The diagnosis `c` on to convergence, when its fit in the search spent the budget first (a
/// dead band and a Coulomb level trade along a long valley the search's budget may stop in,
/// ten standard errors from the optimum): refitted from its own values, up to
/// k_converge_rounds fits of the search's budget, its profiled breakaways held as
/// pin_diagnosis() holds them. `c` takes the refit, is scored again and says so in its status;
/// the verdict stays. Nothing is done after the time budget, nor kept when it cuts the refit.
void converge_diagnosis(GapCandidate& c, const GapData& data, const std::vector<OutputFloor>& floors,
                        const GapSettings& settings);
/// After the verdict, the parameters of diagnosis `c`'s fit that the runs do not set are held as
/// mcg-fit model holds them (pin_undetermined()): one with an infinite error at its value in the
/// model as given (`as_given`, the nominal scales at 1), else where the fit left it; one at a
/// lower bound of 0 at 0. The rest is refitted once from `c`'s values, with a friction effect's
/// breakaway held where its profile put it and the other levels on the exact stick the profile
/// used (the breakaway's value, error, flags and note stay the profile's: a breakaway near 0 with
/// a profiled error is determined). The pins stand only when they cost no more than one standard
/// error's worth of fit; then `c` takes the refit's values, errors and findings, lists the pins
/// in `pinned` and its status, and is scored again. Which candidate is the diagnosis, and the
/// verdict, stay as they are. Nothing is done after the time budget.
void pin_diagnosis(GapCandidate& c, const model::Model& as_given, const GapData& data,
                   const std::vector<OutputFloor>& floors, const GapSettings& settings);
/// After the verdict, each nominal scale diagnosis `c` left at a bound of its default range, with
/// a standard error within k_gap_max_relative_error of its value and no [bounds] of the user's,
/// is refitted within the range widened by k_gap_scale_widening (its profiled breakaways held):
/// `c` takes the refit (from its own values: it costs no more on the training runs), and its
/// status says so.
/// Nothing is done after the time budget.
void widen_diagnosis_scales(GapCandidate& c, const GapData& data, const std::vector<OutputFloor>& floors,
                            const GapSettings& settings);
/// Flags every free parameter of `c` whose standard error is not finite and that no flag of its
/// own names (an open profile sets the error after the fit's flags were drawn) as undetermined,
/// with a warning when it has none; the same effect's other parameters get a warning that their
/// errors hold it fixed. Display only: called after the verdict.
void flag_infinite_errors(GapCandidate& c);
/// After the verdict, the nominal static friction scale of diagnosis `c`, when free and fitted
/// on the exact stick (no friction effect among `c`'s), is profiled as a friction effect's
/// breakaway is (the exact stick's cost is flat between the drive levels that bracket a
/// breakaway, and a fit locked on a level's edge reports an error of nothing): `c` takes the
/// profile's value and error, its status says so, and it is scored again. Nothing is done after
/// the time budget.
void profile_nominal_breakaway(GapCandidate& c, const GapData& data, const std::vector<OutputFloor>& floors,
                               const GapSettings& settings);

// --- decision --------------------------------------------------------------------------

/// score_ref - score > max(k_abs, k_rel (score_ref - outputs)).
bool improves(double score, double score_ref, std::size_t outputs);
/// Akaike's final prediction error: score (N + k) / (N - k), N = `samples` (validation rows
/// times outputs), k free parameters; inf when not finite or k >= N.
double fpe(double score, std::size_t k, double samples);
/// The verdict: sets report.diagnosis, report.reason and report.candidates (diagnosis first,
/// then the rest by FPE, the skipped last).
void decide(Candidates candidates, bool gap, std::size_t outputs, GapReport& report);

// --- report ----------------------------------------------------------------------------

/// Where the residual of `simulated` lies on the validation runs: speed regimes, frequency
/// bands, current regimes, and the whiteness checks.
void analyse(const GapData& data, const std::vector<std::vector<std::vector<double>>>& simulated,
             std::vector<RegimeStat>& regimes, std::vector<RegimeStat>& bands, std::vector<RegimeStat>& current,
             Whiteness& white);

}  // namespace mcg::fit::gap_detail
