// Grey-box fit: simulation error minimised with Levenberg-Marquardt over named parameters.
#include "fit/greybox.hpp"

#include "common/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>

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

/// The ADC range in `# i_measurement:` ("... (range -2.5..2.495 A, saturates) ..."), if any.
std::optional<std::pair<double, double>> current_range(std::string_view text) {
  const auto at = text.find("range ");
  if (at == std::string_view::npos) return std::nullopt;
  const char* p = text.data() + at + 6;
  const char* end = text.data() + text.size();
  double lo = 0.0;
  double hi = 0.0;
  auto r = std::from_chars(p, end, lo);
  if (r.ec != std::errc{} || end - r.ptr < 2 || r.ptr[0] != '.' || r.ptr[1] != '.') return std::nullopt;
  r = std::from_chars(r.ptr + 2, end, hi);
  if (r.ec != std::errc{} || !(lo < hi)) return std::nullopt;
  return std::pair{lo, hi};
}

}  // namespace

std::vector<double> window_average_rpm(const std::vector<double>& t_s, const std::vector<double>& theta_rad,
                                       const sim::CountEstimator& estimator) {
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
             std::size_t min_rows) {
  Run run;
  run.source = table.source;
  run.first_line = table.first_line;
  table::require_increasing(table, "t");
  run.inputs.t_s = table.col("t");
  if (!table.has("v") && table.has("duty")) {
    run.inputs.v_V = table.col("duty");
    for (double& v : run.inputs.v_V) v *= params.supply_V;
  } else {
    run.inputs.v_V = table.col("v");
  }
  run.inputs.clutch = table.col("clutch");
  run.inputs.r_load_ohm = table.col("r_load");
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
      if (table.has(name) && varies(name) && (generator || !of_generator)) run.outputs.push_back(name);
    }
    if (run.outputs.empty()) {
      fail("{}: no measured column to compare with the model (one of rpm, i, i_gen, v_gen, omega)", table.source);
    }
  } else {
    for (const auto& name : outputs) {
      if (std::find(measurable_columns().begin(), measurable_columns().end(), name) == measurable_columns().end()) {
        fail("unknown output '{}' (one of rpm, i, i_gen, v_gen, omega)", name);
      }
      run.outputs.push_back(name);
    }
  }
  for (const auto& name : run.outputs) run.measured.push_back(table.col(name));
  // A saturated current reading says only "at least this much": not measured.
  const auto range = table.meta.get("i_measurement");
  const auto limits = range ? current_range(*range) : std::nullopt;
  for (std::size_t o = 0; o < run.outputs.size() && limits; ++o) {
    if (run.outputs[o] != "i") continue;
    for (double& y : run.measured[o]) {
      if (y <= limits->first || y >= limits->second) y = k_nan;
    }
  }
  if (const auto text = table.meta.get("rpm_estimator")) {
    run.rpm_estimator = sim::parse_rpm_estimator(*text, table.source);
  }
  return run;
}

std::vector<std::vector<double>> simulate_as_measured(const model::Model& model, const Run& run,
                                                      const model::SimOptions& options) {
  const model::Outputs out = model::simulate(model, run.inputs, options);
  std::vector<std::vector<double>> series;
  series.reserve(run.outputs.size());
  for (const auto& name : run.outputs) {
    if (name == "rpm" && run.rpm_estimator) {
      series.push_back(window_average_rpm(run.inputs.t_s, out.theta_rad, *run.rpm_estimator));
    } else {
      series.push_back(pick(out, name));
    }
  }
  return series;
}

double fit_percent(const std::vector<double>& measured, const std::vector<double>& simulated) {
  std::size_t count = 0;
  const double mean = mean_of_finite(measured, count);
  double err = 0.0;
  double spread = 0.0;
  for (std::size_t k = 0; k < measured.size(); ++k) {
    if (!std::isfinite(measured[k])) continue;
    err += (measured[k] - simulated[k]) * (measured[k] - simulated[k]);
    spread += (measured[k] - mean) * (measured[k] - mean);
  }
  if (spread == 0.0) return err == 0.0 ? 100.0 : -std::numeric_limits<double>::infinity();
  return 100.0 * (1.0 - std::sqrt(err / spread));
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

FitResult fit_model(const FitProblem& problem) {
  if (problem.runs.empty()) fail("nothing to fit: no runs");
  const std::vector<model::ParamInfo> infos = model::parameters(problem.model);
  std::vector<ParameterSpec> specs;
  std::vector<std::pair<double, double>> bounds;
  std::set<std::string> seen;
  for (const auto& name : problem.free) {
    if (!seen.insert(name).second) fail("parameter '{}' is listed twice", name);
    const auto it = std::find_if(infos.begin(), infos.end(), [&](const auto& p) { return p.name == name; });
    if (it == infos.end()) fail("unknown parameter '{}' (see mcg-fit model --list)", name);
    if (!(it->value >= it->lower && it->value <= it->upper)) {
      fail("parameter '{}': initial value {} is outside [{}, {}]", name, it->value, it->lower, it->upper);
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
  }

  // Per (run, output): the normalisation std(y) sqrt(N) and the offset of its block.
  std::vector<std::vector<double>> norm(problem.runs.size());
  std::size_t total = 0;
  for (std::size_t r = 0; r < problem.runs.size(); ++r) {
    const Run& run = problem.runs[r];
    for (std::size_t o = 0; o < run.outputs.size(); ++o) {
      std::size_t count = 0;
      const double mean = mean_of_finite(run.measured[o], count);
      double sq = 0.0;
      for (double y : run.measured[o]) {
        if (std::isfinite(y)) sq += (y - mean) * (y - mean);
      }
      if (count < 2 || sq == 0.0) {
        fail("{}: column '{}' is constant: no excitation to fit", run.source, run.outputs[o]);
      }
      norm[r].push_back(std::sqrt(sq));
      total += run.measured[o].size();
    }
  }

  const ResidualFunction residual = [&](const Eigen::VectorXd& p, Eigen::VectorXd& out) {
    model::Model m = problem.model;
    for (std::size_t i = 0; i < specs.size(); ++i) {
      const double v = p[static_cast<Eigen::Index>(i)];
      if (!(v >= bounds[i].first && v <= bounds[i].second)) {
        out.setConstant(k_nan);
        return;
      }
      model::set_parameter(m, specs[i].name, v);
    }
    Eigen::Index k = 0;
    for (std::size_t r = 0; r < problem.runs.size(); ++r) {
      const Run& run = problem.runs[r];
      const auto sim = simulate_as_measured(m, run, problem.sim);
      for (std::size_t o = 0; o < run.outputs.size(); ++o) {
        const auto& y = run.measured[o];
        for (std::size_t n = 0; n < y.size(); ++n, ++k) {
          out[k] = std::isfinite(y[n]) ? (sim[o][n] - y[n]) / norm[r][o] : 0.0;
        }
      }
    }
  };

  FitResult result;
  result.nls = least_squares(specs, total, residual, problem.nls);
  result.model = problem.model;
  for (std::size_t i = 0; i < specs.size(); ++i) {
    model::set_parameter(result.model, specs[i].name, result.nls.values[static_cast<Eigen::Index>(i)]);
  }
  for (const Run& run : problem.runs) {
    const RunResiduals res = residuals(result.model, run, problem.sim);
    RunFit fit{run.source, run.outputs, res.fit_percent, {}};
    for (const auto& r : res.residual) fit.rms.push_back(rms_finite(r));
    result.runs.push_back(std::move(fit));
  }
  return result;
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
