// Grey-box fit: simulation error minimised with Levenberg-Marquardt over named parameters.
#include "fit/greybox.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <string_view>
#include <tuple>

#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/units.hpp"
#include "model/sensitivity.hpp"

namespace mcg::fit {

namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

double mean_of_finite(const std::vector<double>& y, std::size_t& count) {
  double sum = 0.0;
  count = 0;
  for (double v : y) {
    if (std::isfinite(v)) {
      sum += v;
      ++count;
    }
  }
  return count > 0 ? sum / static_cast<double>(count) : k_nan;
}

const std::vector<double>& pick(const model::Outputs& out, const std::string& name) {
  if (name == "i") return out.i_A;
  if (name == "i_gen") return out.i_gen_A;
  if (name == "v_gen") return out.v_gen_V;
  if (name == "omega") return out.omega_rad_s;
  return out.rpm;
}

}  // namespace

std::vector<double> window_average_rpm(const std::vector<double>& t_s, const std::vector<double>& theta_rad,
                                       const measurement::CountEstimator& estimator) {
  const std::size_t n = t_s.size();
  std::vector<double> rpm(n);
  const double to_rpm = 60.0 / (2.0 * std::numbers::pi * estimator.window_s);
  std::size_t j = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double ta = t_s[k] - estimator.window_s;
    double theta_a = theta_rad[0];
    if (ta > t_s[0]) {
      while (j + 1 < n && t_s[j + 1] <= ta) ++j;
      const double span = t_s[j + 1] - t_s[j];
      const double frac = (ta - t_s[j]) / span;
      theta_a = theta_rad[j] + frac * (theta_rad[j + 1] - theta_rad[j]);
    }
    rpm[k] = (theta_rad[k] - theta_a) * to_rpm;
  }
  return rpm;
}

const std::vector<std::string>& measurable_columns() {
  static const std::vector<std::string> columns{"rpm", "i", "i_gen", "v_gen", "omega"};
  return columns;
}

Run make_run(const table::Table& table, const std::vector<std::string>& outputs, const model::Params& params,
             std::size_t min_rows, const DriveInput& drive) {
  Run run;
  run.source = table.source;
  run.first_line = table.first_line;
  table::require_increasing(table, "t");
  run.inputs.t_s = table.col("t");
  const std::size_t rows = table.rows();
  if (drive.current && !drive.torque_column.empty()) fail("a drive is current- or torque-driven, not both");
  if (!table.has("v") && table.has("duty")) {
    run.inputs.v_V = table.col("duty");
    for (double& v : run.inputs.v_V) v *= params.supply_V;
  } else if (!drive.voltage() && !table.has("v")) {
    run.inputs.v_V.assign(rows, 0.0);
  } else {
    run.inputs.v_V = table.col("v");
  }
  if (drive.current) run.inputs.i_cmd_A = table.col("i");
  if (!drive.torque_column.empty()) {
    run.drive_torque = table.col(drive.torque_column);
    run.torque_column = drive.torque_column;
    run.inputs.T_cmd_Nm = run.drive_torque;
  }
  // A motor alone has no clutch and no load relay to log: without those columns the run is the
  // motor alone (clutch 0, relay open), as mcg-fit friction reads it.
  run.inputs.clutch = table.has("clutch") ? table.col("clutch") : std::vector<double>(rows, 0.0);
  run.inputs.r_load_ohm =
      table.has("r_load") ? table.col("r_load") : std::vector<double>(rows, model::k_open_circuit);
  model::validate_inputs(run.inputs, table.source, table.first_line);
  if (table.rows() < min_rows) {
    fail("{}: too short: {} rows (at least {} needed)", table.source, table.rows(), min_rows);
  }
  if (outputs.empty()) {
    // The measured speed (rpm, else omega) and every electrical column that varies.
    const auto varies = [&](const std::string& name) {
      const auto& y = table.col(name);
      const auto first = std::find_if(y.begin(), y.end(), [](double v) { return std::isfinite(v); });
      return first != y.end() && std::any_of(first, y.end(), [&](double v) { return std::isfinite(v) && v != *first; });
    };
    if (table.has("rpm")) {
      run.outputs.push_back("rpm");
    } else if (table.has("omega")) {
      run.outputs.push_back("omega");
    }
    // Without the generator on the rig (clutch 0 throughout) its columns hold noise only.
    const bool generator = std::any_of(run.inputs.clutch.begin(), run.inputs.clutch.end(), [](double c) { return c != 0.0; });
    for (const char* name : {"i", "i_gen", "v_gen"}) {
      const bool of_generator = std::string_view(name) != "i";
      if (drive.current && !of_generator) continue;  // the drive's command, not a measurement
      if (table.has(name) && varies(name) && (generator || !of_generator)) run.outputs.push_back(name);
    }
    if (run.outputs.empty()) {
      fail("{}: no measured column to compare with the model (one of rpm, i, i_gen, v_gen, omega)", table.source);
    }
  } else {
    for (const auto& name : outputs) {
      if (std::find(measurable_columns().begin(), measurable_columns().end(), name) == measurable_columns().end()) {
        fail("unknown output {} (one of rpm, i, i_gen, v_gen, omega)", quote(name));
      }
      if (drive.current && name == "i") {
        fail("{}: output 'i': on a current-driven run the current is the input", table.source);
      }
      run.outputs.push_back(name);
    }
  }
  for (const auto& name : run.outputs) run.measured.push_back(table.col(name));
  // A saturated current reading says only "at least this much": not measured.
  if (const auto text = table.meta.get("i_measurement")) {
    const measurement::CurrentChain chain =
        measurement::parse_i_measurement(*text, fmt::format("{}: i_measurement", table.source));
    for (std::size_t o = 0; o < run.outputs.size(); ++o) {
      if (run.outputs[o] != "i") continue;
      for (double& y : run.measured[o]) {
        if (chain.at_rail(y)) y = k_nan;
      }
    }
  }
  if (const auto text = table.meta.get("rpm_estimator")) {
    run.rpm_estimator = measurement::parse_rpm_estimator(*text, table.source);
  }
  run.stated = measurement::speed_path_stated(table.meta.get("gear_ratio"), table.meta.get("speed_filter"),
                                              table.source);
  run.gear_ratio = run.stated.gear_ratio.value_or(1.0);
  run.speed_filter = run.stated.filter.value_or(measurement::SpeedFilter{});
  return run;
}

void apply_speed_path(Run& run, const measurement::SpeedPath& ini, std::optional<double> gear_override) {
  const measurement::SpeedPath settled =
      measurement::settle_speed_path(run.stated, ini, gear_override, run.source);
  run.gear_ratio = *settled.gear_ratio;
  run.speed_filter = *settled.filter;
  for (std::size_t k = 0; k < run.drive_torque.size(); ++k)
    run.inputs.T_cmd_Nm[k] = run.drive_torque[k] / run.gear_ratio;
}

table::Table select_time(const table::Table& table, double from_s, double to_s) {
  table::require_increasing(table, "t");
  const auto& t = table.col("t");
  const auto first = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), from_s) - t.begin());
  const auto last = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), to_s) - t.begin());
  if (first >= last) fail("{}: no rows between --from {} s and --to {} s", table.source, from_s, to_s);
  if (first == 0 && last == t.size()) return table;
  table::Table out;
  out.source = table.source;
  out.meta = table.meta;
  out.names = table.names;
  out.first_line = table.first_line + first;
  for (const auto& c : table.columns) {
    out.columns.emplace_back(c.begin() + static_cast<std::ptrdiff_t>(first), c.begin() + static_cast<std::ptrdiff_t>(last));
  }
  return out;
}

table::Table with_speed_from_position(table::Table table, const std::string& column) {
  if (column.empty()) return table;
  if (table.has("omega") || table.has("rpm")) {
    fail("{}: --position {}: the run already has a speed column", table.source, quote(column));
  }
  table::require_finite(table, column);
  table::require_increasing(table, "t");
  const auto& x = table.col(column);
  const auto& t = table.col("t");
  const std::size_t n = x.size();
  std::vector<double> omega(n, 0.0);
  for (std::size_t k = 0; n > 1 && k < n; ++k) {
    const std::size_t a = k > 0 ? k - 1 : 0;
    const std::size_t b = k + 1 < n ? k + 1 : n - 1;
    omega[k] = (x[b] - x[a]) / (t[b] - t[a]);
  }
  table.set("omega", std::move(omega));
  return table;
}

const std::vector<double>& drive_command(const Run& run) {
  switch (drive_kind(run)) {
    case model::DriveKind::current:
      return run.inputs.i_cmd_A;
    case model::DriveKind::torque:
      return run.drive_torque;
    case model::DriveKind::voltage:
      break;
  }
  return run.inputs.v_V;
}

model::DriveKind drive_kind(const Run& run) {
  if (!run.inputs.i_cmd_A.empty()) return model::DriveKind::current;
  if (!run.drive_torque.empty()) return model::DriveKind::torque;
  return model::DriveKind::voltage;
}

const std::vector<double>& drive_command(const model::Inputs& inputs) {
  switch (drive_kind(inputs)) {
    case model::DriveKind::current:
      return inputs.i_cmd_A;
    case model::DriveKind::torque:
      return inputs.T_cmd_Nm;
    case model::DriveKind::voltage:
      break;
  }
  return inputs.v_V;
}

model::DriveKind drive_kind(const model::Inputs& inputs) {
  if (!inputs.i_cmd_A.empty()) return model::DriveKind::current;
  if (!inputs.T_cmd_Nm.empty()) return model::DriveKind::torque;
  return model::DriveKind::voltage;
}

double drive_jump(std::span<const double> command, model::DriveKind kind, double jump_V, double share) {
  if (kind == model::DriveKind::voltage) return jump_V;
  double largest = 0.0;
  std::vector<double> changes;
  for (std::size_t n = 0; n < command.size(); ++n) {
    if (!std::isfinite(command[n])) continue;
    largest = std::max(largest, std::abs(command[n]));
    if (n > 0 && std::isfinite(command[n - 1])) changes.push_back(std::abs(command[n] - command[n - 1]));
  }
  double typical = 0.0;
  if (!changes.empty()) {
    const auto q90 = changes.begin() + static_cast<std::ptrdiff_t>((changes.size() - 1) * 9 / 10);
    std::nth_element(changes.begin(), q90, changes.end());
    typical = *q90;
  }
  return std::max(share * largest, k_jump_over_typical * typical);
}

std::string drive_name(const Run& run) {
  switch (drive_kind(run)) {
    case model::DriveKind::current:
      return "i";
    case model::DriveKind::torque:
      return run.torque_column;
    case model::DriveKind::voltage:
      break;
  }
  return "v";
}

table::Table with_rpm(table::Table table) {
  if (table.has("rpm") || !table.has("omega")) return table;
  std::vector<double> rpm = table.col("omega");
  for (double& x : rpm) x *= k_rpm_per_rad_s;
  table.set("rpm", std::move(rpm));
  return table;
}

std::vector<std::string> fix_parameters(model::Model& model, const std::vector<std::string>& items) {
  std::vector<std::string> names;
  const auto infos = model::parameters(model);
  for (const auto& item : items) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0) fail("--fix: expected NAME=VALUE: {}", quote(item));
    const std::string name = item.substr(0, eq);
    const std::string text = item.substr(eq + 1);
    double value = 0.0;
    if (!table::parse_number(text, value) || !std::isfinite(value)) fail("--fix: {}: invalid number {}", name, quote(text));
    if (std::none_of(infos.begin(), infos.end(), [&](const auto& p) { return p.name == name; })) {
      fail("--fix: unknown parameter {} (see mcg-fit model --list)", quote(name));
    }
    if (const auto problem = model::parameter_problem(model, name, value)) {
      fail("--fix: {}: {}", quote(item), *problem);
    }
    model::set_parameter(model, name, value);
    names.push_back(name);
  }
  return names;
}

double rad_s_per_unit(std::string_view name) {
  return name == "rpm" ? k_rad_s_per_rpm : name == "omega" ? 1.0 : 0.0;
}

namespace {

/// A run's fastest measured motor speed with a margin of k_ripple_margin, rad/s (0: no speed
/// measured): the fastest a torque ripple is resolved at (model::SimOptions::ripple_speed_rad_s).
constexpr double k_ripple_margin = 1.2;
double ripple_speed(const Run& run) {
  double fastest = 0.0;
  for (std::size_t k = 0; k < run.outputs.size(); ++k) {
    const double to_rad_s = rad_s_per_unit(run.outputs[k]);
    for (double x : run.measured[k]) {
      if (std::isfinite(x)) fastest = std::max(fastest, std::abs(x) * to_rad_s);
    }
  }
  return k_ripple_margin * fastest * run.gear_ratio;
}

}  // namespace

namespace {

/// The options a run is simulated with: a ripple resolved up to its fastest measured speed.
model::SimOptions options_for(const Run& run, const model::SimOptions& options) {
  model::SimOptions at_speed = options;
  if (at_speed.ripple_speed_rad_s == 0.0) at_speed.ripple_speed_rad_s = ripple_speed(run);
  return at_speed;
}

/// Per output of the run, the simulated series as it was measured. Every step is linear in
/// the outputs (the estimator's differences, the gear, the speed filter from rest), so it maps
/// the outputs' derivatives to the series' alike.
std::vector<std::vector<double>> as_measured(const model::Outputs& out, const Run& run) {
  std::vector<std::vector<double>> series;
  series.reserve(run.outputs.size());
  const double g = run.gear_ratio;
  for (const auto& name : run.outputs) {
    const bool speed = name == "rpm" || name == "omega";
    if (name == "rpm" && run.rpm_estimator) {
      std::vector<double> theta_out = out.theta_rad;
      for (double& x : theta_out) x /= g;
      series.push_back(window_average_rpm(run.inputs.t_s, theta_out, *run.rpm_estimator));
    } else {
      series.push_back(pick(out, name));
      if (speed && g != 1.0) {
        for (double& x : series.back()) x /= g;
      }
    }
    if (speed) series.back() = run.speed_filter.apply(run.inputs.t_s, series.back());
  }
  return series;
}

}  // namespace

std::vector<std::vector<double>> simulate_as_measured(const model::Model& model, const Run& run,
                                                      const model::SimOptions& options) {
  return as_measured(model::simulate(model, run.inputs, options_for(run, options)), run);
}

double deviation_norm(const std::vector<double>& y) {
  std::size_t count = 0;
  const double mean = mean_of_finite(y, count);
  if (count < 2) return 0.0;
  double sq = 0.0;
  for (double v : y) {
    if (std::isfinite(v)) sq += (v - mean) * (v - mean);
  }
  return std::sqrt(sq);
}

double fit_percent(const std::vector<double>& measured, const std::vector<double>& simulated) {
  double err = 0.0;
  for (std::size_t k = 0; k < measured.size(); ++k) {
    if (std::isfinite(measured[k])) err += (measured[k] - simulated[k]) * (measured[k] - simulated[k]);
  }
  const double spread = deviation_norm(measured);
  if (spread == 0.0) return err == 0.0 ? 100.0 : -std::numeric_limits<double>::infinity();
  return 100.0 * (1.0 - std::sqrt(err) / spread);
}

RunResiduals residuals(const model::Model& model, const Run& run, const model::SimOptions& options) {
  RunResiduals res;
  res.outputs = run.outputs;
  res.simulated = simulate_as_measured(model, run, options);
  for (std::size_t o = 0; o < run.outputs.size(); ++o) {
    std::vector<double> r(run.measured[o].size());
    for (std::size_t k = 0; k < r.size(); ++k) r[k] = run.measured[o][k] - res.simulated[o][k];
    res.residual.push_back(std::move(r));
    res.fit_percent.push_back(fit_percent(run.measured[o], res.simulated[o]));
  }
  return res;
}

std::map<std::string, std::pair<double, double>> read_bounds(const config::Ini& ini, const model::Model& model) {
  std::map<std::string, std::pair<double, double>> out;
  const auto infos = model::parameters(model);
  const auto catalog_param = [](std::string_view name) {
    const auto dot = name.find('.');
    const model::EffectSpec* spec = dot == std::string_view::npos ? nullptr : model::find_effect(name.substr(0, dot));
    return spec != nullptr && std::any_of(spec->params.begin(), spec->params.end(),
                                          [&](const auto& p) { return p.name == name.substr(dot + 1); });
  };
  for (const auto* entry : ini.entries("bounds")) {
    if (!catalog_param(entry->key) &&
        std::none_of(infos.begin(), infos.end(), [&](const auto& p) { return p.name == entry->key; })) {
      ini.reject("bounds", entry->key, "unknown parameter (see mcg-fit model --list)");
    }
    const auto v = *ini.numbers("bounds", entry->key);
    if (v.size() != 2) ini.reject("bounds", entry->key, "expected 'LOWER UPPER'");
    if (!(v[0] < v[1])) ini.reject("bounds", entry->key, "lower bound must be below the upper");
    out[entry->key] = {v[0], v[1]};
  }
  return out;
}

std::vector<std::string> default_free(const std::vector<Run>& runs, const std::vector<std::string>& fixed,
                                      std::vector<std::pair<std::string, std::string>>& ties) {
  const bool current = std::any_of(runs.begin(), runs.end(), [](const Run& r) {
    return std::find(r.outputs.begin(), r.outputs.end(), "i") != r.outputs.end();
  });
  const bool driven = std::any_of(runs.begin(), runs.end(), [](const Run& r) {
    return !r.inputs.i_cmd_A.empty() || !r.inputs.T_cmd_Nm.empty();
  });
  std::vector<std::string> wanted;
  if (driven) {
    // The drive sets the torque: Kt only scales J and the friction (or, torque-driven, drops
    // out), and no back-EMF damps the shaft, so the viscous friction is fitted instead. The
    // drive's bias (k_drive_offset) is not: where the model misses more than an offset (a
    // current loop taken as ideal), the bias trades with the Coulomb level and drives it to 0.
    wanted = {"motor.J_kg_m2", "motor.Tc_Nm", "motor.visc1_Nm_s_rad"};
  } else if (current) {
    wanted = {"motor.J_kg_m2", "motor.R_ohm", "motor.Kt_Nm_A", "motor.Ke_V_s_rad", "motor.Tc_Nm"};
  } else {
    wanted = {"motor.J_kg_m2", "motor.Kt_Nm_A", "motor.Tc_Nm"};
  }
  const auto is_fixed = [&](const std::string& n) { return std::find(fixed.begin(), fixed.end(), n) != fixed.end(); };
  std::vector<std::string> free;
  for (const auto& n : wanted) {
    if (!is_fixed(n)) free.push_back(n);
  }
  const bool kt_free = std::find(free.begin(), free.end(), "motor.Kt_Nm_A") != free.end();
  if (!current && !driven && kt_free && !is_fixed("motor.Ke_V_s_rad"))
    ties.emplace_back("motor.Ke_V_s_rad", "motor.Kt_Nm_A");
  return free;
}

void add_free_effects(model::Model& model, const std::vector<std::string>& free) {
  for (const auto& name : free) {
    const auto dot = name.find('.');
    if (dot == std::string::npos) continue;
    const std::string effect = name.substr(0, dot);
    const model::EffectSpec* spec = model::find_effect(effect);
    if (spec == nullptr || model.effect(effect) != nullptr) continue;
    model::Effect e = model::default_effect(effect);
    for (const auto& p : spec->params) {
      if (p.lower < 0.0 && p.upper > 0.0) e.set(p.name, 0.0);
    }
    model.effects.push_back(std::move(e));
  }
}

std::vector<RunFit> evaluate_model(const model::Model& model, const std::vector<Run>& runs,
                                   const model::SimOptions& options) {
  std::vector<RunFit> out;
  for (const Run& run : runs) {
    const RunResiduals res = residuals(model, run, options);
    RunFit fit{run.source, run.outputs, res.fit_percent, {}};
    for (const auto& r : res.residual) fit.rms.push_back(rms_finite(r));
    out.push_back(std::move(fit));
  }
  return out;
}

namespace {

/// Why a fitted value is physically impossible, empty when it is not: a machine constant or
/// scale that is not positive, a friction level or a viscous coefficient below zero (a
/// friction that drives the shaft). [bounds] may let a fit reach such values; the check holds
/// whatever the bounds.
std::string impossible(std::string_view name, double v) {
  const auto key = name.substr(name.rfind('.') + 1);
  for (const std::string_view k : {"R_ohm", "L_H", "Kt_Nm_A", "Ke_V_s_rad", "J_kg_m2", "supply_V", "Kt_scale",
                                   "J_scale", "R_scale", "L_scale"}) {
    if (key == k && !(v > 0.0)) return "is not positive: physically impossible";
  }
  for (const std::string_view k : {"Tc_Nm", "Ts_Nm", "coulomb_scale", "static_scale"}) {
    if (key == k && v < 0.0) return "is a negative friction level: physically impossible";
  }
  for (const std::string_view k : {"visc1_Nm_s_rad", "c1_Nm_s_rad", "viscous_scale"}) {
    if (key == k && v < 0.0) return "is a negative viscous friction (it would drive the shaft): physically impossible";
  }
  return {};
}

}  // namespace

BoundSide bound_reached(double v, double se, double lo, double hi) {
  const bool logs = lo > 0.0 && std::isfinite(hi);
  const double span = logs ? std::log(hi / lo) : hi - lo;
  if (!std::isfinite(span)) return BoundSide::none;
  const double from_lo = logs ? std::log(v / lo) : v - lo;
  const double from_hi = logs ? std::log(hi / v) : hi - v;
  // At a bound the Jacobian steps out of the range: its standard error says nothing more.
  // A positive parameter bounded by 0 is fitted in log coordinates: it nears the bound only
  // by orders of magnitude, so only a value that is 0 in all but name is at it, and only
  // when the data cannot tell it from 0 (a standard error at least its size). A small
  // motor's viscous level, 1e-6 of a range sized for a large one, is not at the bound when
  // the data fix it to a few per cent.
  const bool positive_near_0 = lo == 0.0 && v > 0.0;
  const double lo_margin = positive_near_0 ? 1e-6 * span : k_at_bound * span;
  const bool told_from_0 = positive_near_0 && se < v;
  // A value pressed against a bound the data cannot tell it from (a small fraction of a
  // standard error away) is at it too, whatever the few steps the solver kept off it.
  const double se_coords = logs ? se / v : se;
  const auto pressed = [&](double from) {
    return lo != 0.0 && std::isfinite(se_coords) && from <= k_near_bound * span &&
           from <= k_bound_within_se * se_coords;
  };
  if ((from_lo <= lo_margin && !told_from_0) || pressed(from_lo)) return BoundSide::lower;
  if (from_hi <= k_at_bound * span || pressed(from_hi)) return BoundSide::upper;
  return BoundSide::none;
}

namespace {

/// The honest-numbers checks of FitResult::warnings and ::flags.
void fit_warnings(const NlsResult& n, const std::vector<std::pair<double, double>>& bounds,
                  const std::vector<double>& periods, const std::vector<std::string>& units,
                  FitResult& result) {
  auto add = [&](FitFlag::Kind kind, std::vector<std::string> names, std::string text,
                 double bound = std::numeric_limits<double>::quiet_NaN()) {
    result.flags.push_back({kind, std::move(names), bound});
    result.warnings.push_back(std::move(text));
  };
  using Kind = FitFlag::Kind;
  const auto count = static_cast<Eigen::Index>(n.names.size());
  for (Eigen::Index i = 0; i < count; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const double v = n.values[i];
    const auto [lo, hi] = bounds[k];
    // A scale's unit is "1": printed after a number it would read as a second value.
    const std::string unit = units[k].empty() || units[k] == "1" ? "" : " " + units[k];
    if (const std::string why = impossible(n.names[k], v); !why.empty()) {
      add(Kind::impossible, {n.names[k]}, fmt::format("{} = {:.6g}{} {}", n.names[k], v, unit, why));
      continue;
    }
    const BoundSide side = periods[k] > 0.0 ? BoundSide::none : bound_reached(v, n.std_errors[i], lo, hi);
    if (side != BoundSide::none) {
      const bool lower = side == BoundSide::lower;
      add(Kind::at_bound, {n.names[k]},
          fmt::format("{} = {:.6g}{} is at its {} bound", n.names[k], v, unit, lower ? "lower" : "upper"),
          lower ? lo : hi);
      continue;
    }
    const double se = n.std_errors[i];
    if (n.stopped) {
      add(Kind::undetermined, {n.names[k]},
          fmt::format("{}: no standard error (the time budget cut the fit short)", n.names[k]));
    } else if (!std::isfinite(se)) {
      add(Kind::undetermined, {n.names[k]},
          fmt::format("{}: not determined by the data (infinite standard error)", n.names[k]));
    } else if (const double reported = result.reported_se(k);
               std::isfinite(hi - lo) && reported > 0.5 * (hi - lo)) {
      // Within one error of anywhere in its range (a phase known to +- 78 rad): no value at all.
      add(Kind::undetermined, {n.names[k]},
          fmt::format(
              "{}: not determined by the data (standard error {:.3g}{} beyond half its range {:.6g} to "
              "{:.6g})",
              n.names[k], reported, unit, lo, hi));
    } else if ((k < n.rough.size() && n.rough[k]) || se <= 1e-9 * std::abs(v)) {
      add(Kind::too_precise, {n.names[k]},
          fmt::format("{}: standard error {:.3g}{} is too small to be true: the residual is not smooth "
                      "in it (it sits on a discontinuity of the data)",
                      n.names[k], se, unit));
    }
  }
  for (Eigen::Index i = 0; i < count; ++i) {
    for (Eigen::Index j = i + 1; j < count; ++j) {
      const double c = n.correlation(i, j);
      if (std::isfinite(c) && std::abs(c) > k_max_correlation) {
        const std::string& a = n.names[static_cast<std::size_t>(i)];
        const std::string& b = n.names[static_cast<std::size_t>(j)];
        add(Kind::correlated, {a, b},
            fmt::format("{} and {} are correlated {:.4f}: the data do not tell them apart", a, b, c));
      }
    }
  }
}

void apply_ties(model::Model& m, const std::vector<std::pair<std::string, std::string>>& ties) {
  for (const auto& [follower, leader] : ties) model::set_parameter(m, follower, model::get_parameter(m, leader));
}

/// Eigenvalues of a stretch's scaled normal matrix below this share of its largest are taken as 0
/// (the linearised jackknife's undetermined directions).
constexpr double k_jackknife_rank_floor = 1e-12;

/// One stretch of the delete-one-stretch jackknife: in run `run`, the rows [from, to), whose
/// residuals (every output) it leaves out.
struct Stretch {
  std::size_t run;
  std::size_t from;
  std::size_t to;
};

/// The runs' rows cut into problem.jackknife_stretches contiguous stretches of about equal
/// length (a run of its share, at least one).
std::vector<Stretch> jackknife_stretches(const FitProblem& problem) {
  std::size_t rows = 0;
  for (const Run& run : problem.runs) rows += run.inputs.t_s.size();
  std::vector<Stretch> stretches;
  for (std::size_t r = 0; r < problem.runs.size(); ++r) {
    const std::size_t n = problem.runs[r].inputs.t_s.size();
    const auto share =
        static_cast<std::size_t>(std::llround(static_cast<double>(problem.jackknife_stretches) *
                                              static_cast<double>(n) / static_cast<double>(rows)));
    const std::size_t pieces = std::clamp<std::size_t>(share, 1, n);
    for (std::size_t k = 0; k < pieces; ++k) stretches.push_back({r, k * n / pieces, (k + 1) * n / pieces});
  }
  return stretches;
}

/// Standard errors from the jackknife's values p_(i), one per stretch:
/// se^2 = (g - 1) / g sum_i (p_(i) - mean)^2.
std::vector<double> jackknife_spread(const std::vector<Eigen::VectorXd>& fits) {
  if (fits.size() < 2) return {};
  const auto g = static_cast<double>(fits.size());
  const Eigen::Index count = fits.front().size();
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(count);
  for (const auto& f : fits) mean += f / g;
  Eigen::VectorXd var = Eigen::VectorXd::Zero(count);
  for (const auto& f : fits) var += (f - mean).cwiseAbs2();
  var *= (g - 1.0) / g;
  std::vector<double> se;
  for (Eigen::Index i = 0; i < count; ++i) se.push_back(std::sqrt(var[i]));
  return se;
}

/// The linearised jackknife (FitProblem::jackknife_linearised): with J the fit's Jacobian, r
/// its residuals and J_s, r_s their rows of stretch s, leaving s out moves the values by the
/// Gauss-Newton step dp_s = -(J^T J - J_s^T J_s)^-1 (J^T r - J_s^T r_s), taken in columns scaled
/// to unit norm. Empty when some parameter's error is not finite.
std::vector<double> linear_jackknife(const NlsResult& n, const FitProblem& problem,
                                     const std::vector<std::size_t>& offset) {
  const Eigen::MatrixXd& jac = n.jacobian;
  const Eigen::Index count = jac.cols();
  if (count == 0 || jac.rows() != n.residuals.size() || !jac.allFinite() || !n.std_errors.allFinite())
    return {};
  const Eigen::VectorXd norms = jac.colwise().norm().transpose();
  if (!(norms.minCoeff() > 0.0)) return {};
  const Eigen::MatrixXd scaled = jac * norms.cwiseInverse().asDiagonal();
  const Eigen::MatrixXd gram = scaled.transpose() * scaled;
  const Eigen::VectorXd grad = scaled.transpose() * n.residuals;
  std::vector<Eigen::VectorXd> steps;
  for (const Stretch& s : jackknife_stretches(problem)) {
    const Run& run = problem.runs[s.run];
    const std::size_t len = run.inputs.t_s.size();
    Eigen::MatrixXd gram_s = gram;
    Eigen::VectorXd grad_s = grad;
    for (std::size_t o = 0; o < run.outputs.size(); ++o) {
      const auto at = static_cast<Eigen::Index>(offset[s.run] + o * len + s.from);
      const auto rows = static_cast<Eigen::Index>(s.to - s.from);
      const auto block = scaled.middleRows(at, rows);
      gram_s -= block.transpose() * block;
      grad_s -= block.transpose() * n.residuals.segment(at, rows);
    }
    // A direction the other stretches leave undetermined (a breakaway only this stretch starts
    // from) takes no step: the spread then says nothing of it, rather than infinitely much.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram_s);
    if (eig.info() != Eigen::Success) return {};
    const Eigen::VectorXd& lambda = eig.eigenvalues();
    const double floor = k_jackknife_rank_floor * lambda.cwiseAbs().maxCoeff();
    const Eigen::VectorXd inverse = lambda.unaryExpr([floor](double l) { return l > floor ? 1.0 / l : 0.0; });
    const Eigen::VectorXd step =
        -(eig.eigenvectors() * inverse.asDiagonal() * eig.eigenvectors().transpose() * grad_s);
    steps.push_back(step.cwiseQuotient(norms));
  }
  return jackknife_spread(steps);
}

/// The delete-one-stretch jackknife of FitResult::se_jackknife: each stretch
/// (jackknife_stretches()) left out of the residual in turn and the fit repeated from `fitted`.
/// Empty when a refit fails to converge (its spread would then be the solver's, not the data's).
std::vector<double> jackknife(std::vector<ParameterSpec> specs, std::size_t total,
                              const ResidualFunction& residual, const FitProblem& problem,
                              const std::vector<std::size_t>& offset, const Eigen::VectorXd& fitted) {
  const std::vector<Stretch> stretches = jackknife_stretches(problem);
  for (std::size_t i = 0; i < specs.size(); ++i) specs[i].initial = fitted[static_cast<Eigen::Index>(i)];
  NlsOptions options = problem.nls;
  options.check_smoothness = false;
  std::vector<Eigen::VectorXd> fits;
  for (const Stretch& s : stretches) {
    const Run& run = problem.runs[s.run];
    const std::size_t len = run.inputs.t_s.size();
    const ResidualFunction without = [&](const Eigen::VectorXd& p, Eigen::VectorXd& out) {
      residual(p, out);
      for (std::size_t o = 0; o < run.outputs.size(); ++o) {
        const auto at = static_cast<Eigen::Index>(offset[s.run] + o * len + s.from);
        out.segment(at, static_cast<Eigen::Index>(s.to - s.from)).setZero();
      }
    };
    const NlsResult r = least_squares(specs, total, without, options);
    if (!r.converged) return {};
    fits.push_back(r.values);
  }
  return jackknife_spread(fits);
}

}  // namespace

FitResult fit_model(const FitProblem& problem) {
  if (problem.runs.empty()) fail("nothing to fit: no runs");
  std::vector<model::ParamInfo> infos = model::parameters(problem.model);
  for (auto& info : infos) {
    const auto it = problem.bounds.find(info.name);
    if (it == problem.bounds.end()) continue;
    // Bounds the user gives a phase are a constraint: it is no longer wrapped.
    std::tie(info.lower, info.upper) = it->second;
    info.period = 0.0;
  }
  for (const auto& [follower, leader] : problem.ties) {
    for (const auto& name : {follower, leader}) {
      if (std::none_of(infos.begin(), infos.end(), [&](const auto& p) { return p.name == name; })) {
        fail("unknown parameter {} (see mcg-fit model --list)", quote(name));
      }
    }
    if (std::find(problem.free.begin(), problem.free.end(), follower) != problem.free.end()) {
      fail("parameter {} is tied to {} and cannot be free too", quote(follower), quote(leader));
    }
  }
  std::vector<std::string> units;
  std::vector<ParameterSpec> specs;
  std::vector<std::pair<double, double>> bounds;
  std::vector<double> periods;
  std::set<std::string> seen;
  for (const auto& name : problem.free) {
    if (!seen.insert(name).second) fail("parameter {} is listed twice", quote(name));
    const auto it = std::find_if(infos.begin(), infos.end(), [&](const auto& p) { return p.name == name; });
    if (it == infos.end()) fail("unknown parameter {} (see mcg-fit model --list)", quote(name));
    if (!(it->value >= it->lower && it->value <= it->upper)) {
      fail("parameter {}: initial value {} is outside [{}, {}]", quote(name), it->value, it->lower, it->upper);
    }
    ParameterSpec spec{name, it->value, Transform::linear, 0.0};
    if (it->lower >= 0.0 && it->value > 0.0) {
      spec.transform = Transform::log;
    } else if (it->value == 0.0) {
      // A parameter starting at 0 (a dead time, a polynomial coefficient) gets a unit step
      // of 1 % of its finite bound, or 1e-3 in its own units.
      const double span = std::isfinite(it->upper) ? std::abs(it->upper)
                          : std::isfinite(it->lower) ? std::abs(it->lower) : 0.0;
      spec.scale = span > 0.0 ? 1e-2 * span : 1e-3;
    }
    specs.push_back(spec);
    bounds.emplace_back(it->lower, it->upper);
    periods.push_back(it->period);
    units.push_back(it->unit);
  }
  // A periodic parameter moves freely; the model sees it wrapped into its range.
  const auto in_range = [&](std::size_t i, double v) {
    if (periods[i] <= 0.0 || !std::isfinite(v)) return v;
    const double from_lower = std::fmod(v - bounds[i].first, periods[i]);
    return bounds[i].first + (from_lower < 0.0 ? from_lower + periods[i] : from_lower);
  };

  // Per (run, output): the normalisation std(y) sqrt(N) and the offset of its block.
  std::vector<std::vector<double>> norm(problem.runs.size());
  std::vector<std::size_t> offset(problem.runs.size());
  std::size_t total = 0;
  for (std::size_t r = 0; r < problem.runs.size(); ++r) {
    const Run& run = problem.runs[r];
    offset[r] = total;
    for (std::size_t o = 0; o < run.outputs.size(); ++o) {
      const double spread = deviation_norm(run.measured[o]);
      if (spread == 0.0)
        fail("{}: column {} is constant: no excitation to fit", run.source, quote(run.outputs[o]));
      norm[r].push_back(spread);
      total += run.measured[o].size();
    }
  }

  const ResidualFunction residual = [&](const Eigen::VectorXd& p, Eigen::VectorXd& out) {
    model::Model m = problem.model;
    for (std::size_t i = 0; i < specs.size(); ++i) {
      const double v = in_range(i, p[static_cast<Eigen::Index>(i)]);
      if (!(v >= bounds[i].first && v <= bounds[i].second)) {
        out.setConstant(k_nan);
        return;
      }
      model::set_parameter(m, specs[i].name, v);
    }
    apply_ties(m, problem.ties);
    // The runs are simulated side by side (each fills its own block of the residuals).
    parallel::for_each(problem.runs.size(), problem.nls.threads, [&](std::size_t r) {
      const Run& run = problem.runs[r];
      const auto sim =
          problem.simulate ? problem.simulate(m, r, problem.sim) : simulate_as_measured(m, run, problem.sim);
      auto k = static_cast<Eigen::Index>(offset[r]);
      for (std::size_t o = 0; o < run.outputs.size(); ++o) {
        const auto& y = run.measured[o];
        for (std::size_t n = 0; n < y.size(); ++n, ++k) {
          out[k] = std::isfinite(y[n]) ? (sim[o][n] - y[n]) / norm[r][o] : 0.0;
        }
      }
    });
  };

  // The Jacobian by sensitivities: each run simulated once on dual numbers, its outputs'
  // derivatives taken to the series as measured like the outputs themselves. Every parameter
  // moves with whatever is tied to it.
  NlsOptions nls = problem.nls;
  if (problem.sensitivities) {
    nls.sensitivities = [&](const Eigen::VectorXd& p, Eigen::VectorXd& out, Eigen::MatrixXd& jac) {
      model::Model m = problem.model;
      for (std::size_t i = 0; i < specs.size(); ++i) {
        const double v = in_range(i, p[static_cast<Eigen::Index>(i)]);
        if (!(v >= bounds[i].first && v <= bounds[i].second)) return false;
        model::set_parameter(m, specs[i].name, v);
      }
      apply_ties(m, problem.ties);
      std::vector<std::string> names;
      for (const ParameterSpec& spec : specs) names.push_back(spec.name);
      std::vector<model::Direction> directions = model::parameter_directions(m, names);
      for (model::Direction& d : directions) {
        apply_ties(d.plus, problem.ties);
        apply_ties(d.minus, problem.ties);
      }
      out.resize(static_cast<Eigen::Index>(total));
      jac.resize(static_cast<Eigen::Index>(total), static_cast<Eigen::Index>(specs.size()));
      std::atomic<bool> ok{true};
      parallel::for_each(problem.runs.size(), problem.nls.threads, [&](std::size_t r) {
        const Run& run = problem.runs[r];
        const auto sens =
            model::simulate_sensitivities(m, directions, run.inputs, options_for(run, problem.sim));
        if (!sens) {
          ok = false;
          return;
        }
        const auto sim = as_measured(sens->value, run);
        std::vector<std::vector<std::vector<double>>> d;
        for (const model::Outputs& dj : sens->d) d.push_back(as_measured(dj, run));
        auto k = static_cast<Eigen::Index>(offset[r]);
        for (std::size_t o = 0; o < run.outputs.size(); ++o) {
          const auto& y = run.measured[o];
          for (std::size_t n = 0; n < y.size(); ++n, ++k) {
            const bool measured = std::isfinite(y[n]);
            out[k] = measured ? (sim[o][n] - y[n]) / norm[r][o] : 0.0;
            for (std::size_t j = 0; j < d.size(); ++j)
              jac(k, static_cast<Eigen::Index>(j)) = measured ? d[j][o][n] / norm[r][o] : 0.0;
          }
        }
      });
      return ok.load();
    };
  }

  FitResult result;
  result.nls = least_squares(specs, total, residual, nls);
  for (std::size_t i = 0; i < specs.size(); ++i) {
    auto& v = result.nls.values[static_cast<Eigen::Index>(i)];
    v = in_range(i, v);
  }
  if (problem.jackknife_stretches > 1 && problem.jackknife_linearised) {
    result.se_jackknife = linear_jackknife(result.nls, problem, offset);
    if (!result.se_jackknife.empty()) result.jackknife_stretches = problem.jackknife_stretches;
  } else if (problem.jackknife_stretches > 1 && result.nls.converged) {
    result.se_jackknife = jackknife(specs, total, residual, problem, offset, result.nls.values);
    if (!result.se_jackknife.empty()) result.jackknife_stretches = problem.jackknife_stretches;
  }
  result.model = problem.model;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    model::set_parameter(result.model, specs[i].name, result.nls.values[static_cast<Eigen::Index>(i)]);
  }
  apply_ties(result.model, problem.ties);
  // A fit its time budget stopped starts no further simulation: the caller reports it cut short.
  if (!result.nls.stopped && problem.evaluate_runs)
    result.runs = evaluate_model(result.model, problem.runs, problem.sim);
  result.se_widening = ar1_widening(result.nls.residuals, problem.runs);
  fit_warnings(result.nls, bounds, periods, units, result);
  return result;
}

double ar1_widening(const Eigen::VectorXd& residuals, const std::vector<Run>& runs) {
  // Lag-1 autocorrelation of the residuals within each (run, output) block.
  double lag0 = 0.0;
  double lag1 = 0.0;
  Eigen::Index at = 0;
  for (const Run& run : runs) {
    for (const auto& y : run.measured) {
      const auto len = static_cast<Eigen::Index>(y.size());
      for (Eigen::Index k = 0; k < len && at + k < residuals.size(); ++k) {
        const double r = residuals[at + k];
        lag0 += r * r;
        if (k > 0) lag1 += r * residuals[at + k - 1];
      }
      at += len;
    }
  }
  const double rho = lag0 > 0.0 ? std::clamp(lag1 / lag0, 0.0, 0.9999) : 0.0;
  return std::sqrt((1.0 + rho) / (1.0 - rho));
}

std::string pinned_text(const PinnedParameter& pin) {
  return fmt::format("{} = {:.6g} {}", pin.name, config::without_negative_zero(pin.value), pin.why);
}

std::vector<PinnedParameter> undetermined_pins(
    const std::vector<FitFlag>& flags, const std::vector<std::string>& names,
    const std::vector<double>& std_errors,
    const std::function<std::optional<double>(const std::string&)>& given) {
  const auto infinite_error = [&](const std::string& name) {
    const auto it = std::find(names.begin(), names.end(), name);
    const auto k = static_cast<std::size_t>(it - names.begin());
    return it != names.end() && k < std_errors.size() && !std::isfinite(std_errors[k]);
  };
  std::vector<PinnedParameter> pins;
  const auto pinned = [&](const std::string& name) {
    return std::any_of(pins.begin(), pins.end(), [&](const PinnedParameter& p) { return p.name == name; });
  };
  for (const FitFlag& f : flags) {
    if (f.names.size() != 1 || pinned(f.names.front())) continue;
    const std::string& name = f.names.front();
    if (f.kind == FitFlag::Kind::at_bound && f.bound == 0.0) {
      pins.push_back({name, 0.0, std::string(k_pinned_bound)});
    } else if (f.kind == FitFlag::Kind::undetermined ||
               (f.kind == FitFlag::Kind::at_bound && infinite_error(name))) {
      if (const std::optional<double> value = given(name))
        pins.push_back({name, *value, std::string(k_pinned_given)});
    }
  }
  return pins;
}

bool pin_costs_nothing(const FitResult& free, const FitResult& held) {
  const auto residuals = static_cast<double>(free.nls.residuals.size());
  if (!(residuals > 0.0) || !std::isfinite(held.nls.cost)) return false;
  return held.nls.cost <= free.nls.cost * (1.0 + free.se_widening * free.se_widening / residuals);
}

FitResult pin_undetermined(const FitProblem& problem, FitResult first,
                           const std::function<std::optional<double>(const std::string&)>& given) {
  if (first.nls.stopped) return first;
  std::vector<double> se;
  for (std::size_t k = 0; k < first.nls.names.size(); ++k) se.push_back(first.reported_se(k));
  std::vector<PinnedParameter> pins = undetermined_pins(first.flags, first.nls.names, se, given);
  if (pins.empty() || pins.size() >= problem.free.size()) return first;
  FitProblem held = problem;
  held.model = first.model;
  for (const PinnedParameter& pin : pins) {
    model::set_parameter(held.model, pin.name, pin.value);
    std::erase(held.free, pin.name);
  }
  FitResult refit = fit_model(held);
  if (!pin_costs_nothing(first, refit)) return first;
  refit.pinned = std::move(pins);
  return refit;
}

FitResult fit_model_pinned(const FitProblem& problem) {
  return pin_undetermined(problem, fit_model(problem), [&](const std::string& name) -> std::optional<double> {
    return model::get_parameter(problem.model, name);
  });
}

double rms_finite(std::span<const double> x) {
  double sq = 0.0;
  std::size_t count = 0;
  for (double v : x) {
    if (std::isfinite(v)) {
      sq += v * v;
      ++count;
    }
  }
  return count > 0 ? std::sqrt(sq / static_cast<double>(count)) : k_nan;
}

}  // namespace mcg::fit
