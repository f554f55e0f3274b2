// mcg-fit model: the runs read, fit_model (one joint fit, or one per file), INI or CSV written.
#include "cmd/fit/model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <optional>
#include <tuple>

#include "cmd/fit/ini_text.hpp"
#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/quote.hpp"
#include "common/range.hpp"
#include "common/tool.hpp"
#include "config/ini.hpp"
#include "fit/greybox.hpp"
#include "mcg/version.hpp"
#include "model/model.hpp"
#include "table/table.hpp"

namespace mcg::cmd {

using namespace mcg::fit;

namespace {

/// "motor.J_kg_m2" -> the INI section and key model_to_ini() wrote it under.
std::optional<std::pair<std::string, std::string>> ini_place(const config::Ini& ini,
                                                             const std::string& name) {
  const auto dot = name.find('.');
  if (dot == std::string::npos) return std::nullopt;
  const std::string section = name.substr(0, dot);
  const std::string key = name.substr(dot + 1);
  if (ini.has(section, key)) return std::pair{section, key};
  if (ini.has("effect." + section, key)) return std::pair{"effect." + section, key};
  return std::nullopt;
}

std::string unit_of(const std::vector<model::ParamInfo>& infos, const std::string& name) {
  for (const auto& p : infos) {
    if (p.name == name) return p.unit;
  }
  return {};
}

void write_model_ini(const FitResult& r, const FitProblem& problem, const measurement::SpeedPath& speed,
                     Io& io) {
  config::Ini ini;
  model::model_to_ini(r.model, ini);
  measurement::speed_path_to_ini(speed, ini);
  const auto infos = model::parameters(r.model);
  const auto& n = r.nls;
  for (std::size_t i = 0; i < n.names.size(); ++i) {
    const auto place = ini_place(ini, n.names[i]);
    const auto k = static_cast<Eigen::Index>(i);
    const std::string unit = unit_of(infos, n.names[i]);
    // The larger of the two errors leads; both stand beside it.
    const std::string beside =
        i < r.se_jackknife.size() && std::isfinite(n.std_errors[k])
            ? fmt::format(" (jackknife over {} stretches {}; Jacobian, widened, {})", r.jackknife_stretches,
                          se_comment(r.se_jackknife[i], unit), se_comment(r.widened_se(i), unit))
            : "";
    if (place)
      ini.set(place->first, place->second, num6(n.values[k]),
              "fitted, " + se_comment(r.reported_se(i), unit) + beside);
  }
  for (const PinnedParameter& pin : r.pinned) {
    if (const auto place = ini_place(ini, pin.name))
      ini.set(place->first, place->second, num6(pin.value), pin.why);
  }
  for (const auto& [follower, leader] : problem.ties) {
    if (const auto place = ini_place(ini, follower)) {
      ini.set(place->first, place->second, num6(model::get_parameter(r.model, follower)),
              "tied to " + leader);
    }
  }
  const std::string sec = "fit.model";
  ini.set(sec, "source", fmt::format("{} {}", io.tool, k_version));
  ini.set(sec, "converged", r.trustworthy() ? "yes" : "no");
  ini.set(sec, "reason",
          n.converged && !r.warnings.empty()
              ? fmt::format("{}, but the numbers are not trustworthy (see the warnings)", n.reason)
              : n.reason);
  for (std::size_t w = 0; w < r.warnings.size(); ++w)
    ini.set(sec, fmt::format("warning{}", w + 1), r.warnings[w]);
  ini.set(
      sec, "se_widening", num6(r.se_widening),
      "Jacobian standard errors times this for the residuals' autocorrelation: sqrt((1 + rho) / (1 - rho))");
  if (!r.se_jackknife.empty())
    ini.set(sec, "se_jackknife_stretches", static_cast<double>(r.jackknife_stretches),
            "NAME.se_jackknife from a delete-one-stretch jackknife, NAME.se_jacobian the widened "
            "Jacobian's, NAME.se the larger");
  ini.set(sec, "iterations", static_cast<double>(n.iterations));
  ini.set(sec, "evaluations", static_cast<double>(n.evaluations));
  std::string free;
  for (const auto& name : n.names) free += (free.empty() ? "" : " ") + name;
  ini.set(sec, "free", free);
  if (!r.pinned.empty()) {
    std::string pinned;
    for (const PinnedParameter& pin : r.pinned) pinned += (pinned.empty() ? "" : " ") + pin.name;
    ini.set(sec, "pinned", pinned,
            "asked free, not set by the runs: held and the rest refitted without them");
    for (const PinnedParameter& pin : r.pinned) ini.set(sec, pin.name, num6(pin.value), pin.why);
  }
  for (const auto& [follower, leader] : problem.ties) ini.set(sec, "tie." + follower, leader);
  for (std::size_t i = 0; i < n.names.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    ini.set(sec, n.names[i], num6(n.values[k]));
    ini.set(sec, n.names[i] + ".se", num6(r.reported_se(i)));
    if (i < r.se_jackknife.size()) {
      ini.set(sec, n.names[i] + ".se_jackknife", num6(r.se_jackknife[i]));
      ini.set(sec, n.names[i] + ".se_jacobian", num6(r.widened_se(i)));
    }
  }
  for (std::size_t i = 0; i < n.names.size(); ++i) {
    std::string row;
    for (std::size_t j = 0; j < n.names.size(); ++j) {
      row += (j == 0 ? "" : " ") +
             fmt::format("{:.3f}", n.correlation(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)));
    }
    ini.set(sec, "correlation." + n.names[i], row,
            i == 0 ? "rows of the correlation matrix, columns in the order of free" : "");
  }
  for (std::size_t f = 0; f < r.runs.size(); ++f) {
    const auto& run = r.runs[f];
    ini.set(sec, fmt::format("file{}", f + 1), run.source);
    for (std::size_t k = 0; k < run.outputs.size(); ++k) {
      ini.set(sec, fmt::format("file{}.fit_{}", f + 1, run.outputs[k]),
              fmt::format("{:.2f}", run.fit_percent[k]), "% (NRMSE, as MATLAB compare)");
      ini.set(sec, fmt::format("file{}.rms_{}", f + 1, run.outputs[k]), num6(run.rms[k]));
    }
  }
  ini.write(io.out);
}

/// One measured run of `mcg-fit model` as the options shape it; `speed` is the INI's [measurement].
Run load_model_run(const std::string& path, const FitModelOptions& options, const model::Params& params,
                   const measurement::SpeedPath& speed) {
  Run run = make_run(select_time(with_speed_from_position(table::read_path(path), options.position_column),
                                 options.from_s, options.to_s),
                     options.outputs, params, 50, options.drive);
  apply_speed_path(run, speed, options.gear_ratio);
  return run;
}

std::vector<std::pair<std::string, std::string>> parse_ties(const std::vector<std::string>& items) {
  std::vector<std::pair<std::string, std::string>> ties;
  for (const auto& item : items) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == item.size())
      fail("--tie: expected FOLLOWER=LEADER: {}", quote(item));
    ties.emplace_back(item.substr(0, eq), item.substr(eq + 1));
  }
  return ties;
}

void report_untrustworthy(const FitResult& r, const std::string& what, Diagnostics& diag) {
  for (const PinnedParameter& pin : r.pinned) diag.note(what + pinned_text(pin));
  for (const auto& w : r.warnings) diag.warning(what + w);
}

/// --list: every parameter with its value, unit and bounds.
void list_parameters(const model::Model& base, const FitProblem& problem, std::ostream& out) {
  for (auto p : model::parameters(base)) {
    if (const auto it = problem.bounds.find(p.name); it != problem.bounds.end())
      std::tie(p.lower, p.upper) = it->second;
    out << fmt::format("{} = {} ; {}, {}..{}\n", p.name, config::format_number(p.value), p.unit,
                       num6(p.lower), num6(p.upper));
  }
}

/// --evaluate: fit % and RMS of the model as given on each run, as [fit.evaluate].
void evaluate(const model::Model& base, const FitProblem& problem, const measurement::SpeedPath& speed,
              const FitModelOptions& options, Io& io) {
  std::vector<Run> runs;
  for (const auto& f : options.files) runs.push_back(load_model_run(f, options, base.params, speed));
  model::Model m = base;
  for (const auto& [follower, leader] : problem.ties)
    model::set_parameter(m, follower, model::get_parameter(m, leader));
  const auto fits = evaluate_model(m, runs, problem.sim);
  config::Ini res;
  const std::string sec = "fit.evaluate";
  res.set(sec, "source", fmt::format("{} {}", io.tool, k_version));
  for (std::size_t f = 0; f < fits.size(); ++f) {
    res.set(sec, fmt::format("file{}", f + 1), fits[f].source);
    for (std::size_t k = 0; k < fits[f].outputs.size(); ++k) {
      res.set(sec, fmt::format("file{}.fit_{}", f + 1, fits[f].outputs[k]),
              fmt::format("{:.2f}", fits[f].fit_percent[k]), "% (NRMSE, as MATLAB compare)");
      res.set(sec, fmt::format("file{}.rms_{}", f + 1, fits[f].outputs[k]), num6(fits[f].rms[k]));
    }
  }
  res.write(io.out);
}

/// One joint fit of every run, as INI.
void fit_joint(const model::Model& base, FitProblem problem, const std::vector<std::string>& fixed,
               const measurement::SpeedPath& speed, const FitModelOptions& options, Io& io) {
  for (const auto& f : options.files) problem.runs.push_back(load_model_run(f, options, base.params, speed));
  if (options.free.empty()) {
    problem.free = default_free(problem.runs, fixed, problem.ties);
  } else {
    problem.free = options.free;
  }
  add_free_effects(problem.model, problem.free);
  problem.jackknife_stretches = options.jackknife;
  problem.nls.threads = parallel::worker_count(options.threads, problem.free.size());
  const FitResult result = fit_model_pinned(problem);
  write_model_ini(result, problem, speed, io);
  report_untrustworthy(result, "", io.diag);
  if (!result.nls.converged) {
    io.diag.error(fmt::format("the fit did not converge: {} (after {} iterations)", result.nls.reason,
                              result.nls.iterations),
                  k_untrustworthy_status);
  } else if (!result.trustworthy()) {
    io.diag.error(fmt::format("the fit converged but its numbers are not trustworthy ({} warnings)",
                              result.warnings.size()),
                  k_untrustworthy_status);
  }
}

/// The fit of one file of a batch, or why there is none.
struct Outcome {
  std::optional<FitResult> result;
  std::string error;
};

/// The batch's CSV: one row per file, in input order.
void write_batch(const std::vector<Outcome>& outcomes, const FitProblem& problem,
                 const FitModelOptions& options, Io& io) {
  const std::size_t count = outcomes.size();
  std::vector<std::string> outputs = options.outputs;
  if (outputs.empty()) {
    for (const auto& o : outcomes) {
      if (!o.result) continue;
      for (const auto& name : o.result->runs[0].outputs) {
        if (std::find(outputs.begin(), outputs.end(), name) == outputs.end()) outputs.push_back(name);
      }
    }
  }
  table::Writer w(io.out);
  w.meta("source", fmt::format("{} {} model --batch", io.tool, k_version));
  for (std::size_t k = 0; k < count; ++k) w.meta(fmt::format("file.{}", k + 1), input_name(options.files[k]));
  std::vector<std::string> header{"file"};
  for (const auto& name : problem.free) {
    header.push_back(name);
    header.push_back(name + ".se");
  }
  for (const auto& name : outputs) header.push_back("fit_" + name);
  header.push_back("converged");
  header.push_back("iterations");
  w.header(header);
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < count; ++k) {
    std::vector<double> row{static_cast<double>(k + 1)};
    const auto& o = outcomes[k];
    for (std::size_t i = 0; i < problem.free.size(); ++i) {
      const auto idx = static_cast<Eigen::Index>(i);
      row.push_back(o.result ? o.result->nls.values[idx] : nan);
      row.push_back(o.result ? o.result->reported_se(static_cast<std::size_t>(idx)) : nan);
    }
    for (const auto& name : outputs) {
      double fit = nan;
      if (o.result) {
        const auto& run = o.result->runs[0];
        const auto it = std::find(run.outputs.begin(), run.outputs.end(), name);
        if (it != run.outputs.end())
          fit = run.fit_percent[static_cast<std::size_t>(it - run.outputs.begin())];
      }
      row.push_back(fit);
    }
    row.push_back(o.result && o.result->trustworthy() ? 1.0 : 0.0);
    row.push_back(o.result ? static_cast<double>(o.result->nls.iterations) : nan);
    w.row(row);
  }
  w.finish();
}

/// --batch: one independent fit per file, in parallel; the CSV, then what failed.
void fit_batch(const model::Model& base, FitProblem problem, const std::vector<std::string>& fixed,
               const measurement::SpeedPath& speed, const FitModelOptions& options, Io& io) {
  const std::size_t count = options.files.size();
  std::vector<Outcome> outcomes(count);
  std::atomic<std::size_t> done{0};
  std::mutex progress_mutex;
  const bool progress = stderr_is_terminal() && &io.diag.stream() == &std::cerr;
  // The runs first: the default free set depends on what all of them measure.
  std::vector<std::optional<Run>> runs(count);
  std::vector<Run> loaded;
  for (std::size_t k = 0; k < count; ++k) {
    try {
      runs[k] = load_model_run(options.files[k], options, base.params, speed);
      loaded.push_back(*runs[k]);
    } catch (const Error& e) {
      outcomes[k].error = e.what();
    }
  }
  problem.free = options.free.empty() ? default_free(loaded, fixed, problem.ties) : options.free;
  add_free_effects(problem.model, problem.free);
  parallel::for_each(count, options.threads, [&](std::size_t k) {
    try {
      if (runs[k]) {
        FitProblem p = problem;
        p.runs.push_back(*runs[k]);
        outcomes[k].result = fit_model(p);
      }
    } catch (const Error& e) {
      outcomes[k].error = e.what();
    }
    const std::size_t finished = ++done;
    if (progress) {
      const std::lock_guard<std::mutex> lock(progress_mutex);
      io.diag.progress(fmt::format("model: {}/{} files", finished, count));
    }
  });
  if (progress) io.diag.end_progress();
  write_batch(outcomes, problem, options, io);
  for (std::size_t k = 0; k < count; ++k) {
    const auto& o = outcomes[k];
    const std::string file = input_name(options.files[k]);
    if (!o.result) {
      io.diag.error(o.error);
    } else if (!o.result->nls.converged) {
      io.diag.error(fmt::format("{}: the fit did not converge: {}", file, o.result->nls.reason),
                    k_untrustworthy_status);
    } else if (!o.result->trustworthy()) {
      report_untrustworthy(*o.result, file + ": ", io.diag);
      io.diag.error(fmt::format("{}: the fit converged but its numbers are not trustworthy", file),
                    k_untrustworthy_status);
    }
  }
}

}  // namespace

void add_jacobian_option(CLI::App* app, bool& sensitivities) {
  app->add_option_function<std::string>(
         "--jacobian", [&sensitivities](const std::string& how) { sensitivities = how == "sensitivities"; },
         "the solver's Jacobians: differences (a simulation per free parameter) or sensitivities "
         "(one simulation on dual numbers: exact, and slower; see mcg-fit(1))")
      ->check(CLI::IsMember({"differences", "sensitivities"}))
      ->default_str("differences");
}

void FitModel::define(CLI::App& app) {
  FitModelOptions& model = options;
  CLI::App* md = &app;
  md->add_option("--config", model.config,
                 "INI parameter set: initial and fixed values (repeatable, later files win)")
      ->allow_extra_args(false);
  md->add_option(
        "--free", model.free,
        "parameters to fit, comma separated (default from the data: J, R, Kt, Ke, Tc with a current, "
        "else J, Kt = Ke, Tc; driven: J, Tc, visc1; a drive's bias: friction_asymmetry.dT_Nm)")
      ->allow_extra_args(false)
      ->delimiter(',');
  md->add_option("--fix", model.fix, "measured parameters pinned, NAME=VALUE, comma separated")
      ->allow_extra_args(false)
      ->delimiter(',');
  md->add_option("--tie", model.tie, "FOLLOWER=LEADER: the follower takes the leader's fitted value")
      ->allow_extra_args(false)
      ->delimiter(',');
  md->add_flag("--evaluate", model.evaluate, "no fit: fit % and RMS of the given model on the runs");
  md->add_option("--from", model.from_s, "use the rows of each run from this time on, s");
  md->add_option("--to", model.to_s, "use the rows of each run up to this time, s");
  md->add_option("--gear-ratio", model.gear_ratio,
                 "motor turns per turn of the shaft whose speed was measured (default: the captures' "
                 "gear_ratio, else the INI's [measurement], else 1)")
      ->check(mcg::Range(1e-6, 1e6));
  md->add_flag("--current", model.drive.current,
               "current-driven drive: the i column is the current loop's command, A (not compared)");
  md->add_option("--torque", model.drive.torque_column,
                 "torque-driven drive: this column is the drive torque, N m at the measured shaft (N with a "
                 "linear axis' gear ratio in rad/m)")
      ->excludes("--current");
  md->add_option("--position", model.position_column,
                 "column holding the position (rad; m on a linear axis): speed by central differences");
  md->add_option("--outputs", model.outputs,
                 "measured columns compared (default: rpm and each varying i, i_gen, v_gen)")
      ->allow_extra_args(false)
      ->delimiter(',');
  md->add_flag("--batch", model.batch, "one fit per file, one CSV row each, files in parallel");
  md->add_flag("--list", model.list, "list the parameter names, values, units and bounds, then stop");
  md->add_option("--threads", model.threads, "worker threads (0 = every core)")
      ->check(mcg::Range(0, 1024))
      ->capture_default_str();
  md->add_option("--max-step", model.max_step_s, "integrator step bound during the fit, s")
      ->check(mcg::Range(1e-6, 1e-3))
      ->capture_default_str();
  md->add_option("--max-evaluations", model.max_evaluations, "simulation budget of the solver")
      ->check(mcg::Range(1, 1000000))
      ->capture_default_str();
  md->add_option("--jackknife", model.jackknife,
                 "standard errors from a jackknife leaving out each of this many stretches of the runs "
                 "in turn (0: the Jacobian's only)")
      ->check(mcg::Range(0, 100))
      ->capture_default_str();
  add_jacobian_option(md, model.sensitivities);
  md->add_option("files", model.files, "measured runs ('-' = stdin)");
}

int FitModel::run(Io& io) {
  const config::Ini ini = config::Ini::load_all(options.config);
  model::Model base = model::model_from_ini(ini);
  const std::vector<std::string> fixed = fix_parameters(base, options.fix);
  // The model's own gear ratio and speed filter; --gear-ratio overrides the ratio for these runs.
  measurement::SpeedPath speed = measurement::speed_path_from_ini(ini);
  if (options.gear_ratio) speed.gear_ratio = options.gear_ratio;
  FitProblem problem;
  problem.bounds = read_bounds(ini, base);
  if (options.list) {
    list_parameters(base, problem, io.out);
    return 0;
  }
  if (options.files.empty()) fail("model: no input files");
  if (!(options.from_s < options.to_s))
    fail("--from {} s is not before --to {} s", options.from_s, options.to_s);
  problem.model = base;
  problem.sensitivities = options.sensitivities;
  problem.ties = parse_ties(options.tie);
  problem.sim.max_step_s = options.max_step_s;
  problem.nls.max_evaluations = options.max_evaluations;
  model::Model with_free = base;
  add_free_effects(with_free, options.free);
  const auto infos = model::parameters(with_free);
  for (const auto& name : options.free) {
    if (std::none_of(infos.begin(), infos.end(), [&](const auto& p) { return p.name == name; })) {
      fail("unknown parameter {} (see {} model --list)", quote(name), io.tool);
    }
    if (std::find(fixed.begin(), fixed.end(), name) != fixed.end())
      fail("parameter {} is fixed (--fix) and free", quote(name));
  }
  if (options.evaluate) {
    evaluate(base, problem, speed, options, io);
  } else if (options.batch) {
    fit_batch(base, problem, fixed, speed, options, io);
  } else {
    fit_joint(base, problem, fixed, speed, options, io);
  }
  return 0;
}

}  // namespace mcg::cmd
