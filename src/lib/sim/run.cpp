// mcg-sim: read inputs, simulate open or closed loop, add measurement effects, write the table.
#include "sim/run.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <ostream>
#include <random>

#include "common/error.hpp"
#include "config/ini.hpp"
#include "mcg/version.hpp"
#include "model/model.hpp"
#include "sim/controller.hpp"
#include "sim/encoder.hpp"
#include "table/table.hpp"

namespace mcg::sim {

namespace {

/// The board's current measurement: 1 ohm shunt, 10-bit ADC over 0..5 V, 2.5 V offset.
double adc_current(double i_A) {
  const double code = std::clamp(std::round((i_A + 2.5) / 5.0 * 1024.0), 0.0, 1023.0);
  return code * 5.0 / 1024.0 - 2.5;
}

std::string join(const std::vector<std::string>& parts, std::string_view sep) {
  std::string out;
  for (const auto& p : parts) {
    if (!out.empty()) out += sep;
    out += p;
  }
  return out;
}

std::string coefficient_list(const std::vector<double>& v) {
  std::vector<std::string> parts;
  for (double x : v) parts.push_back(config::format_number(x));
  return join(parts, " ");
}

/// Column `name` of `tbl`, or a constant column of `fallback`.
std::vector<double> column_or(const table::Table& tbl, std::string_view name, double fallback) {
  if (tbl.has(name)) return tbl.col(name);
  return std::vector<double>(tbl.rows(), fallback);
}

void check_states(const table::Table& tbl, const std::vector<double>& clutch, const std::vector<double>& r_load) {
  for (std::size_t r = 0; r < clutch.size(); ++r) {
    const double c = clutch[r];
    if (!(c == 0.0 || c == 1.0 || c == 2.0)) {
      fail("{}:{}: column 'clutch': {} is not a clutch state (0, 1 or 2)", tbl.source, tbl.line_of(r),
           config::format_number(c));
    }
    if (std::isnan(r_load[r]) || r_load[r] < 0.0) {
      fail("{}:{}: column 'r_load': {} is not a load (>= 0 ohm, inf = open circuit)", tbl.source,
           tbl.line_of(r), config::format_number(r_load[r]));
    }
  }
}

}  // namespace

void run(const RunOptions& opt, std::istream& in, const std::string& source, std::ostream& out) {
  const config::Ini ini = config::Ini::load_all(opt.configs);
  model::Model model = model::model_from_ini(ini);
  for (const auto& text : opt.effects) {
    model::Effect effect = model::parse_effect(text, "--effect");
    auto it = std::find_if(model.effects.begin(), model.effects.end(),
                           [&](const model::Effect& e) { return e.name == effect.name; });
    if (it != model.effects.end()) {
      *it = effect;
    } else {
      model.effects.push_back(effect);
    }
  }
  const std::optional<Controller> configured = controller_from_ini(ini);

  table::Table tbl = table::read(in, source);
  if (tbl.rows() == 0) fail("{}: no data rows", source);
  const bool closed = tbl.has("rpm_cmd") && !opt.open_loop;
  table::require_increasing(tbl, "t");
  const double supply = model.params.supply_V;
  std::vector<double> v_in;
  if (!closed) {
    if (tbl.has("v")) {
      table::require_finite(tbl, "v");
      v_in = tbl.col("v");
    } else if (tbl.has("duty")) {
      table::require_finite(tbl, "duty");
      v_in = tbl.col("duty");
      for (double& x : v_in) x *= supply;
    } else {
      tbl.col("v");  // throws the missing-column error naming the columns present
    }
  } else {
    table::require_finite(tbl, "rpm_cmd");
  }
  if (tbl.has("clutch")) table::require_finite(tbl, "clutch");
  const std::vector<double> clutch = column_or(tbl, "clutch", opt.clutch);
  const std::vector<double> r_load = column_or(tbl, "r_load", opt.r_load_ohm);
  check_states(tbl, clutch, r_load);

  model::SimOptions sim_opt;
  sim_opt.max_step_s = opt.max_step_s;
  const CountEstimator estimator{opt.window_s, opt.counts_per_rev};
  const std::vector<double>& t = tbl.col("t");
  model::Outputs o;
  std::vector<double> duty;
  std::vector<double> v_applied;
  Controller controller = configured.value_or(report_pi());
  if (closed) {
    ClosedLoopOutputs cl =
        simulate_closed_loop(model, controller, estimator, {t, tbl.col("rpm_cmd"), clutch, r_load}, sim_opt);
    o = std::move(cl.plant);
    duty = std::move(cl.duty);
    v_applied = std::move(cl.v_V);
  } else {
    o = model::simulate(model, {t, v_in, clutch, r_load}, sim_opt);
  }

  std::vector<double> rpm = o.rpm;
  if (opt.encoder) rpm = estimate_rpm(t, o.theta_rad, estimator);
  std::vector<double> i_meas = o.i_A;
  std::vector<double> v_gen = o.v_gen_V;
  const bool noisy = opt.noise_i_A > 0.0 || opt.noise_v_gen_V > 0.0;
  if (noisy) {
    std::mt19937_64 rng(opt.seed);
    std::normal_distribution<double> unit(0.0, 1.0);
    for (std::size_t r = 0; r < i_meas.size(); ++r) {
      if (opt.noise_i_A > 0.0) i_meas[r] += opt.noise_i_A * unit(rng);
      if (opt.noise_v_gen_V > 0.0) v_gen[r] += opt.noise_v_gen_V * unit(rng);
    }
  }
  if (opt.adc) {
    for (double& x : i_meas) x = adc_current(x);
  }

  // The output: the input columns (replaced where the simulation writes the same name),
  // then the new ones.
  table::Table result;
  result.source = source;
  result.meta = tbl.meta;
  result.names = tbl.names;
  result.columns = tbl.columns;
  if (!tbl.has("clutch")) result.set("clutch", clutch);
  if (!tbl.has("r_load")) result.set("r_load", r_load);
  if (closed) {
    result.set("duty", duty);
    result.set("v", v_applied);
  }
  result.set("omega", o.omega_rad_s);
  result.set("rpm", rpm);
  if (opt.encoder) result.set("rpm_true", o.rpm);
  result.set("i", i_meas);
  result.set("i_gen", o.i_gen_A);
  result.set("v_gen", v_gen);
  result.set("theta", o.theta_rad);

  auto& meta = result.meta;
  meta.set("source", fmt::format("mcg-sim {}", k_version));
  meta.set("model", opt.configs.empty() ? std::string("built-in rig (the report's, tuned friction)")
                                        : join(opt.configs, " + "));
  std::vector<std::string> effect_texts;
  for (const auto& e : model.effects) effect_texts.push_back(model::format_effect(e));
  meta.set("effects", effect_texts.empty() ? std::string("none") : join(effect_texts, "; "));
  const std::string drive_name = closed ? "rpm_cmd" : (tbl.has("v") ? "v" : "duty");
  meta.set("timing", fmt::format("{}, clutch, r_load of row n act over [t(n), t(n+1)); rpm, i, v_gen sampled at t(n){}",
                                 drive_name, closed ? "; duty, v: the controller's output at t(n), held to t(n+1)" : ""));
  meta.set("initial_state", fmt::format("at rest, t = {}", config::format_number(t.front())));
  meta.erase("rpm_estimator");
  meta.erase("encoder");
  meta.erase("i_measurement");
  meta.erase("v_gen_measurement");
  meta.erase("seed");
  if (opt.encoder) {
    meta.set("rpm_estimator", format_rpm_estimator(estimator));
    meta.set("encoder", opt.counts_per_rev == 2048.0
                            ? std::string("512 lines, x4 quadrature decoding = 2048 counts/rev")
                            : fmt::format("{} counts/rev", config::format_number(opt.counts_per_rev)));
  }
  if (noisy || opt.adc) {
    std::string text = opt.adc ? "1 ohm shunt, 10-bit ADC over 0-5 V with 2.5 V mid-scale offset (range "
                                 "-2.5..2.495 A, saturates)"
                               : "simulated";
    if (opt.noise_i_A > 0.0) text += fmt::format(", noise sigma {} A", config::format_number(opt.noise_i_A));
    meta.set("i_measurement", text);
  }
  if (opt.noise_v_gen_V > 0.0) {
    meta.set("v_gen_measurement", fmt::format("noise sigma {} V", config::format_number(opt.noise_v_gen_V)));
  }
  if (noisy) meta.set("seed", std::to_string(opt.seed));
  if (closed) {
    meta.set("controller",
             fmt::format("{}{}: b = {}, a = {}, dt_s = {}, input_scale = {}, duty_full_scale = {}, "
                         "duty_resolution = {}, rpm from {}",
                         controller.type, configured ? "" : " (built-in: the report's PI)",
                         coefficient_list(controller.b), coefficient_list(controller.a),
                         config::format_number(controller.dt_s), config::format_number(controller.input_scale),
                         config::format_number(controller.duty_full_scale),
                         config::format_number(controller.duty_resolution), format_rpm_estimator(estimator)));
  }
  table::write(out, result);
}

}  // namespace mcg::sim
