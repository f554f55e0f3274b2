// The gap diagnosis' search: how a model is scored, how each candidate is fitted (the
// nominal refit, one effect, mixtures by forward selection), and the order in which they are tried.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <iterator>
#include <limits>
#include <map>
#include <mutex>
#include <numbers>
#include <optional>
#include <ranges>
#include <type_traits>

#include "common/demand.hpp"
#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/units.hpp"
#include "fit/friction.hpp"
#include "fit/gap_parts.hpp"
#include "model/effects/compiled.hpp"

namespace mcg::fit {

using namespace gap_detail;

namespace {

/// The nominal parameters a refit moves: the scale factors of the param_mismatch effect.
/// L is left alone: at 1 kHz sampling the 1 ms electrical time constant barely shows.
const std::vector<std::string>& mismatch_scales() {
  static const std::vector<std::string> names = {"Kt_scale",     "J_scale",       "coulomb_scale",
                                                 "static_scale", "viscous_scale", "R_scale"};
  return names;
}

/// The catalog's candidate effects (each module's plan says how it is fitted).
std::vector<const model::EffectSpec*> candidate_effects() {
  std::vector<const model::EffectSpec*> out;
  for (const auto& spec : model::effect_catalog()) {
    if (spec.plan.candidate) out.push_back(&spec);
  }
  return out;
}

/// A friction effect of the catalog (its plan says so).
bool is_friction(std::string_view name) {
  const model::EffectSpec* spec = model::find_effect(name);
  return spec != nullptr && spec->plan.friction;
}

/// True when the mixture was rejected early (see k_rejected_early).
bool rejected(const GapCandidate& c) { return c.status.starts_with(k_rejected_early); }

/// The candidate effect `name`, or nullptr.
const model::EffectSpec* find_plan(std::string_view name) {
  const model::EffectSpec* spec = model::find_effect(name);
  return spec != nullptr && spec->plan.candidate ? spec : nullptr;
}

/// Why an effect cannot be identified from the training runs (empty: it can).
std::string not_excited(const model::EffectPlan& plan, const std::vector<Run>& runs) {
  bool engaged = false;
  bool engages = false;
  bool forward = false;
  bool reverse = false;
  for (const Run& run : runs) {
    const auto& c = run.inputs.clutch;
    const auto& drive = drive_command(run);
    for (std::size_t n = 0; n < c.size(); ++n) {
      if (c[n] == 2.0) engaged = true;
      if (n > 0 && c[n] == 2.0 && c[n - 1] != 2.0) engages = true;
      forward = forward || drive[n] > 0.0;
      reverse = reverse || drive[n] < 0.0;
    }
  }
  using Needs = model::EffectPlan::Needs;
  if (plan.needs == Needs::both_directions && !(forward && reverse)) {
    return "not excited: the drive never reverses in training";
  }
  if (plan.needs == Needs::clutch_engaged && !engaged) return "not excited: clutch never engaged in training";
  if (plan.needs == Needs::clutch_engagement && !engages) return "not excited: no engagement in training";
  return {};
}

/// True when `c` scores significantly better than its own fitted model without `effect`:
/// the effect carries the gain (an effect fitted to nothing, whose presence merely changed
/// what else was refitted, does not).
bool carries_weight(const GapCandidate& c, const std::string& effect, const GapData& data,
                    const std::vector<OutputFloor>& floors, std::size_t outputs, SimulationMemo& memo) {
  model::Model without = c.model;
  std::erase_if(without.effects, [&](const model::Effect& e) { return e.name == effect; });
  return improves(c.score, evaluate(without, data, floors, &memo).score, outputs);
}

/// True when `added` holds a steady-state offset of another shape than one that a member of
/// `effects` holds already (a dead band added to a Coulomb level).
bool alike_offset(const std::vector<std::string>& effects, const std::string& added) {
  const model::TermShape shape = offset_shape(added);
  return shape != model::TermShape::none &&
         std::any_of(effects.begin(), effects.end(), [&](const std::string& e) {
           const model::TermShape own = offset_shape(e);
           return own != model::TermShape::none && own != shape;
         });
}

/// The parameters of `spec` that its offset term of `shape` sets, each with its value per volt
/// of the offset on a motor of resistance `R_ohm` and torque constant `Kt_Nm_A` (a Coulomb
/// level's N m, a dead band's duty, a brush drop's volt): the keys whose seeded value grows with
/// the term's coefficient.
std::vector<std::pair<std::string, double>> offset_keys_per_volt(const model::EffectSpec& spec,
                                                                 model::TermShape shape,
                                                                 const model::Params& p, double R_ohm,
                                                                 double Kt_Nm_A) {
  std::vector<std::pair<std::string, double>> out;
  for (const model::TermSeed& rule : spec.plan.seeded_by) {
    if (rule.shape != shape || rule.start == nullptr) continue;
    // A Coulomb level is a torque against the motion (a negative coefficient), held by R / Kt volts
    // per N m; the others are volts.
    const double sign = shape == model::TermShape::sign ? -1.0 : 1.0;
    const double volts_per_unit = shape == model::TermShape::sign ? R_ohm / Kt_Nm_A : 1.0;
    model::TermValues one;
    model::TermValues two;
    one.coefficient = sign;
    two.coefficient = 2.0 * sign;
    const auto a = rule.start(one, p);
    const auto b = rule.start(two, p);
    for (std::size_t k = 0; k < a.size() && k < b.size(); ++k) {
      const double per_unit = b[k].second - a[k].second;
      if (a[k].first == b[k].first && per_unit > 0.0) out.emplace_back(a[k].first, per_unit / volts_per_unit);
    }
  }
  return out;
}

/// The shares of a steady offset split_offset() starts a mixture at.
constexpr std::array<double, 3> k_offset_shares{0.25, 0.5, 0.75};

/// Validation rows at least where two models must disagree for those rows to decide between
/// them (where_they_differ).
constexpr std::size_t k_min_disagreeing_rows = 10;

/// The validation scores of models `a` and `b` on the scored rows where their simulations differ
/// by more than the output's noise floor: per output the mean of r^2 / floor^2 over those rows,
/// summed over the outputs, and how many rows that is.
struct Disagreement {
  double score_a = 0.0;
  double score_b = 0.0;
  std::size_t rows = 0;
};
Disagreement where_they_differ(const model::Model& a, const model::Model& b, const GapData& data,
                               const std::vector<OutputFloor>& floors, SimulationMemo& memo) {
  const Evaluation ea = evaluate(a, data, floors, &memo);
  const Evaluation eb = evaluate(b, data, floors, &memo);
  std::vector<double> sum_a(floors.size(), 0.0);
  std::vector<double> sum_b(floors.size(), 0.0);
  std::vector<std::size_t> count(floors.size(), 0);
  for (std::size_t r = 0; r < data.validate.size(); ++r) {
    const ScoredRun& sr = data.validate[r];
    for (std::size_t o = 0; o < sr.run.outputs.size(); ++o) {
      const std::size_t f = floor_index(floors, sr.run.outputs[o]);
      if (f == std::string::npos) continue;
      const auto& y = sr.run.measured[o];
      const auto& ya = ea.simulated[r][o];
      const auto& yb = eb.simulated[r][o];
      for (std::size_t n = sr.first_scored; n < y.size(); ++n) {
        const double ra = y[n] - ya[n];
        const double rb = y[n] - yb[n];
        if (!std::isfinite(ra) || !std::isfinite(rb) || !(std::abs(ya[n] - yb[n]) > floors[f].floor))
          continue;
        sum_a[f] += ra * ra;
        sum_b[f] += rb * rb;
        ++count[f];
      }
    }
  }
  Disagreement d;
  for (std::size_t f = 0; f < floors.size(); ++f) {
    if (count[f] == 0) continue;
    const double norm = static_cast<double>(count[f]) * floors[f].floor * floors[f].floor;
    d.score_a += sum_a[f] / norm;
    d.score_b += sum_b[f] / norm;
    d.rows += count[f];
  }
  return d;
}

struct Job {
  std::string name;
  std::vector<std::string> effects;
  model::Model start;  ///< effects present with starting values (grid applied later)
  std::vector<std::string> free;
  std::vector<std::string> grid_effects;   ///< effects whose plan grid is searched before the fit
  int evaluations_per_parameter = 10;      ///< simulation budget per free parameter (and one)
  std::vector<std::string> stage1_free;    ///< fitted alone first (the added effect's parameters)
  std::vector<model::Model> other_starts;  ///< further nominal models the grid is searched on
  /// Per effect, a starting point from the data (values of its plan's free keys), tried before
  /// its grid.
  std::map<std::string, std::vector<double>> data_starts;
  /// A mixture extending the current best model by one effect: rejected early when that
  /// effect, fitted alone on it, removes almost nothing (k_gap_reject_gain).
  bool extension = false;
  /// Fitted in stage 1 only (k_no_gap_alone): the search has no gap to close.
  bool stage1_only = false;
  /// A mixture's: the model it extends (`start` without the added effect, whose keys are
  /// stage1_free). The fit ends no worse on the training runs than this model
  /// (k_no_worse_than_extended).
  std::optional<model::Model> extends = std::nullopt;
  /// A mixture's: the breakaway keys the model it extends holds at 0 (GapCandidate::unexcited),
  /// not free here either.
  std::vector<std::string> unexcited{};
};

/// How much more than the model it extends a mixture's fit may cost on the training runs, relative:
/// the solver's tolerance, with room.
constexpr double k_no_worse_than_extended = 1e-3;

/// Adds effect `name` at its catalog defaults, as the search tries it on `runs` (searched_effect),
/// unless `m` holds it already (the model as given may: its values stand).
void add_effect(model::Model& m, std::string_view name, const std::vector<Run>& runs) {
  if (m.effect(name) == nullptr) m.effects.push_back(searched_effect(name, runs));
}

/// The column a friction table holds a torque-driven run's motor torque in.
constexpr const char* k_motor_torque_column = "T_motor_Nm";

/// How mcg-fit friction reads the tables friction_table() makes of runs driven as `run`.
DriveInput friction_drive(const Run& run) {
  DriveInput drive;
  drive.current = drive_kind(run) == model::DriveKind::current;
  if (drive_kind(run) == model::DriveKind::torque) drive.torque_column = k_motor_torque_column;
  return drive;
}

/// A run as mcg-fit friction reads it: t, v, clutch, r_load, the motor shaft's speed in rpm
/// (`speed`: per output of the run, as measured, times the gear ratio) and the current; a
/// current-driven run's command as `i`, a torque-driven run's motor torque (the logged torque
/// over the gear ratio) in k_motor_torque_column.
table::Table friction_table(const Run& run, const std::vector<std::vector<double>>& series) {
  table::Table t;
  t.source = run.source;
  t.set("t", run.inputs.t_s);
  t.set("v", run.inputs.v_V);
  if (drive_kind(run) == model::DriveKind::current) t.set("i", run.inputs.i_cmd_A);
  if (drive_kind(run) == model::DriveKind::torque) t.set(k_motor_torque_column, run.inputs.T_cmd_Nm);
  t.set("clutch", run.inputs.clutch);
  t.set("r_load", run.inputs.r_load_ohm);
  for (std::size_t o = 0; o < run.outputs.size(); ++o) {
    if (run.outputs[o] == "rpm" || run.outputs[o] == "omega") {
      std::vector<double> rpm = series[o];
      const double factor = run.gear_ratio * (run.outputs[o] == "omega" ? k_rpm_per_rad_s : 1.0);
      for (double& x : rpm) x *= factor;
      t.set("rpm", std::move(rpm));
    } else if (run.outputs[o] == "i") {
      t.set("i", series[o]);
    }
  }
  return t;
}

/// The friction mcg-fit friction sees in `tables` (order 1, with a constant bias when the
/// shaft turns both ways): Tc, Ts, c1 and the bias, in the clutch state with most windows; or
/// nothing when the runs hold no quasi-steady stretch.
std::optional<std::array<double, 4>> seen_friction(const std::vector<table::Table>& tables,
                                                   const model::Params& p, bool both_directions,
                                                   const DriveInput& drive) {
  FrictionOptions options;
  options.drive = drive;
  options.order = 1;
  options.offset = both_directions;
  for (const bool statics : {true, false}) {
    options.static_friction = statics;
    try {
      const FrictionResult r = fit_friction(tables, p, options);
      const StateFriction* best = nullptr;
      for (const auto& s : r.states) {
        if (best == nullptr || s.windows > best->windows) best = &s;
      }
      if (best == nullptr || best->windows < 3) return std::nullopt;
      const model::Friction& f = best->total.value;
      return std::array<double, 4>{f.Tc_Nm, f.Ts_Nm, f.viscous[0], both_directions ? best->offset : 0.0};
    } catch (const Error&) {
      // No start from rest: the static level is left to the grid; no quasi-steady windows: nothing.
    }
  }
  return std::nullopt;
}

/// Searches the effect's grid (the cartesian product of its starting values, on each of the
/// `bases`) on the training cost and returns the best point.
model::Model grid_start(const std::vector<model::Model>& bases, const model::EffectSpec& effect,
                        const std::vector<Run>& runs, const std::vector<double>& orders,
                        std::chrono::steady_clock::time_point deadline, const std::vector<double>* data_point,
                        SimulationMemo& memo) {
  const model::EffectPlan& plan = effect.plan;
  std::vector<std::vector<double>> axes = plan.grid;
  std::vector<std::string> keys = plan.free;
  if (plan.grid_scale != nullptr) {
    const std::vector<double> scale =
        plan.grid_scale(bases.front().params, drive_scale(bases.front().params, runs));
    MCG_DEMAND(scale.size() == axes.size());
    // Scaled to another motor or drive, a start stays inside the range the fit keeps it in.
    const std::vector<model::ParamInfo> ranges = model::parameters(bases.front());
    for (std::size_t k = 0; k < axes.size(); ++k) {
      const auto range = std::find_if(ranges.begin(), ranges.end(), [&](const auto& info) {
        return info.name == effect.name + "." + keys[k];
      });
      for (double& v : axes[k]) {
        v *= scale[k];
        if (range != ranges.end()) v = std::clamp(v, range->lower, range->upper);
      }
    }
  }
  // A key the runs do not fit is held where the bases hold it, not gridded.
  const std::vector<std::string> fitted = fitted_keys(effect, runs);
  for (std::size_t k = keys.size(); k-- > 0;) {
    if (std::find(fitted.begin(), fitted.end(), keys[k]) == fitted.end()) {
      keys.erase(keys.begin() + static_cast<std::ptrdiff_t>(k));
      axes.erase(axes.begin() + static_cast<std::ptrdiff_t>(k));
    }
  }
  if (!plan.angle_order_key.empty() && !orders.empty()) {
    keys.push_back(plan.angle_order_key);
    axes.push_back(orders);
  }
  std::size_t points = 1;
  for (const auto& a : axes) points *= a.size();
  // The trials in the order they are ranked: the point the data put the effect at
  // (data_friction_starts) on each base first, then the grid on each base; the first of equal
  // costs wins, so the choice does not depend on which thread scored what.
  std::vector<model::Model> trials;
  if (data_point != nullptr) {
    MCG_DEMAND(data_point->size() == plan.free.size());
    for (const model::Model& base : bases) {
      model::Model& trial = trials.emplace_back(base);
      for (std::size_t k = 0; k < plan.free.size(); ++k)
        model::set_parameter(trial, effect.name + "." + plan.free[k], (*data_point)[k]);
    }
  }
  for (const model::Model& base : bases) {
    for (std::size_t p = 0; p < points; ++p) {
      model::Model& trial = trials.emplace_back(base);
      std::size_t rest = p;
      for (std::size_t k = 0; k < keys.size(); ++k) {
        model::set_parameter(trial, effect.name + "." + keys[k], axes[k][rest % axes[k].size()]);
        rest /= axes[k].size();
      }
    }
  }
  std::vector<double> costs(trials.size(), std::numeric_limits<double>::infinity());
  parallel::for_each(trials.size(), 0, [&](std::size_t k) {
    if (std::chrono::steady_clock::now() < deadline) costs[k] = training_cost(trials[k], runs, &memo);
  });
  const auto best = std::min_element(costs.begin(), costs.end());
  if (!std::isfinite(*best)) return bases.front();
  return std::move(trials[static_cast<std::size_t>(best - costs.begin())]);
}

/// The nominal scales a gauge is pinned on, most reliably measured first.
constexpr std::array<std::string_view, 3> k_gauge_pins{"param_mismatch.R_scale", "param_mismatch.Kt_scale",
                                                       "param_mismatch.J_scale"};

/// True when `flags` correlate nominal scale `key` beyond k_max_correlation with a parameter of
/// an added effect: the trade a gauge pin on `key` breaks.
bool gauge_trade(const std::vector<FitFlag>& flags, std::string_view key) {
  return std::any_of(flags.begin(), flags.end(), [&](const FitFlag& f) {
    if (f.kind != FitFlag::Kind::correlated) return false;
    const bool has_key = std::find(f.names.begin(), f.names.end(), key) != f.names.end();
    const bool has_effect = std::any_of(f.names.begin(), f.names.end(), [](const std::string& n) {
      return !n.starts_with("param_mismatch.");
    });
    return has_key && has_effect;
  });
}

/// True when flag `f` leaves an added effect's viscous level (a key in N m s/rad) at its bound or
/// undetermined.
bool viscous_loose(const FitFlag& f) {
  return (f.kind == FitFlag::Kind::at_bound || f.kind == FitFlag::Kind::undetermined) &&
         f.names.size() == 1 && !f.names.front().starts_with("param_mismatch.") &&
         f.names.front().ends_with("_Nm_s_rad");
}

/// True when, on runs that measure speed alone under a voltage drive, `flags` leave an added
/// effect's viscous level loose (viscous_loose). Speed alone sets the steady state's slope and
/// offset in the drive, (Kt/R) / (c + Kt Ke/R) and Tc / (c + Kt Ke/R), and the time constant
/// J / (c + Kt Ke/R): Kt and the viscous level c trade exactly along a family the fit may leave
/// at c = 0, where no correlation is computed (a 4.9 s training part put the level at 0 and
/// Kt_scale at 1.07 +- 0.0002, truth 1). The trade a gauge pin on Kt_scale breaks.
bool viscous_trade(const std::vector<FitFlag>& flags, const std::vector<Run>& runs) {
  if (measures_current(runs) || std::any_of(runs.begin(), runs.end(), [](const Run& r) {
        return drive_kind(r) != model::DriveKind::voltage;
      }))
    return false;
  return std::any_of(flags.begin(), flags.end(), viscous_loose);
}

/// True when `flags` say the data leave parameter `key` undetermined, too precise to believe,
/// or traded against another.
bool loose_flagged(const std::vector<FitFlag>& flags, std::string_view key) {
  return std::any_of(flags.begin(), flags.end(), [&](const FitFlag& f) {
    return f.kind != FitFlag::Kind::at_bound && f.kind != FitFlag::Kind::impossible &&
           std::find(f.names.begin(), f.names.end(), key) != f.names.end();
  });
}

/// Points of the breakaway profile on each side of the fitted value.
constexpr int k_profile_half_points = 16;
/// Scans of the breakaway profile at most: one around the fit, then, while the least cost lies
/// at the scan's edge, again around that edge.
constexpr int k_profile_scans = 3;
/// Profiles of a breakaway level at most, each followed by a refit of the other levels around it.
constexpr int k_breakaway_rounds = 2;

/// The breakaway level `key` of a friction effect, fitted on the regularised stick (or the
/// nominal static_scale, fitted on the exact stick), profiled on
/// the exact stick-slip the final score uses: the training cost at values around the fit, the
/// other parameters held. The value moves to the profile's least cost, and its standard error
/// is the reach of the values whose cost lies within one standard error's worth of it (a
/// likelihood ratio of 1: cost_min / M for M residuals, times the AR(1) widening squared, since
/// a simulation error is autocorrelated), or half that of two errors' worth, when that is wider
/// than the Jacobian's. A
/// staircase whose steps bracket the breakaway coarsely gives a flat profile between the
/// steps: the error then says how little the data tell. A fit that left the level at its
/// bound, or without a finite error, gives no scale to scan by: the scan then starts over the
/// motor's whole Coulomb level above the bound (a breakaway is seldom more than twice the
/// Coulomb level; for a scale, the scale 1). Returns the note for the status, which names the
/// `fitted_on` fit's value and error (regularised, regularised_se: the level before any profile
/// moved it).
std::string profile_breakaway(GapCandidate& c, const std::string& key, double residuals, double se_widening,
                              const std::vector<Run>& runs, std::chrono::steady_clock::time_point deadline,
                              SimulationMemo& memo, double regularised, double regularised_se,
                              std::string_view fitted_on = "regularised fit") {
  const auto it = std::find(c.free.begin(), c.free.end(), key);
  if (it == c.free.end()) return {};
  const auto k = static_cast<std::size_t>(it - c.free.begin());
  if (k >= c.values.size() || k >= c.std_errors.size()) return {};
  const double value = c.values[k];
  const double jacobian_se = c.std_errors[k];
  if (!std::isfinite(value) || residuals < 1.0) return {};
  double lower = 0.0;
  for (const model::ParamInfo& info : model::parameters(c.model)) {
    if (info.name == key) lower = info.lower;
  }
  // The size of a level: the motor's Coulomb torque, or 1 for a nominal scale (static_scale).
  const double coulomb_Nm =
      key.starts_with("param_mismatch.") ? 1.0 : model::Compiled(c.model).p.motor.friction.Tc_Nm;
  // The profile spans five of the solver's own (unwidened) errors.
  const double solver_se = jacobian_se / se_widening;
  const bool collapsed = !std::isfinite(solver_se) || !(value - lower > 0.05 * coulomb_Nm);
  double centre_value = collapsed ? lower + 0.5 * coulomb_Nm : value;
  // Five errors, but not past the level's own size: an error far beyond it (a flat regularised
  // fit) would scan in steps wider than the level, and the exact stick's least cost between
  // them would be missed; the scans move on while the least cost lies at an edge.
  double half =
      collapsed ? 0.5 * coulomb_Nm
                : std::max(0.3 * std::abs(value), std::min(5.0 * (std::isfinite(solver_se) ? solver_se : 0.0),
                                                           std::max(std::abs(value), coulomb_Nm)));
  if (!(half > 0.0)) return {};
  std::vector<double> points;
  std::vector<double> costs;
  std::size_t best = 0;
  double step = 0.0;
  bool open = true;
  for (int scan = 0; scan < k_profile_scans && open; ++scan) {
    step = half / k_profile_half_points;
    // Below the centre the scan ends at the bound, with as many points as above: a level
    // nearer its bound than half the scan is resolved there, not stepped over.
    const double step_below = std::min(step, (centre_value - lower) / k_profile_half_points);
    points.clear();
    for (int n = step_below > 0.0 ? -k_profile_half_points : 0; n <= k_profile_half_points; ++n) {
      points.push_back(std::max(lower, centre_value + (n < 0 ? step_below : step) * n));
    }
    costs.assign(points.size(), std::numeric_limits<double>::infinity());
    parallel::for_each(points.size(), 0, [&](std::size_t n) {
      if (std::chrono::steady_clock::now() >= deadline) return;
      model::Model m = c.model;
      model::set_parameter(m, key, points[n]);
      costs[n] = training_cost(m, runs, &memo);
    });
    const auto centre =
        static_cast<std::size_t>(std::find(points.begin(), points.end(), centre_value) - points.begin());
    if (centre >= points.size() ||
        !std::all_of(costs.begin(), costs.end(), [](double x) { return std::isfinite(x); }))
      return {};
    // The least cost, ties to the centre.
    best = centre;
    for (std::size_t n = 0; n < points.size(); ++n) {
      const auto far = [&](std::size_t a) { return a > centre ? a - centre : centre - a; };
      if (costs[n] < costs[best] || (costs[n] == costs[best] && far(n) < far(best))) best = n;
    }
    open = (best == 0 && points[0] > lower) || best + 1 == points.size();
    centre_value = points[best];
    // After a scan over the whole Coulomb level, a finer one around its least cost.
    if (collapsed && scan == 0) {
      open = true;
      half = std::max(0.3 * centre_value, 2.0 * step);
    }
  }
  const double threshold = costs[best] / residuals * se_widening * se_widening;
  std::size_t lo = best;
  std::size_t hi = best;
  while (lo > 0 && costs[lo - 1] <= costs[best] + threshold) --lo;
  while (hi + 1 < points.size() && costs[hi + 1] <= costs[best] + threshold) ++hi;
  // On the exact stick the profile is no parabola: a start from rest moves by whole samples,
  // and the cost undulates by a few likelihood units (a gearmotor's second least cost near the
  // truth, 1.5 errors up, 4 errors of the one-unit stretch away). The error is each side's reach
  // (a profile is seldom symmetric) of the costs within one unit, and half the reach of those
  // within four (two errors), whichever is widest.
  double reach = 0.0;
  for (int errors = 1; errors <= 2; ++errors) {
    for (std::size_t n = 0; n < points.size(); ++n) {
      if (costs[n] <= costs[best] + errors * errors * threshold)
        reach = std::max(reach, std::abs(points[n] - points[best]) / errors);
    }
  }
  const double profile_se = reach + 0.5 * step;
  const bool open_below = lo == 0 && points[0] > lower;
  const bool open_above = hi + 1 == points.size();
  open = open_below || open_above;
  // What the scan shows of an open profile's error: the reach to the edge it did not close at.
  const double open_reach = std::max(open_below ? points[best] - points.front() : 0.0,
                                     open_above ? points.back() - points[best] : 0.0);
  model::set_parameter(c.model, key, points[best]);
  c.values[k] = points[best];
  // The fit's error counts where it speaks of this level: beyond the level's own size it is the
  // regularised stick's flatness, which the closed profile on the exact stick has replaced.
  const bool jacobian_speaks =
      std::isfinite(jacobian_se) && jacobian_se <= std::max(std::abs(value), coulomb_Nm);
  c.std_errors[k] = open              ? std::numeric_limits<double>::infinity()
                    : jacobian_speaks ? std::max(jacobian_se, profile_se)
                                      : profile_se;
  // The profile's word on this one level replaces the fit's: off its bound it is no longer at
  // it, and a closed profile determines it.
  std::erase_if(c.flags, [&](const FitFlag& f) {
    if (f.names != std::vector<std::string>{key}) return false;
    switch (f.kind) {
      case FitFlag::Kind::at_bound:
        return points[best] > lower;
      case FitFlag::Kind::undetermined:
      case FitFlag::Kind::too_precise:
        return !open;
      case FitFlag::Kind::correlated:
      case FitFlag::Kind::impossible:
        return false;
    }
    return false;
  });
  // The fit's sentences on this level go with its flags (a warning printed after the profile
  // moved the level off its bound would name a value the report no longer holds).
  std::erase_if(c.warnings, [&](const std::string& w) {
    if (points[best] > lower && w.starts_with(key + " = ") && w.ends_with(" bound")) return true;
    return !open && w.starts_with(key + ": ");
  });
  // Left at its bound, the level's sentence names the profile's value, which the report holds.
  for (std::string& w : c.warnings) {
    if (points[best] <= lower && w.starts_with(key + " = ") && w.ends_with(" bound")) {
      const std::size_t rest = w.find(' ', key.size() + 3);
      if (rest != std::string::npos) w = fmt::format("{} = {:.6g}{}", key, points[best], w.substr(rest));
    }
  }
  // An open profile's least cost may lie on the scan's last value, a reach of nothing: then that
  // is what is said (flag_infinite_errors flags the level after the verdict).
  const std::string open_text = open_reach > 0.0
                                    ? fmt::format("its error is more than {:.2g}", open_reach)
                                    : std::string("its least cost lies at the edge of the values scanned");
  if (open && std::none_of(c.warnings.begin(), c.warnings.end(),
                           [&](const std::string& w) { return w.starts_with(key + ": "); }))
    c.warnings.push_back(fmt::format(
        "{}: its profile on the exact stick does not close within the values scanned ({})", key, open_text));
  const std::string error = open ? fmt::format("inf, {}", open_text) : fmt::format("{:.2g}", profile_se);
  return fmt::format("{} profiled on the exact stick: {:.4g} +- {} ({} {:.4g} +- {:.2g})", key, points[best],
                     error, fitted_on, regularised, regularised_se);
}

/// A level of an added effect that a fit drove to its zero bound is trapped there: the fit moves
/// positive levels in log coordinates, by ratios, and from 1e-30 no step brings it back when
/// the other parameters have moved to where it belongs (a friction level first fitted beside a
/// coasting driver's share that, without friction, had to hold the speeds down). The level
/// below which `key` is trapped: a hundredth of its plan's smallest start on the drive of `runs`
/// (0: not a level).
double trap_floor(const model::Model& m, const std::string& key, const std::vector<Run>& runs) {
  const auto dot = key.find('.');
  const model::EffectSpec* spec = find_plan(key.substr(0, dot));
  if (spec == nullptr || spec->plan.grid.empty()) return 0.0;
  const model::EffectPlan& plan = spec->plan;
  const auto it = std::find(plan.free.begin(), plan.free.end(), key.substr(dot + 1));
  if (it == plan.free.end()) return 0.0;
  const auto k = static_cast<std::size_t>(it - plan.free.begin());
  const auto param =
      std::find_if(spec->params.begin(), spec->params.end(), [&](const auto& q) { return q.name == *it; });
  if (param == spec->params.end() || param->lower != 0.0 || k >= plan.grid.size() || plan.grid[k].empty())
    return 0.0;
  const double scale =
      plan.grid_scale != nullptr ? plan.grid_scale(m.params, drive_scale(m.params, runs))[k] : 1.0;
  return 0.01 * scale * *std::min_element(plan.grid[k].begin(), plan.grid[k].end());
}

/// Sets each trapped level of `free` at its trap_floor() before a further fit.
void lift_trapped_levels(model::Model& m, const std::vector<std::string>& free,
                         const std::vector<Run>& runs) {
  for (const std::string& key : free) {
    const double floor = trap_floor(m, key, runs);
    if (floor > 0.0 && model::get_parameter(m, key) < floor) model::set_parameter(m, key, floor);
  }
}

/// True when `free` has levels and every one is trapped: the fit switched the effect off.
bool switched_off(const model::Model& m, const std::vector<std::string>& free, const std::vector<Run>& runs) {
  bool any = false;
  for (const std::string& key : free) {
    const double floor = trap_floor(m, key, runs);
    if (floor <= 0.0) continue;
    if (model::get_parameter(m, key) >= floor) return false;
    any = true;
  }
  return any;
}

/// A fit of a candidate with `effects` on the training runs, as the search makes every one (its
/// model and free parameters to be set).
FitProblem candidate_problem(const std::vector<std::string>& effects, const GapData& data,
                             const GapSettings& settings) {
  FitProblem problem;
  problem.runs = data.train;
  problem.nls.threads = 0;  // the search's pool: columns and runs beside the other candidates
  problem.nls.xtol = 1e-4;
  problem.nls.ftol = 1e-5;
  problem.nls.check_smoothness = false;
  problem.sensitivities = settings.sensitivities;
  problem.evaluate_runs = false;  // the candidate is scored by evaluate() and training_speed_rms()
  // Standard errors no smaller than a jackknife's over stretches of the runs (a quantised speed
  // at rest, a dead band trading with a Coulomb level: the Jacobian's error takes the residual
  // for the noise), linearised so that it costs no simulation.
  problem.jackknife_stretches = k_gap_jackknife_stretches;
  problem.jackknife_linearised = true;
  // Jacobians by finite differences throughout: Broyden's updates between them (NlsOptions::
  // broyden) saved a fifth of the public cases' time but lost a two-effect mixture, whose
  // single fits stopped early on updated Jacobians.
  problem.bounds = settings.bounds;
  // Friction is fitted on the regularised stick, where the breakaway moves the response
  // continuously (on the exact stick-slip any level between two drive levels of a staircase
  // gives the same run, and the fit locks onto a level's edge); evaluate() scores it exact.
  problem.sim.smooth_stick = std::any_of(effects.begin(), effects.end(), is_friction);
  if (settings.deadline != std::chrono::steady_clock::time_point::max()) {
    problem.nls.stop = [deadline = settings.deadline] {
      return std::chrono::steady_clock::now() >= deadline;
    };
  }
  return problem;
}

/// The simulation budget of a candidate's fit of `free` parameters: GapSettings::max_evaluations,
/// else `per_parameter` per parameter and one.
int fit_budget(const GapSettings& settings, int per_parameter, std::size_t free) {
  return settings.max_evaluations > 0 ? settings.max_evaluations : per_parameter * static_cast<int>(free + 1);
}

GapCandidate run_job(const Job& job, const GapData& data, const std::vector<OutputFloor>& floors,
                     const GapSettings& settings, const std::vector<double>& orders, SimulationMemo& memo) {
  GapCandidate c;
  c.name = job.name;
  c.effects = job.effects;
  model::Model start = job.start;
  if (job.grid_effects.empty() && !job.other_starts.empty()) {
    double best = training_cost(start, data.train, &memo);
    for (model::Model other : job.other_starts) {
      const double cost = training_cost(other, data.train, &memo);
      if (cost < best) {
        best = cost;
        start = std::move(other);
      }
    }
  }
  for (const auto& e : job.grid_effects) {
    if (const model::EffectSpec* plan = find_plan(e)) {
      std::vector<model::Model> bases{start};
      for (model::Model other : job.other_starts) {
        add_effect(other, e, data.train);
        bases.push_back(std::move(other));
      }
      const auto point = job.data_starts.find(e);
      start = grid_start(bases, *plan, data.train, orders, settings.deadline,
                         point == job.data_starts.end() ? nullptr : &point->second, memo);
    }
  }
  FitProblem problem = candidate_problem(job.effects, data, settings);
  // A fit starts at the optimum of the fit before it (stage 1, a further round), simulated then.
  problem.simulate = [&](const model::Model& m, std::size_t run, const model::SimOptions& options) {
    return memo.simulate(m, data.train[run], options);
  };
  // The solver's evaluations, a look-up in the memo counted as one (GapSettings::max_evaluations).
  auto budget = [&](std::size_t free) { return fit_budget(settings, job.evaluations_per_parameter, free); };
  const auto take = [&](const FitResult& r, const std::vector<std::string>& free) {
    c.model = r.model;
    c.free = free;
    c.values.clear();
    c.std_errors.clear();
    for (Eigen::Index k = 0; k < r.nls.values.size(); ++k) {
      c.values.push_back(r.nls.values[k]);
      // Widened for the residuals' autocorrelation, as mcg-fit model reports them.
      c.std_errors.push_back(r.reported_se(static_cast<std::size_t>(k)));
    }
    c.warnings = r.warnings;
    c.flags = r.flags;
  };
  const auto expired = [&] { return std::chrono::steady_clock::now() >= settings.deadline; };
  // After the time budget only the validation score starts: a fit it cut short is ranked with
  // the values it reached, without standard errors (flagged, so it cannot be the diagnosis),
  // and the status says so.
  const auto cut_short = [&](const FitResult& r) {
    for (const auto& e : job.effects) {
      if (const model::EffectSpec* plan = find_plan(e))
        c.added_parameters += fitted_keys(*plan, data.train).size();
    }
    c.status = fmt::format("{}; fit cut short after {} iterations, scored as it stands", k_out_of_time,
                           r.nls.iterations);
    c.evaluated = true;
    const Evaluation ev = evaluate(c.model, data, floors, &memo);
    c.score = ev.score;
    c.rms = ev.rms;
    c.train_rms_rpm = k_nan;
  };
  const auto score = [&] {
    for (const auto& e : job.effects) {
      if (const model::EffectSpec* plan = find_plan(e))
        c.added_parameters += fitted_keys(*plan, data.train).size();
    }
    c.evaluated = true;
    const Evaluation ev = evaluate(c.model, data, floors, &memo);
    c.score = ev.score;
    c.rms = ev.rms;
    c.train_rms_rpm = training_speed_rms(c.model, data.train, problem.sim, &memo);
  };
  // A training cost above that of the model a mixture extends (on the fit's own simulation, as
  // it stands when asked), beyond the solver's tolerance; never for a single.
  const auto worse = [&](double cost) {
    return job.extends && cost > (1.0 + k_no_worse_than_extended) *
                                     training_cost(*job.extends, data.train, &memo, problem.sim);
  };
  // Stage 1: the added effect alone on the refitted nominal model (cheap, and it brings the
  // effect into its basin before the nominal parameters may move to absorb it).
  if (!job.stage1_free.empty()) {
    // An added effect its single fit switched off (supply_sag's R_s at 0) starts off its zero
    // bound, or its stage 1 removes nothing and the extension is rejected. One still on starts
    // where that fit put it: lifting only the level the data hold at 0 (hbridge's R_on beside
    // its dead band of 0.1) ended the stage-1 fit beside friction_levels at a dead band of 0.01
    // that removed nothing, and hbridge+friction_levels was rejected.
    if (switched_off(start, job.stage1_free, data.train))
      lift_trapped_levels(start, job.stage1_free, data.train);
    problem.model = start;
    problem.free = job.stage1_free;
    problem.nls.max_evaluations = budget(job.stage1_free.size());
    // An extension whose added effect, fitted alone on the current best model, removes almost
    // nothing of its training cost cannot beat it: the joint refit is skipped. Singles are
    // always refitted jointly (a weak effect's single fit, distorted by a stronger one it cannot
    // explain, still ranks it for the mixtures), and so is friction: a model's own friction
    // levels, refitted through the nominal scales, may hold what the effect takes over only
    // jointly.
    const auto friction_key = [](const std::string& key) {
      return is_friction(key.substr(0, key.find('.')));
    };
    const bool may_reject = settings.early_rejection && job.extension &&
                            std::none_of(job.stage1_free.begin(), job.stage1_free.end(), friction_key);
    double before = 0.0;
    if (may_reject) {
      model::Model without = start;
      std::erase_if(without.effects, [&](const model::Effect& e) {
        return std::any_of(job.stage1_free.begin(), job.stage1_free.end(),
                           [&](const std::string& key) { return key.starts_with(e.name + "."); });
      });
      before = training_cost(without, data.train, &memo);
    }
    const FitResult alone = fit_model(problem);
    if (expired()) {
      take(alone, job.stage1_free);
      cut_short(alone);
      return c;
    }
    if (job.stage1_only) {
      take(alone, job.stage1_free);
      c.converged = alone.nls.converged;
      c.status = std::string(k_no_gap_alone);
      score();
      return c;
    }
    start = alone.model;
    const double gain = before > 0.0 ? (before - alone.nls.cost) / before : 1.0;
    if (may_reject && !(gain >= k_gap_reject_gain) && std::isfinite(before)) {
      take(alone, job.stage1_free);
      // A fit alone that ended above the model without the effect stalled where its start put
      // it (a level lifted off 0): its numbers are that stalled fit's, and the status says so.
      c.status = -gain > k_no_worse_than_extended
                     ? fmt::format("{}: fitted alone it stalls {:.2g} % above the training cost without it",
                                   k_rejected_early, -100.0 * gain)
                     : fmt::format("{}: fitted alone it removes {:.2g} % of the training cost",
                                   k_rejected_early, 100.0 * std::max(gain, 0.0));
      score();
      return c;
    }
  }
  // A mixture's members may trade along a long valley (a drive dead band against Coulomb
  // friction: the steady states see only their sum, the coasts and reversals tell them apart):
  // a joint fit that spent its budget still moving goes on from where it stopped, while each
  // round still takes a tenth off the cost (a coasting driver's share and the friction it hides
  // climb a valley together), at most k_joint_rounds times.
  const auto joint_fit = [&](model::Model from, bool lift) {
    // A single's own level at 0 after stage 1 is its fit's word (a gauge may hold it there).
    if (lift && job.effects.size() > 1) lift_trapped_levels(from, job.free, data.train);
    problem.model = std::move(from);
    problem.free = job.free;
    problem.nls.max_evaluations = budget(job.free.size());
    FitResult joint = fit_model(problem);
    constexpr int k_joint_rounds = 3;
    double cost_before = std::numeric_limits<double>::infinity();
    for (int round = 0; round < k_joint_rounds && job.effects.size() > 1 && !joint.nls.converged &&
                        joint.nls.cost < 0.9 * cost_before && !expired();
         ++round) {
      cost_before = joint.nls.cost;
      problem.model = joint.model;
      lift_trapped_levels(problem.model, job.free, data.train);
      joint = fit_model(problem);
    }
    return joint;
  };
  FitResult fit = joint_fit(start, true);
  // A joint fit that ends worse than the model it extends is made again, and the better one kept.
  // A start whose added effect doubles an offset a member holds already (a brush drop at the 3 V
  // its single fit gave it, beside a Coulomb level) may hold the shaft still: no parameter then
  // moves the runs, and stage 1 and the joint fit stop where they began. Stage 1 is then made
  // again from the model extended with the effect nearly off (its levels at their trap floor).
  // The levels lifted off 0 may also leave the joint fit short of where stage 1 was, on a valley
  // of members that trade (an added brush drop against the Coulomb level): it is made again from
  // stage 1's end as it was.
  if (!expired() && worse(fit.nls.cost)) {
    model::Model from = start;
    if (worse(training_cost(from, data.train, &memo, problem.sim))) {
      problem.model = job.start;
      for (const std::string& key : job.stage1_free) {
        if (const double floor = trap_floor(problem.model, key, data.train); floor > 0.0)
          model::set_parameter(problem.model, key, floor);
      }
      problem.free = job.stage1_free;
      problem.nls.max_evaluations = budget(job.stage1_free.size());
      FitResult alone = fit_model(problem);
      if (alone.nls.cost < training_cost(from, data.train, &memo, problem.sim)) from = std::move(alone.model);
    }
    FitResult again = joint_fit(from, false);
    if (again.nls.cost < fit.nls.cost) {
      fit = std::move(again);
      start = std::move(from);
    }
  }
  take(fit, job.free);
  if (expired()) {
    cut_short(fit);
    return c;
  }
  // A gauge the data cannot fix: an added effect that trades exactly against the nominal
  // scales (a drive dead band wider than one drive level leaves the volt unmeasured, so Kt, R,
  // J and friction scale with it; on speed alone, Kt and J trade with a viscous level along
  // the valley that keeps the gain and the time constant). The effect's shape is determined,
  // the common scale is not: pin the nominal scale a datasheet measures best (R by ohmmeter,
  // then Kt, then J) at the given value, one at a time, while it trades beyond
  // k_max_correlation with an effect's parameter, and say so in the status. Small errors do not
  // clear a trade: along such a valley a slight misfit moves both far (a dead-band rig's Kt_scale
  // 0.952 +- 0.008 and viscous level +42 %, 6.6 of its errors, where the truth is 1).
  // Refits the candidate with parameter `key` held at `value` and the rest free.
  const auto refit_pinned = [&](const std::string& key, double value) {
    std::vector<std::string> free = c.free;
    std::erase(free, key);
    problem.model = c.model;
    model::set_parameter(problem.model, key, value);
    problem.free = free;
    problem.nls.max_evaluations = budget(free.size());
    fit = fit_model(problem);
    // A mixture's scales, moved along a valley to trade with the added effect, may start the
    // pinned fit worse than the model it extends: it is made again from stage 1's end, where they
    // had not moved, and the better one kept.
    if (!expired() && worse(fit.nls.cost)) {
      problem.model = start;
      model::set_parameter(problem.model, key, value);
      FitResult again = fit_model(problem);
      if (again.nls.cost < fit.nls.cost) fit = std::move(again);
    }
    take(fit, free);
  };
  std::vector<std::string> pinned;
  for (const std::string_view pin : k_gauge_pins) {
    const std::string key(pin);
    if (expired()) break;
    if (gauge_trade(c.flags, key)) {
      refit_pinned(key, 1.0);
      pinned.push_back(key);
      continue;
    }
    if (key != "param_mismatch.Kt_scale" || std::find(c.free.begin(), c.free.end(), key) == c.free.end() ||
        !viscous_trade(c.flags, data.train))
      continue;
    // Along the trade, Kt_scale s with no viscous level is the point c = (s - 1) Kt0 Ke0 / R of
    // the gauge (Kt_eff = s Kt0): the pinned fit starts there, where a level stuck at its zero
    // bound (fitted in log coordinates) could never move from. Below s = 1 the gauge would need a
    // negative level; a pinned fit that costs more than the solver's tolerance is not the trade.
    const double s_kt = model::get_parameter(c.model, key);
    if (!(s_kt > 1.0)) continue;
    const model::Compiled nominal(c.model);
    const double c_seed = (s_kt - 1.0) / (s_kt * s_kt) * nominal.p.motor.Kt_Nm_A *
                          nominal.p.motor.Ke_V_s_rad / nominal.p.motor.R_ohm;
    const GapCandidate unpinned = c;
    const FitResult unpinned_fit = fit;
    if (std::isfinite(c_seed) && c_seed > 0.0) {
      for (const FitFlag& f : unpinned.flags) {
        if (viscous_loose(f)) model::set_parameter(c.model, f.names.front(), c_seed);
      }
    }
    refit_pinned(key, 1.0);
    if (!(fit.nls.cost <= (1.0 + k_no_worse_than_extended) * unpinned_fit.nls.cost)) {
      c = unpinned;
      fit = unpinned_fit;
      continue;
    }
    pinned.push_back(key);
  }
  std::vector<std::string> profiled;
  for (const auto& e : job.effects) {
    const model::EffectSpec* spec = find_plan(e);
    if (spec == nullptr || spec->plan.breakaway_key.empty()) continue;
    const std::string key = e + "." + spec->plan.breakaway_key;
    const auto k = static_cast<std::size_t>(std::find(c.free.begin(), c.free.end(), key) - c.free.begin());
    // A breakaway the regularised fit left at its bound or without a finite error, or one the
    // profile moved beyond the fit's own error of it, had the other levels fitted around the
    // wrong value (a Coulomb level and a viscous drag that traded with it, several of their
    // errors off): once the profile has found it, they are refitted with it held there, on the
    // exact stick-slip the profile used, and it keeps its place and its profile error. The
    // profile, taken with the others held, is then taken again around the refitted levels,
    // until it stays within its error (k_breakaway_rounds at most).
    if (k >= c.values.size() || k >= c.std_errors.size()) continue;
    std::string note;
    const double regularised = c.values[k];
    const double regularised_se = c.std_errors[k];
    const bool collapsed =
        !std::isfinite(regularised_se) || std::any_of(c.flags.begin(), c.flags.end(), [&](const FitFlag& f) {
          return f.kind == FitFlag::Kind::at_bound && f.names == std::vector<std::string>{key};
        });
    for (int round = 0; round < k_breakaway_rounds; ++round) {
      const double fitted = c.values[k];
      const double fitted_se = c.std_errors[k];
      std::string again =
          profile_breakaway(c, key, static_cast<double>(fit.nls.residuals.size()), fit.se_widening,
                            data.train, settings.deadline, memo, regularised, regularised_se);
      if (again.empty()) break;
      note = std::move(again);
      const double value = c.values[k];
      const double se = c.std_errors[k];
      // A collapsed fit is refitted once; after that only a profile that moves the level is.
      const bool moved = std::abs(value - fitted) > fitted_se;
      if (!((round == 0 && collapsed) || moved) || !std::isfinite(se) ||
          std::chrono::steady_clock::now() >= settings.deadline)
        break;
      std::vector<FitFlag> own;
      for (const FitFlag& f : c.flags) {
        if (f.names == std::vector<std::string>{key}) own.push_back(f);
      }
      const bool smooth = problem.sim.smooth_stick;
      problem.sim.smooth_stick = false;
      refit_pinned(key, value);
      problem.sim.smooth_stick = smooth;
      c.free.insert(c.free.begin() + static_cast<std::ptrdiff_t>(k), key);
      c.values.insert(c.values.begin() + static_cast<std::ptrdiff_t>(k), value);
      c.std_errors.insert(c.std_errors.begin() + static_cast<std::ptrdiff_t>(k), se);
      c.flags.insert(c.flags.end(), own.begin(), own.end());
    }
    if (!note.empty()) profiled.push_back(std::move(note));
  }
  // A breakaway the runs never excite (no start from rest near it) leaves a friction effect's
  // static excess undetermined, even on the exact stick's profile, while its Coulomb and
  // viscous levels are not: pin the excess at 0 (breakaway at the Coulomb level) and say so,
  // rather than set the effect aside.
  std::vector<std::string> unexcited = job.unexcited;
  for (const auto& e : job.effects) {
    const model::EffectSpec* spec = find_plan(e);
    if (c.determined() || spec == nullptr || spec->plan.breakaway_key.empty() || expired()) continue;
    const std::string key = e + "." + spec->plan.breakaway_key;
    if (!loose_flagged(c.flags, key)) continue;
    refit_pinned(key, 0.0);
    unexcited.push_back(key);
    std::erase_if(profiled, [&](const std::string& note) { return note.starts_with(key + " "); });
  }
  if (expired()) {
    cut_short(fit);
    return c;
  }
  c.converged = fit.nls.converged;
  c.unexcited = unexcited;
  c.status = fit.nls.converged ? "fitted" : k_fitted_budget_spent;
  if (!pinned.empty())
    c.status += fmt::format("; {} pinned at the given value (a gauge)", fmt::join(pinned, " "));
  if (!unexcited.empty())
    c.status +=
        fmt::format("; {} pinned at 0: no start from rest in these runs sets it", fmt::join(unexcited, " "));
  // Where the search added the effect it holds the key at 0; an effect of the model as given at
  // the given value.
  std::vector<std::string> held;
  std::vector<std::string> held_given;
  for (const std::string& e : job.effects) {
    const model::EffectSpec* spec = find_plan(e);
    if (spec == nullptr) continue;
    const std::vector<std::string> fitted = fitted_keys(*spec, data.train);
    for (const std::string& key : spec->plan.free) {
      if (std::find(fitted.begin(), fitted.end(), key) != fitted.end()) continue;
      const double value = model::get_parameter(c.model, e + "." + key);
      if (value == 0.0) {
        held.push_back(e + "." + key);
      } else {
        held_given.push_back(fmt::format("{} at the given {:.6g}", e + "." + key, value));
      }
    }
  }
  constexpr const char* k_held_why = "without a measured current speed does not tell it from R";
  if (!held.empty()) c.status += fmt::format("; {} held at 0: {}", fmt::join(held, " "), k_held_why);
  if (!held_given.empty()) c.status += fmt::format("; {} held: {}", fmt::join(held_given, ", "), k_held_why);
  for (const std::string& note : profiled) c.status += "; " + note;
  score();
  return c;
}

/// Runs the jobs on the search's pool (their Jacobian columns and runs share it); each result
/// lands at its job's index.
std::vector<GapCandidate> run_jobs(const std::vector<Job>& jobs, const GapData& data,
                                   const std::vector<OutputFloor>& floors, const GapSettings& settings,
                                   const std::vector<double>& orders, std::size_t& done, std::size_t total,
                                   SimulationMemo& memo) {
  std::vector<GapCandidate> out(jobs.size());
  std::mutex mutex;
  parallel::for_each(jobs.size(), 0, [&](std::size_t k) {
    if (std::chrono::steady_clock::now() >= settings.deadline) {
      GapCandidate& c = out[k];
      c.name = jobs[k].name;
      c.effects = jobs[k].effects;
      c.model = jobs[k].start;
      c.status = std::string(k_out_of_time) + "; not fitted";
      c.score = k_nan;
      c.fpe = std::numeric_limits<double>::infinity();
      c.rms.assign(floors.size(), k_nan);
      c.train_rms_rpm = k_nan;
      return;
    }
    try {
      out[k] = run_job(jobs[k], data, floors, settings, orders, memo);
    } catch (const Error& e) {
      // A candidate the data cannot fit is reported as such; the others go on.
      GapCandidate& c = out[k];
      c.name = jobs[k].name;
      c.effects = jobs[k].effects;
      c.model = jobs[k].start;
      c.status = fmt::format("fit failed: {}", e.what());
      c.score = k_nan;
      c.rms.assign(floors.size(), k_nan);
      c.train_rms_rpm = k_nan;
    }
    const std::lock_guard lock(mutex);
    ++done;
    if (settings.progress) {
      std::string left;
      if (settings.deadline != std::chrono::steady_clock::time_point::max()) {
        const std::chrono::duration<double> rest = settings.deadline - std::chrono::steady_clock::now();
        left = fmt::format(", {:.0f} s of the budget left", std::max(0.0, rest.count()));
      }
      settings.progress(
          fmt::format("fitted {} ({}/{}{}): {}", jobs[k].name, done, total, left, out[k].status));
    }
  });
  return out;
}

}  // namespace

namespace gap_detail {

model::TermShape offset_shape(std::string_view name, bool with_sign) {
  using Shape = model::TermShape;
  const model::EffectSpec* spec = model::find_effect(name);
  if (spec == nullptr) return Shape::none;
  for (const model::TermSeed& rule : spec->plan.seeded_by) {
    if ((with_sign && rule.shape == Shape::sign) || rule.shape == Shape::current_drop ||
        rule.shape == Shape::drive_dead_band)
      return rule.shape;
  }
  return Shape::none;
}

std::optional<model::Model> split_offset(const model::Model& m, const std::vector<std::string>& effects,
                                         const std::string& added, double share) {
  const model::EffectSpec* added_spec = find_plan(added);
  const model::TermShape added_shape = offset_shape(added);
  if (added_spec == nullptr || added_shape == model::TermShape::none) return std::nullopt;
  const model::Compiled compiled(m);
  const double R_ohm = compiled.p.motor.R_ohm;
  const double Kt_Nm_A = compiled.p.motor.Kt_Nm_A;
  if (!(R_ohm > 0.0) || !(Kt_Nm_A > 0.0)) return std::nullopt;
  model::Model out = m;
  double held_V = 0.0;
  for (const std::string& e : effects) {
    const model::TermShape shape = offset_shape(e);
    const model::EffectSpec* spec = find_plan(e);
    if (e == added || spec == nullptr || shape == model::TermShape::none || shape == added_shape) continue;
    const auto keys = offset_keys_per_volt(*spec, shape, m.params, R_ohm, Kt_Nm_A);
    if (keys.empty()) continue;
    held_V += model::get_parameter(m, e + "." + keys.front().first) / keys.front().second;
    for (const auto& [key, per_volt] : keys) {
      const std::string name = e + "." + key;
      model::set_parameter(out, name, (1.0 - share) * model::get_parameter(m, name));
    }
  }
  const auto keys = offset_keys_per_volt(*added_spec, added_shape, m.params, R_ohm, Kt_Nm_A);
  if (!(held_V > 0.0) || keys.empty()) return std::nullopt;
  for (const auto& [key, per_volt] : keys)
    model::set_parameter(out, added + "." + key, share * held_V * per_volt);
  return out;
}

std::map<std::string, std::vector<double>> data_friction_starts(const model::Model& model,
                                                                const std::vector<Run>& runs) {
  std::map<std::string, std::vector<double>> out;
  if (runs.empty()) return out;
  bool forward = false;
  bool reverse = false;
  std::vector<table::Table> measured;
  std::vector<table::Table> simulated;
  try {
    for (const Run& run : runs) {
      measured.push_back(friction_table(run, run.measured));
      simulated.push_back(friction_table(run, simulate_as_measured(model, run)));
      if (measured.back().has("rpm")) {
        for (double x : measured.back().col("rpm")) {
          forward = forward || x > 0.0;
          reverse = reverse || x < 0.0;
        }
      }
    }
  } catch (const Error&) {
    return out;  // a run without a speed: no friction from steady states
  }
  const bool both = forward && reverse;
  const DriveInput drive = friction_drive(runs.front());
  const auto seen = seen_friction(measured, model.params, both, drive);
  auto own = seen_friction(simulated, model.params, both, drive);
  if (!seen) return out;
  // A driven model short of friction may run away from the data's speeds, leaving no steady
  // state to estimate through: then its own friction is its parameters' (no bias).
  const model::Friction& own_f = model.params.motor.friction;
  if (!own)
    own = std::array<double, 4>{own_f.Tc_Nm, std::max(own_f.Ts_Nm, own_f.Tc_Nm), own_f.viscous[0], 0.0};
  // What the data show beyond what the model's own friction shows through the same estimate
  // (so that the estimate's biases cancel). The static excess is the data's beyond the model's
  // own parameters, not through the model's simulated starts from rest, which a model without
  // stiction lacks (its shaft only coasts through zero, and those brackets reach the next drive
  // level).
  model::DataFriction d;
  d.coulomb_Nm = (*seen)[0] - (*own)[0];
  d.static_excess_Nm = (*seen)[1] - (*seen)[0] - std::max(0.0, own_f.Ts_Nm - own_f.Tc_Nm);
  d.viscous_Nm_s_rad = (*seen)[2] - (*own)[2];
  d.asymmetry_Nm = (*seen)[3] - (*own)[3];
  d.both_directions = both;
  // Each friction effect's own start (its plan), kept inside the effect's ranges.
  for (const model::EffectSpec& spec : model::effect_catalog()) {
    if (spec.plan.data_start == nullptr) continue;
    std::vector<double> start = spec.plan.data_start(d, model.params);
    if (start.empty()) continue;
    MCG_DEMAND(start.size() == spec.plan.free.size());
    for (std::size_t k = 0; k < start.size(); ++k) {
      const auto it = std::find_if(spec.params.begin(), spec.params.end(),
                                   [&](const auto& q) { return q.name == spec.plan.free[k]; });
      MCG_DEMAND(it != spec.params.end());
      start[k] = std::clamp(start[k], it->lower, it->upper);
    }
    out[spec.name] = std::move(start);
  }
  return out;
}

std::string not_applicable(const model::EffectPlan& plan, const std::vector<Run>& runs) {
  bool loaded = false;
  for (const Run& run : runs) {
    for (std::size_t n = 0; n < run.inputs.clutch.size() && !loaded; ++n)
      loaded = run.inputs.clutch[n] == 2.0 && std::isfinite(run.inputs.r_load_ohm[n]);
  }
  for (const Run& run : runs) {
    const model::DriveKind drive = drive_kind(run);
    if (!plan.applies_to(drive, loaded))
      return fmt::format("not applicable to {}", model::drive_kind_text(drive));
  }
  return {};
}

bool measures_current(const std::vector<Run>& runs) {
  return std::any_of(runs.begin(), runs.end(), [](const Run& r) {
    return std::find(r.outputs.begin(), r.outputs.end(), "i") != r.outputs.end();
  });
}

std::vector<std::string> fitted_keys(const model::EffectSpec& spec, const std::vector<Run>& runs) {
  std::vector<std::string> keys = spec.plan.free;
  if (!measures_current(runs)) {
    std::erase_if(keys, [&](const std::string& k) {
      return std::find(spec.plan.series_resistance.begin(), spec.plan.series_resistance.end(), k) !=
             spec.plan.series_resistance.end();
    });
  }
  return keys;
}

void hold_unfitted(model::Effect& e, const std::vector<Run>& runs) {
  if (measures_current(runs)) return;
  if (const model::EffectSpec* spec = model::find_effect(e.name)) {
    for (const std::string& key : spec->plan.series_resistance) e.set(key, 0.0);
  }
}

model::Effect searched_effect(std::string_view name, const std::vector<Run>& runs) {
  model::Effect e = model::default_effect(name);
  hold_unfitted(e, runs);
  return e;
}

std::vector<std::string> mismatch_free(const std::vector<std::string>& fixed, const model::Params& p,
                                       const std::vector<Run>& runs,
                                       const std::vector<std::string>& effects) {
  const bool current = measures_current(runs);
  bool detached = false;
  bool engaged = false;
  bool generator_shows = false;
  bool driven = false;
  for (const Run& run : runs) {
    driven = driven || drive_kind(run) != model::DriveKind::voltage;
    for (std::size_t n = 0; n < run.inputs.clutch.size(); ++n) {
      detached = detached || run.inputs.clutch[n] == 1.0;
      engaged = engaged || run.inputs.clutch[n] == 2.0;
      generator_shows =
          generator_shows || (run.inputs.clutch[n] == 2.0 && std::isfinite(run.inputs.r_load_ohm[n]));
    }
    for (const auto& o : run.outputs) generator_shows = generator_shows || o == "i_gen" || o == "v_gen";
  }
  // The friction elements the runs' clutch states put on a turning shaft (mcg-fit friction's
  // stacking): the motor's always, the attached clutch's in state 1, the generator's and the
  // engaged clutch's in state 2.
  const model::Friction* const none = nullptr;
  const model::Friction* const all[] = {&p.motor.friction, detached ? &p.clutch_disengaged : none,
                                        engaged ? &p.generator.friction : none,
                                        engaged ? &p.clutch_engaged : none};
  auto any = [&](auto level) {
    return std::any_of(std::begin(all), std::end(all),
                       [&](const model::Friction* f) { return f && level(f); });
  };
  const bool coulomb = any([](const model::Friction* f) { return f->Tc_Nm != 0.0; });
  const bool statics = any([](const model::Friction* f) { return f->Ts_Nm != 0.0; });
  const bool viscous = any([](const model::Friction* f) {
    return std::any_of(f->viscous.begin(), f->viscous.end(), [](double c) { return c != 0.0; });
  });
  // A current or torque drive sets the motor's torque itself: Kt then only scales J and the
  // friction together (or nothing), unless the generator's load current or EMF shows it.
  const bool torque_constant = !driven || generator_shows;
  std::vector<std::string> free;
  for (const auto& s : mismatch_scales()) {
    if ((s == "coulomb_scale" && !coulomb) || (s == "static_scale" && !statics) ||
        (s == "viscous_scale" && !viscous) || (s == "R_scale" && !current) ||
        (s == "Kt_scale" && !torque_constant)) {
      continue;
    }
    const bool superseded = std::any_of(effects.begin(), effects.end(), [&](const std::string& e) {
      const model::EffectSpec* spec = model::find_effect(e);
      return spec != nullptr && std::find(spec->plan.supersedes.begin(), spec->plan.supersedes.end(), s) !=
                                    spec->plan.supersedes.end();
    });
    if (superseded) continue;
    if (std::none_of(fixed.begin(), fixed.end(),
                     [&](const std::string& f) { return model::mismatch_scale_of(f) == s; })) {
      free.push_back("param_mismatch." + s);
    }
  }
  if (free.empty()) fail("--fix pins every parameter the refit moves");
  return free;
}

void check_excluded(const std::vector<std::string>& excluded) {
  for (const auto& e : excluded) {
    if (find_plan(e) == nullptr) {
      fail("--exclude: {} is not a candidate effect ({})", quote(e), model::unknown_effect_hint(e, true));
    }
  }
}

namespace {

void append_bytes(std::string& key, const void* bytes, std::size_t size) {
  key.append(static_cast<const char*>(bytes), size);
}

/// Everything a simulation of one run depends on besides the run: the bits of every parameter
/// (the nominal ones are a struct of doubles), the effects with their values, the shaft terms
/// and the options.
std::string memo_key(const model::Model& model, const model::SimOptions& options) {
  static_assert(std::is_trivially_copyable_v<model::Params> && sizeof(model::Params) % sizeof(double) == 0,
                "the key reads the nominal parameters as bytes: they must be doubles without padding");
  static_assert(sizeof(model::SimOptions) == 3 * sizeof(double),
                "a new simulation option belongs in the key");
  std::string key;
  append_bytes(key, &model.params, sizeof model.params);
  for (const model::Effect& e : model.effects) {
    key += e.name;
    key += '\0';
    for (const auto& [name, value] : e.params) {
      key += name;
      key += '\0';
      append_bytes(key, &value, sizeof value);
    }
    key += '\n';
  }
  for (const model::ShaftTerm& t : model.shaft_terms) {
    key += t.equation;
    key += '\0';
    append_bytes(key, t.k.data(), sizeof t.k);
    append_bytes(key, &t.basis, sizeof t.basis);
    append_bytes(key, &t.basis_it, sizeof t.basis_it);
  }
  append_bytes(key, &options.max_step_s, sizeof options.max_step_s);
  key += options.circuit_bound ? '1' : '0';
  append_bytes(key, &options.ripple_speed_rad_s, sizeof options.ripple_speed_rad_s);
  key += options.smooth_stick ? '1' : '0';
  return key;
}

}  // namespace

SimulationMemo::Series SimulationMemo::simulate(const model::Model& model, const Run& run,
                                                const model::SimOptions& options) {
  std::string key = memo_key(model, options);
  {
    const std::lock_guard lock(m_mutex);
    const auto held = std::find_if(m_entries.begin(), m_entries.end(),
                                   [&](const Entry& e) { return e.run == &run && e.key == key; });
    if (held != m_entries.end()) {
      m_entries.splice(m_entries.begin(), m_entries, held);
      ++m_hits;
      return held->series;
    }
  }
  Series series = simulate_as_measured(model, run, options);
  std::size_t bytes = 0;
  for (const auto& s : series) bytes += s.size() * sizeof(double);
  const std::lock_guard lock(m_mutex);
  ++m_simulations;
  m_entries.push_front({&run, std::move(key), series, bytes});
  m_bytes += bytes;
  while (m_entries.size() > k_entries || (m_entries.size() > 1 && m_bytes > k_bytes)) {
    m_bytes -= m_entries.back().bytes;
    m_entries.pop_back();
  }
  return series;
}

std::size_t SimulationMemo::simulations() const {
  const std::lock_guard lock(m_mutex);
  return m_simulations;
}

std::size_t SimulationMemo::hits() const {
  const std::lock_guard lock(m_mutex);
  return m_hits;
}

Evaluation evaluate(const model::Model& model, const GapData& data, const std::vector<OutputFloor>& floors,
                    SimulationMemo* memo) {
  Evaluation ev;
  ev.sum_sq.assign(floors.size(), 0.0);
  ev.count.assign(floors.size(), 0);
  for (const ScoredRun& sr : data.validate) {
    auto sim = memo != nullptr ? memo->simulate(model, sr.run) : simulate_as_measured(model, sr.run);
    for (std::size_t o = 0; o < sr.run.outputs.size(); ++o) {
      const std::size_t f = floor_index(floors, sr.run.outputs[o]);
      if (f == std::string::npos) continue;
      const auto& y = sr.run.measured[o];
      for (std::size_t n = sr.first_scored; n < y.size(); ++n) {
        const double r = y[n] - sim[o][n];
        if (!std::isfinite(r)) continue;
        ev.sum_sq[f] += r * r;
        ++ev.count[f];
      }
    }
    ev.simulated.push_back(std::move(sim));
  }
  for (std::size_t f = 0; f < floors.size(); ++f) {
    const double mse = ev.count[f] > 0 ? ev.sum_sq[f] / static_cast<double>(ev.count[f]) : k_nan;
    ev.rms.push_back(std::sqrt(mse));
    if (ev.count[f] > 0) ev.score += mse / (floors[f].floor * floors[f].floor);
  }
  return ev;
}

Eigen::VectorXd training_residuals(const model::Model& model, const std::vector<Run>& runs,
                                   const model::SimOptions& options, SimulationMemo* memo) {
  Eigen::Index total = 0;
  for (const Run& run : runs) {
    for (const auto& y : run.measured) total += static_cast<Eigen::Index>(y.size());
  }
  Eigen::VectorXd out = Eigen::VectorXd::Zero(total);
  Eigen::Index at = 0;
  for (const Run& run : runs) {
    const auto sim =
        memo != nullptr ? memo->simulate(model, run, options) : simulate_as_measured(model, run, options);
    for (std::size_t o = 0; o < run.outputs.size(); ++o) {
      const auto& y = run.measured[o];
      const Eigen::Index start = at;
      at += static_cast<Eigen::Index>(y.size());
      const double spread = deviation_norm(y);
      if (spread == 0.0) continue;
      const double weight = 1.0 / spread;
      for (std::size_t n = 0; n < y.size(); ++n) {
        if (std::isfinite(y[n])) out[start + static_cast<Eigen::Index>(n)] = weight * (sim[o][n] - y[n]);
      }
    }
  }
  return out;
}

double training_cost(const model::Model& model, const std::vector<Run>& runs, SimulationMemo* memo,
                     const model::SimOptions& options) {
  const double cost = training_residuals(model, runs, options, memo).squaredNorm();
  return std::isfinite(cost) ? cost : std::numeric_limits<double>::infinity();
}

double training_speed_rms(const model::Model& model, const std::vector<Run>& runs,
                          const model::SimOptions& options, SimulationMemo* memo) {
  double sq = 0.0;
  std::size_t count = 0;
  for (const Run& run : runs) {
    const auto it = std::find_if(run.outputs.begin(), run.outputs.end(),
                                 [](const std::string& o) { return o == "rpm" || o == "omega"; });
    if (it == run.outputs.end()) continue;
    const auto o = static_cast<std::size_t>(it - run.outputs.begin());
    const auto sim =
        memo != nullptr ? memo->simulate(model, run, options) : simulate_as_measured(model, run, options);
    for (std::size_t n = 0; n < run.measured[o].size(); ++n) {
      const double r = run.measured[o][n] - sim[o][n];
      if (std::isfinite(r)) {
        sq += r * r;
        ++count;
      }
    }
  }
  return count > 0 ? std::sqrt(sq / static_cast<double>(count)) : k_nan;
}

Candidates search_candidates(const model::Model& model, const GapData& data,
                             const std::vector<OutputFloor>& floors, const Evaluation& before, bool gap,
                             const GapSettings& settings) {
  const std::size_t outputs = floors.size();
  const auto n_val = static_cast<double>(validation_count(data) * outputs);
  auto fpe = [&](double score, std::size_t k) { return gap_detail::fpe(score, k, n_val); };

  // The model as given.
  GapCandidate none;
  none.name = "none";
  none.status = "as given";
  none.model = model;
  none.score = before.score;
  none.fpe = before.score;
  none.rms = before.rms;
  // The search's simulations, looked up when a model is simulated again (runs of `data` by address).
  SimulationMemo memo;
  none.train_rms_rpm = training_speed_rms(model, data.train, {}, &memo);
  none.evaluated = true;

  std::size_t done = 0;
  std::size_t total = 2 + candidate_effects().size();

  // The refit of the nominal parameters, warm start of every effect candidate.
  model::Model base = model;
  add_effect(base, "param_mismatch", data.train);
  Job pm_job{"param_mismatch",
             {},
             base,
             mismatch_free(settings.fixed, model.params, data.train),
             {},
             20,
             {},
             {},
             {}};
  if (settings.progress) settings.progress("fitting param_mismatch (nominal parameters)");
  std::vector<GapCandidate> pm_result = run_jobs({pm_job}, data, floors, settings, {}, done, total, memo);
  GapCandidate pm = std::move(pm_result.front());
  pm.fpe = fpe(pm.score, pm.free.size());

  // Single effects.
  std::vector<Job> jobs;
  std::vector<GapCandidate> skipped;
  const std::vector<double> orders = angle_orders(pm.model, data.train, 2);
  const std::map<std::string, std::vector<double>> friction_starts = data_friction_starts(model, data.train);
  for (const model::EffectSpec* spec : candidate_effects()) {
    const model::EffectSpec& plan = *spec;
    if (model.effect(plan.name) != nullptr) continue;
    if (std::find(settings.excluded.begin(), settings.excluded.end(), plan.name) != settings.excluded.end())
      continue;
    std::string why = not_applicable(plan.plan, data.train);
    if (why.empty()) why = not_excited(plan.plan, data.train);
    if (why.empty() && !plan.plan.angle_order_key.empty() && orders.empty())
      why = "not observable: the training samples show no ripple of 2 or more a motor revolution";
    if (!why.empty()) {
      GapCandidate c;
      c.name = plan.name;
      c.effects = {plan.name};
      c.status = why;
      c.score = k_nan;
      c.fpe = std::numeric_limits<double>::infinity();
      c.rms.assign(outputs, k_nan);
      c.train_rms_rpm = k_nan;
      skipped.push_back(std::move(c));
      ++done;
      continue;
    }
    Job job{plan.name,   {plan.name},
            pm.model,    mismatch_free(settings.fixed, model.params, data.train, {plan.name}),
            {plan.name}, 15,
            {},          {base},
            {}};
    add_effect(job.start, plan.name, data.train);
    for (const auto& key : fitted_keys(plan, data.train)) {
      job.free.push_back(plan.name + "." + key);
      job.stage1_free.push_back(plan.name + "." + key);
    }
    job.data_starts = friction_starts;
    // Without a gap no single is significant (nor, then, any mixture): the joint refit, the
    // profile of a breakaway and the pins of its fit are spent on a verdict already drawn. The
    // grid is then searched on the refit alone: the model as given beside it serves an effect
    // whose gain the refit took, and there is no gain to take.
    job.stage1_only = !gap;
    if (job.stage1_only) job.other_starts.clear();
    jobs.push_back(std::move(job));
  }
  // Friction is what every real motor has and what a model made from a datasheet lacks: its
  // candidates are fitted first, so that a time budget never leaves them unfitted.
  std::stable_partition(jobs.begin(), jobs.end(), [](const Job& j) { return is_friction(j.name); });
  std::vector<GapCandidate> singles = run_jobs(jobs, data, floors, settings, orders, done, total, memo);

  // The refit must not lose to an effect fit that merely found better nominal values: when
  // some candidate's nominal scales alone fit the training runs better, refit from there.
  {
    model::Model start = pm.model;
    const double pm_cost = training_cost(pm.model, data.train, &memo);
    double best = pm_cost;
    std::vector<model::Model> trials(singles.size(), pm.model);
    std::vector<double> costs(singles.size(), std::numeric_limits<double>::infinity());
    parallel::for_each(singles.size(), 0, [&](std::size_t k) {
      if (!singles[k].evaluated || std::chrono::steady_clock::now() >= settings.deadline) return;
      *std::find_if(trials[k].effects.begin(), trials[k].effects.end(), [](const auto& e) {
        return e.name == "param_mismatch";
      }) = *singles[k].model.effect("param_mismatch");
      costs[k] = training_cost(trials[k], data.train, &memo);
    });
    for (std::size_t k = 0; k < singles.size(); ++k) {
      if (costs[k] < best) {
        best = costs[k];
        start = trials[k];
      }
    }
    if (best < pm_cost) {
      if (settings.progress) settings.progress("refitting param_mismatch from a better start");
      ++total;
      Job again{"param_mismatch",
                {},
                start,
                mismatch_free(settings.fixed, model.params, data.train),
                {},
                10,
                {},
                {},
                {}};
      GapCandidate refit =
          std::move(run_jobs({again}, data, floors, settings, {}, done, total, memo).front());
      refit.fpe = fpe(refit.score, refit.free.size());
      if (refit.evaluated && training_cost(refit.model, data.train, &memo) < pm_cost) pm = std::move(refit);
    }
  }
  const double ref_score = std::min(before.score, pm.score);
  parallel::for_each(singles.size(), 0, [&](std::size_t k) {
    GapCandidate& c = singles[k];
    c.fpe = fpe(c.score, c.free.size());
    c.significant = gap && c.determined() && improves(c.score, ref_score, outputs) &&
                    carries_weight(c, c.name, data, floors, outputs, memo);
  });
  std::sort(singles.begin(), singles.end(), [](const auto& a, const auto& b) { return a.fpe < b.fpe; });

  // Mixtures by forward selection: the best significant single is extended by one effect at
  // a time from a pool of the singles that did best (significant or not: a weaker effect's
  // single fit is distorted by the stronger one it cannot explain), each extension refitted
  // jointly; the best extension joins when it is significant against the model it extends,
  // up to k_gap_max_mixture effects; an extension whose added effect alone removes almost
  // nothing of the current model's training cost is rejected before its joint refit. Every
  // extension tried is reported.
  // Every friction effect fitted joins the pool whatever its rank: alone, a friction effect that
  // shapes another's levels (an asymmetry, a load-dependent share) has no Coulomb level beneath
  // it and fits worse than the unrelated effects that happen to rank above it.
  // An effect whose own parameters the data leave undetermined (a voltage-side effect on a
  // driven run) scores as the refit does and would crowd out a weaker one that acts: the pool
  // takes the determined ones first.
  std::vector<const GapCandidate*> ranked;
  for (const auto& c : singles) ranked.push_back(&c);
  std::stable_partition(ranked.begin(), ranked.end(), [](const GapCandidate* c) {
    return std::none_of(c->flags.begin(), c->flags.end(), [&](const FitFlag& f) {
      return f.undetermined() && std::any_of(f.names.begin(), f.names.end(), [&](const std::string& n) {
               return n.starts_with(c->name + ".");
             });
    });
  });
  std::vector<const GapCandidate*> pool;
  for (const GapCandidate* c : ranked) {
    if (c->evaluated && std::isfinite(c->score) && c->score < before.score &&
        (pool.size() < settings.pool_effects || is_friction(c->name))) {
      pool.push_back(c);
    }
  }
  const GapCandidate* best_single = nullptr;
  for (const auto& c : singles) {
    if (c.significant) {
      best_single = &c;
      break;
    }
  }
  std::vector<GapCandidate> mixtures;
  std::string best_mixture;
  if (best_single != nullptr) {
    GapCandidate current = *best_single;
    while (current.effects.size() < k_gap_max_mixture) {
      std::vector<Job> round;
      // The friction the data show beyond the current model's: a friction effect added to a
      // model that already changes the drive's torque (a coasting driver, a dead band) starts
      // there too, where its single fit, made without that change, may lie in another valley.
      const std::map<std::string, std::vector<double>> current_starts =
          data_friction_starts(current.model, data.train);
      // The same friction is also tried with the members at their catalog defaults: a member
      // fitted without friction may hold the friction in its own level (a coasting driver's share
      // lowered until the frictionless speeds fell to the data's), and the joint fit from there
      // trades the two along a valley and stops at friction 0. The friction is the one seen
      // beside the current model, whose speeds pass through the data's where the estimate's
      // biases cancel (a frictionless model at the defaults may run at several times them).
      model::Model defaults = current.model;
      for (model::Effect& e : defaults.effects) {
        if (std::find(current.effects.begin(), current.effects.end(), e.name) != current.effects.end())
          e = searched_effect(e.name, data.train);
      }
      for (const GapCandidate* single : pool) {
        const std::string& added = single->name;
        if (std::find(current.effects.begin(), current.effects.end(), added) != current.effects.end())
          continue;
        std::vector<std::string> members = current.effects;
        members.push_back(added);
        // Named in catalog order, so that a mixture reads the same whichever way it was found.
        std::sort(members.begin(), members.end(),
                  [](const std::string& x, const std::string& y) { return find_plan(x) < find_plan(y); });
        std::string name;
        for (const auto& m : members) name += (name.empty() ? "" : "+") + m;
        // Started from the current model with the added effect at its single-fit values, or
        // from the model as given with every member at its single-fit values.
        Job job{name,
                members,
                current.model,
                mismatch_free(settings.fixed, model.params, data.train, members),
                {},
                10,
                {},
                {base},
                {}};
        // An offset alike one the model holds (a dead band beside a Coulomb level) removes nothing
        // fitted alone: the member holds its share, which only the joint refit moves.
        job.extension = !alike_offset(current.effects, added);
        // Its joint fit walks the valley where the two offsets trade: twice the budget.
        if (!job.extension) job.evaluations_per_parameter = 20;
        job.extends = current.model;
        for (const auto& f : current.free) {
          if (!f.starts_with("param_mismatch.")) job.free.push_back(f);
        }
        job.unexcited = current.unexcited;
        job.start.effects.push_back(*single->model.effect(added));
        for (const auto& m : members) {
          for (const auto& c : singles) {
            if (c.name == m) job.other_starts.front().effects.push_back(*c.model.effect(m));
          }
        }
        const auto start_from_data = [&](const model::Model& on) {
          const auto point = current_starts.find(added);
          if (point == current_starts.end()) return;
          model::Model& from_data = job.other_starts.emplace_back(on);
          from_data.effects.push_back(*single->model.effect(added));
          for (std::size_t k = 0; k < point->second.size(); ++k)
            model::set_parameter(from_data, added + "." + find_plan(added)->plan.free[k], point->second[k]);
        };
        start_from_data(current.model);
        start_from_data(defaults);
        // Only beside one member's offset: a third offset split off two that already share it
        // takes a sliver of each and fits the noise.
        if (!job.extension && current.effects.size() == 1) {
          model::Model with_added = current.model;
          with_added.effects.push_back(*single->model.effect(added));
          for (const double share : k_offset_shares) {
            if (auto split = split_offset(with_added, members, added, share))
              job.other_starts.push_back(std::move(*split));
          }
        }
        for (const auto& key : fitted_keys(*find_plan(added), data.train)) {
          job.stage1_free.push_back(added + "." + key);
          job.free.push_back(added + "." + key);
        }
        round.push_back(std::move(job));
      }
      if (round.empty()) break;
      // Those first, so that a time budget leaves them fitted: without them the model's level
      // holds an offset it does not have.
      std::stable_partition(round.begin(), round.end(), [](const Job& j) { return !j.extension; });
      total = done + round.size();
      std::vector<GapCandidate> fitted = run_jobs(round, data, floors, settings, orders, done, total, memo);
      for (auto& c : fitted) c.fpe = fpe(c.score, c.free.size());
      std::sort(fitted.begin(), fitted.end(), [](const auto& x, const auto& y) { return x.fpe < y.fpe; });
      // An extension whose added member is an offset alike one the model holds.
      const auto offset_added = [&](const GapCandidate& c) {
        return std::any_of(c.effects.begin(), c.effects.end(), [&](const std::string& e) {
          return std::find(current.effects.begin(), current.effects.end(), e) == current.effects.end() &&
                 alike_offset(current.effects, e);
        });
      };
      const auto decided_where_they_differ = [](GapCandidate& c, const std::string& other,
                                                const Disagreement& d) {
        c.status += fmt::format(
            "; on the {} held-out rows where it and {} disagree beyond the noise it scores {:.3g} against "
            "{:.3g}",
            d.rows, other, d.score_a, d.score_b);
      };
      for (auto& c : fitted) {
        c.significant =
            c.evaluated && !rejected(c) && c.determined() && improves(c.score, ref_score, outputs);
        if (!c.significant || improves(c.score, current.score, outputs)) continue;
        // An offset alike a member's differs from the model it extends only in the coasts at zero
        // drive and the reversals, a few rows of the held-out runs whose score it barely moves:
        // those rows decide, where the two disagree by more than the noise.
        const Disagreement d = offset_added(c) && c.score < current.score
                                   ? where_they_differ(c.model, current.model, data, floors, memo)
                                   : Disagreement{};
        c.significant = d.rows >= k_min_disagreeing_rows && improves(d.score_a, d.score_b, outputs);
        if (c.significant) decided_where_they_differ(c, current.name, d);
      }
      // Such an extension may rank below one that is not significant: it is then the one tried.
      if (!fitted.empty() && !fitted.front().significant) {
        const auto judged = std::find_if(fitted.begin(), fitted.end(), [&](const GapCandidate& c) {
          return c.significant && !improves(c.score, current.score, outputs);
        });
        if (judged != fitted.end()) std::rotate(fitted.begin(), judged, judged + 1);
      }
      // Two offsets of other shapes (a dead band, a brush drop) may each complete the model: where
      // the two mixtures disagree beyond the noise, the held-out rows pick one.
      if (!fitted.empty() && fitted.front().significant && offset_added(fitted.front())) {
        for (std::size_t k = 1; k < fitted.size(); ++k) {
          if (!fitted[k].significant || !offset_added(fitted[k])) continue;
          const Disagreement d = where_they_differ(fitted[k].model, fitted.front().model, data, floors, memo);
          if (d.rows >= k_min_disagreeing_rows && improves(d.score_a, d.score_b, outputs)) {
            decided_where_they_differ(fitted[k], fitted.front().name, d);
            std::swap(fitted.front(), fitted[k]);
          }
        }
      }
      // The best extension's gain must come from the effect it adds, not from the nominal
      // values refitted beside it.
      if (!fitted.empty() && fitted.front().significant) {
        GapCandidate& best = fitted.front();
        for (const auto& e : best.effects) {
          if (std::find(current.effects.begin(), current.effects.end(), e) == current.effects.end()) {
            best.significant = carries_weight(best, e, data, floors, outputs, memo);
          }
        }
      }
      const bool extended = !fitted.empty() && fitted.front().significant;
      if (extended) {
        current = fitted.front();
        best_mixture = current.name;
        if (settings.progress)
          settings.progress(fmt::format("{} extends the best model significantly", current.name));
      }
      for (auto& c : fitted) mixtures.push_back(std::move(c));
      if (!extended) break;
    }
  }
  std::sort(mixtures.begin(), mixtures.end(), [](const auto& x, const auto& y) { return x.fpe < y.fpe; });

  Candidates out;
  if (best_single != nullptr) out.best_single = best_single->name;
  out.best_mixture = best_mixture;
  out.none = std::move(none);
  out.pm = std::move(pm);
  out.singles = std::move(singles);
  out.mixtures = std::move(mixtures);
  out.skipped = std::move(skipped);
  return out;
}

namespace {

/// The friction effects' breakaway keys of candidate `c`: each is its profile's
/// (profile_breakaway()), held where the profile put it, never pinned or refitted.
std::vector<std::string> profiled_keys(const GapCandidate& c) {
  std::vector<std::string> profiled;
  for (const auto& e : c.effects) {
    const model::EffectSpec* spec = find_plan(e);
    if (spec != nullptr && !spec->plan.breakaway_key.empty())
      profiled.push_back(e + "." + spec->plan.breakaway_key);
  }
  return profiled;
}

/// A refit of the diagnosis' free parameters but its profiled breakaways, from its own values:
/// with a breakaway held where its profile on the exact stick put it, the other levels are
/// refitted on the exact stick too (as the search refits a collapsed breakaway's).
FitProblem diagnosis_problem(const GapCandidate& c, const std::vector<std::string>& profiled,
                             const GapData& data, const GapSettings& settings) {
  FitProblem problem = candidate_problem(c.effects, data, settings);
  problem.model = c.model;
  std::copy_if(c.free.begin(), c.free.end(), std::back_inserter(problem.free), [&](const std::string& name) {
    return std::find(profiled.begin(), profiled.end(), name) == profiled.end();
  });
  if (problem.free.size() < c.free.size()) problem.sim.smooth_stick = false;
  problem.nls.max_evaluations = fit_budget(settings, 10, problem.free.size());
  return problem;
}

/// `c` scored again on its model: validation score, RMS and FPE, and the training speed RMS
/// simulated with `sim`.
void rescore(GapCandidate& c, const GapData& data, const std::vector<OutputFloor>& floors,
             const model::SimOptions& sim) {
  const Evaluation ev = evaluate(c.model, data, floors);
  c.score = ev.score;
  c.rms = ev.rms;
  c.fpe = fpe(ev.score, c.free.size(), static_cast<double>(validation_count(data) * floors.size()));
  c.train_rms_rpm = training_speed_rms(c.model, data.train, sim);
}

/// `c` takes refit `r`'s model, values, errors and findings; its profiled breakaways keep the
/// profile's; it is scored again.
void adopt(GapCandidate& c, const FitResult& r, const std::vector<std::string>& profiled, const GapData& data,
           const std::vector<OutputFloor>& floors, const model::SimOptions& sim) {
  const auto is_profiled = [&](const std::string& name) {
    return std::find(profiled.begin(), profiled.end(), name) != profiled.end();
  };
  std::vector<std::string> free;
  std::vector<double> values;
  std::vector<double> errors;
  for (std::size_t k = 0; k < c.free.size(); ++k) {
    const std::string& name = c.free[k];
    if (is_profiled(name)) {
      free.push_back(name);
      values.push_back(c.values[k]);
      errors.push_back(c.std_errors[k]);
      continue;
    }
    const auto it = std::find(r.nls.names.begin(), r.nls.names.end(), name);
    if (it == r.nls.names.end()) continue;  // pinned
    const auto i = static_cast<std::size_t>(it - r.nls.names.begin());
    free.push_back(name);
    values.push_back(r.nls.values[static_cast<Eigen::Index>(i)]);
    errors.push_back(r.reported_se(i));
  }
  std::vector<FitFlag> flags = r.flags;
  std::copy_if(c.flags.begin(), c.flags.end(), std::back_inserter(flags),
               [&](const FitFlag& f) { return std::all_of(f.names.begin(), f.names.end(), is_profiled); });
  std::vector<std::string> warnings = r.warnings;
  std::copy_if(c.warnings.begin(), c.warnings.end(), std::back_inserter(warnings), [&](const std::string& w) {
    return std::any_of(profiled.begin(), profiled.end(), [&](const std::string& key) {
      return w.starts_with(key + " = ") || w.starts_with(key + ": ");
    });
  });
  c.model = r.model;
  c.free = std::move(free);
  c.values = std::move(values);
  c.std_errors = std::move(errors);
  c.flags = std::move(flags);
  c.warnings = std::move(warnings);
  rescore(c, data, floors, sim);
}

}  // namespace

void converge_diagnosis(GapCandidate& c, const GapData& data, const std::vector<OutputFloor>& floors,
                        const GapSettings& settings) {
  const auto expired = [&] { return std::chrono::steady_clock::now() >= settings.deadline; };
  if (c.converged || !c.evaluated || c.free.empty() || c.values.size() != c.free.size() ||
      c.std_errors.size() != c.free.size() || expired())
    return;
  if (settings.progress) settings.progress(fmt::format("fitting {} on to convergence", c.name));
  const std::vector<std::string> profiled = profiled_keys(c);
  FitProblem problem = diagnosis_problem(c, profiled, data, settings);
  if (problem.free.empty()) return;
  FitResult r = fit_model(problem);
  for (int round = 1; round < k_converge_rounds && !r.nls.converged && !r.nls.stopped && !expired();
       ++round) {
    problem.model = r.model;
    r = fit_model(problem);
  }
  if (r.nls.stopped || expired()) return;
  adopt(c, r, profiled, data, floors, problem.sim);
  c.converged = r.nls.converged;
  if (c.status.starts_with(k_fitted_budget_spent)) {
    c.status.replace(0, k_fitted_budget_spent.size(),
                     c.converged ? "fitted (on to convergence after the verdict)"
                                 : "fitted; budget spent, also after the verdict");
  }
}

void widen_diagnosis_scales(GapCandidate& c, const GapData& data, const std::vector<OutputFloor>& floors,
                            const GapSettings& settings) {
  const auto expired = [&] { return std::chrono::steady_clock::now() >= settings.deadline; };
  if (!c.evaluated || c.values.size() != c.free.size() || c.std_errors.size() != c.free.size() || expired())
    return;
  std::map<std::string, std::pair<double, double>> widened;
  const std::vector<model::ParamInfo> infos = model::parameters(c.model);
  for (const FitFlag& f : c.flags) {
    if (f.kind != FitFlag::Kind::at_bound || f.names.size() != 1) continue;
    const std::string& key = f.names.front();
    const auto it = std::find(c.free.begin(), c.free.end(), key);
    if (!key.starts_with("param_mismatch.") || settings.bounds.contains(key) || it == c.free.end()) continue;
    const auto k = static_cast<std::size_t>(it - c.free.begin());
    if (!(c.std_errors[k] <= k_gap_max_relative_error * std::abs(c.values[k]))) continue;
    const auto info = std::find_if(infos.begin(), infos.end(), [&](const auto& p) { return p.name == key; });
    if (info != infos.end() && info->lower > 0.0)
      widened[key] = {info->lower / k_gap_scale_widening, info->upper * k_gap_scale_widening};
  }
  if (widened.empty()) return;
  if (settings.progress)
    settings.progress(fmt::format("refitting {} with {} beyond the default range", c.name,
                                  fmt::join(std::views::keys(widened), " ")));
  const std::vector<std::string> profiled = profiled_keys(c);
  FitProblem problem = diagnosis_problem(c, profiled, data, settings);
  for (const auto& [key, range] : widened) problem.bounds[key] = range;
  // Started from the diagnosis' values, the refit costs no more on the training runs (the
  // solver takes only steps that lower the cost).
  const FitResult r = fit_model(problem);
  if (r.nls.stopped || expired()) return;
  const std::string status = c.status;
  adopt(c, r, profiled, data, floors, problem.sim);
  c.status = status;
  for (const auto& [key, range] : widened) {
    c.status += fmt::format("; {} at its default bound, refitted within {:g} to {:g}", key, range.first,
                            range.second);
  }
}

void profile_nominal_breakaway(GapCandidate& c, const GapData& data, const std::vector<OutputFloor>& floors,
                               const GapSettings& settings) {
  const std::string key = "param_mismatch.static_scale";
  const auto expired = [&] { return std::chrono::steady_clock::now() >= settings.deadline; };
  if (!c.evaluated || c.values.size() != c.free.size() || c.std_errors.size() != c.free.size() ||
      std::find(c.free.begin(), c.free.end(), key) == c.free.end() ||
      std::any_of(c.effects.begin(), c.effects.end(), is_friction) || expired())
    return;
  if (settings.progress) settings.progress(fmt::format("profiling {}'s static friction scale", c.name));
  const auto k = static_cast<std::size_t>(std::find(c.free.begin(), c.free.end(), key) - c.free.begin());
  const double fitted = c.values[k];
  // The training residuals as the fit weighs them, for their count and correlation, on the exact
  // stick the diagnosis (no friction effect) was fitted on.
  const model::SimOptions sim;
  const Eigen::VectorXd residuals = training_residuals(c.model, data.train, sim);
  SimulationMemo memo;
  const std::string note = profile_breakaway(
      c, key, static_cast<double>(residuals.size()), ar1_widening(residuals, data.train), data.train,
      settings.deadline, memo, fitted, c.std_errors[k], "fit on the exact stick");
  if (note.empty()) return;
  c.status += "; " + note;
  if (c.values[k] != fitted) rescore(c, data, floors, sim);
}

void flag_infinite_errors(GapCandidate& c) {
  const std::size_t n = std::min(c.free.size(), std::min(c.std_errors.size(), c.values.size()));
  for (std::size_t k = 0; k < n; ++k) {
    const std::string& key = c.free[k];
    if (std::isfinite(c.std_errors[k])) continue;
    if (std::none_of(c.flags.begin(), c.flags.end(),
                     [&](const FitFlag& f) { return f.names == std::vector<std::string>{key}; })) {
      c.flags.push_back({FitFlag::Kind::undetermined, {key}, std::numeric_limits<double>::quiet_NaN()});
      if (std::none_of(c.warnings.begin(), c.warnings.end(),
                       [&](const std::string& w) { return w.starts_with(key + ": "); }))
        c.warnings.push_back(fmt::format("{}: not determined by the data (infinite standard error)", key));
    }
    // The errors of the same effect's other parameters hold this one where the fit left it (a
    // friction effect's Coulomb and viscous levels trade with its breakaway): they are smaller
    // than the data allow.
    const std::string effect = key.substr(0, key.find('.') + 1);
    std::vector<std::string> held;
    for (std::size_t j = 0; j < n; ++j) {
      if (j != k && std::isfinite(c.std_errors[j]) && c.free[j].starts_with(effect))
        held.push_back(c.free[j]);
    }
    if (held.empty() || effect == "param_mismatch.") continue;
    c.warnings.push_back(
        fmt::format("{}: standard errors with {} held at {:.4g}, which the data do not set "
                    "(they may be further off than their errors say)",
                    fmt::join(held, ", "), key, c.values[k]));
  }
}

void pin_diagnosis(GapCandidate& c, const model::Model& as_given, const GapData& data,
                   const std::vector<OutputFloor>& floors, const GapSettings& settings) {
  const auto expired = [&] { return std::chrono::steady_clock::now() >= settings.deadline; };
  if (!c.evaluated || c.free.empty() || c.values.size() != c.free.size() ||
      c.std_errors.size() != c.free.size() || expired())
    return;
  // A friction effect's breakaway is its profile's: never pinned.
  const std::vector<std::string> profiled = profiled_keys(c);
  const auto is_profiled = [&](const std::string& name) {
    return std::find(profiled.begin(), profiled.end(), name) != profiled.end();
  };
  const auto on_profiled = [&](const FitFlag& f) {
    return std::any_of(f.names.begin(), f.names.end(), is_profiled);
  };
  // Only a diagnosis with something to pin is refitted.
  std::vector<FitFlag> own;
  std::copy_if(c.flags.begin(), c.flags.end(), std::back_inserter(own),
               [&](const FitFlag& f) { return !on_profiled(f); });
  const auto any_value = [](const std::string&) -> std::optional<double> { return 0.0; };
  if (undetermined_pins(own, c.free, c.std_errors, any_value).empty()) return;
  if (settings.progress)
    settings.progress(fmt::format("refitting {} with what its runs do not set pinned", c.name));

  FitProblem problem = diagnosis_problem(c, profiled, data, settings);
  // The fit once more from the diagnosis' values: what the pins must not cost against.
  const FitResult first = fit_model(problem);
  model::Model nominal = as_given;
  add_effect(nominal, "param_mismatch", data.train);
  const auto given = [&](const std::string& name) -> std::optional<double> {
    const std::string effect = name.substr(0, name.find('.'));
    if (model::find_effect(effect) != nullptr && nominal.effect(effect) == nullptr) return std::nullopt;
    return model::get_parameter(nominal, name);
  };
  FitResult held = pin_undetermined(problem, first, given);
  // The given value may cost where the one the fit left does not (k_pinned_left).
  if (held.pinned.empty() && !expired()) {
    held = pin_undetermined(problem, first, [&](const std::string& name) -> std::optional<double> {
      return model::get_parameter(first.model, name);
    });
    for (PinnedParameter& pin : held.pinned) {
      if (pin.why == k_pinned_given) pin.why = std::string(k_pinned_left);
    }
  }
  if (held.pinned.empty() || expired()) return;

  adopt(c, held, profiled, data, floors, problem.sim);
  c.pinned = held.pinned;
  for (const PinnedParameter& pin : c.pinned) c.status += "; " + pinned_text(pin);
}

}  // namespace gap_detail

std::vector<double> angle_orders(const model::Model& model, const std::vector<Run>& runs, std::size_t keep) {
  std::vector<std::complex<double>> acc(k_max_angle_order + 1, {0.0, 0.0});
  std::vector<double> power(k_max_angle_order + 1, 0.0);
  std::vector<std::size_t> shown(k_max_angle_order + 1, 0);
  for (const Run& run : runs) {
    const auto it = std::find_if(run.outputs.begin(), run.outputs.end(),
                                 [](const std::string& name) { return rad_s_per_unit(name) > 0.0; });
    if (it == run.outputs.end()) continue;
    const auto o = static_cast<std::size_t>(it - run.outputs.begin());
    const auto& y = run.measured[o];
    const double to_motor_rad_s = rad_s_per_unit(*it) * run.gear_ratio;
    const auto sim = simulate_as_measured(model, run);
    std::fill(acc.begin(), acc.end(), std::complex<double>{0.0, 0.0});
    // The motor angle: the trapezoidal integral of the measured speed, times the gear ratio.
    double theta = 0.0;
    for (std::size_t n = 1; n < y.size(); ++n) {
      const double dt = run.inputs.t_s[n] - run.inputs.t_s[n - 1];
      if (std::isfinite(y[n]) && std::isfinite(y[n - 1]))
        theta += 0.5 * (y[n] + y[n - 1]) * to_motor_rad_s * dt;
      const double r = y[n] - sim[o][n];
      if (!std::isfinite(r) || y[n] == 0.0) continue;
      const double advance_rad = std::abs(y[n]) * to_motor_rad_s * dt;
      for (std::size_t order = 2; order <= k_max_angle_order; ++order) {
        if (static_cast<double>(order) * advance_rad >= std::numbers::pi) break;
        acc[order] += r * std::polar(1.0, -static_cast<double>(order) * theta);
        ++shown[order];
      }
    }
    for (std::size_t order = 2; order <= k_max_angle_order; ++order) power[order] += std::norm(acc[order]);
  }
  std::vector<double> orders;
  for (std::size_t order = 2; order <= k_max_angle_order; ++order) {
    if (shown[order] >= k_min_order_samples) orders.push_back(static_cast<double>(order));
  }
  const auto periodogram = [&](double order) {
    const auto k = static_cast<std::size_t>(order);
    return power[k] / static_cast<double>(shown[k]);
  };
  std::stable_sort(orders.begin(), orders.end(),
                   [&](double a, double b) { return periodogram(a) > periodogram(b); });
  orders.resize(std::min(keep, orders.size()));
  return orders;
}

}  // namespace mcg::fit
