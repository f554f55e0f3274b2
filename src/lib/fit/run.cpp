// mcg-fit friction, tf and model: reading the files, calling the fits, writing INI or CSV.
#include "fit/run.hpp"

#include "boardunits/plant_units.hpp"
#include "common/error.hpp"
#include "common/parallel.hpp"
#include "common/tool.hpp"
#include "config/ini.hpp"
#include "fit/greybox.hpp"
#include "mcg/version.hpp"
#include "model/model.hpp"
#include "table/table.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <iostream>
#include <mutex>
#include <optional>
#include <tuple>

namespace mcg::fit {

namespace {

/// Six significant digits: what the data supports, and readable in an INI file.
std::string num6(double x) { return fmt::format("{:.6g}", x); }

std::string se_comment(double se, std::string_view unit) {
  if (!std::isfinite(se)) return "not determined by the data";
  return unit.empty() ? "+- " + num6(se) : fmt::format("+- {} {}", num6(se), unit);
}

std::vector<table::Table> read_all(const std::vector<std::string>& files) {
  std::vector<table::Table> tables;
  tables.reserve(files.size());
  for (const auto& f : files) tables.push_back(table::read_path(f));
  return tables;
}

void write_friction(config::Ini& ini, const std::string& section, const FrictionTerm& term, std::string_view origin) {
  // A friction level cannot be negative (the model rejects it); a negative difference of two
  // totals is written as 0 and the estimate kept in the comment.
  const auto level = [&](const char* key, double value, double se, const std::string& note) {
    if (value >= 0.0) {
      ini.set(section, key, num6(value), se_comment(se, "N m" + note));
    } else {
      ini.set(section, key, "0", fmt::format("estimate {} {} is below 0{}", num6(value), se_comment(se, "N m"), note));
    }
  };
  level("Ts_Nm", term.value.Ts_Nm, term.se.Ts_Nm, ", " + std::string(origin));
  level("Tc_Nm", term.value.Tc_Nm, term.se.Tc_Nm, "");
  static const char* const keys[3] = {"visc1_Nm_s_rad", "visc2_Nm_s2_rad2", "visc3_Nm_s3_rad3"};
  static const char* const units[3] = {"N m s/rad", "N m s^2/rad^2", "N m s^3/rad^3"};
  for (std::size_t c = 0; c < 3; ++c) {
    ini.set(section, keys[c], num6(term.value.viscous[c]), se_comment(term.se.viscous[c], units[c]));
  }
}

/// "motor.J_kg_m2" -> the INI section and key model_to_ini() wrote it under.
std::optional<std::pair<std::string, std::string>> ini_place(const config::Ini& ini, const std::string& name) {
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

void write_model_ini(const FitResult& r, const FitProblem& problem, std::ostream& out) {
  config::Ini ini;
  model::model_to_ini(r.model, ini);
  const auto infos = model::parameters(r.model);
  const auto& n = r.nls;
  for (std::size_t i = 0; i < n.names.size(); ++i) {
    const auto place = ini_place(ini, n.names[i]);
    const auto k = static_cast<Eigen::Index>(i);
    if (place) ini.set(place->first, place->second, num6(n.values[k]), "fitted, " + se_comment(r.reported_se(i), unit_of(infos, n.names[i])));
  }
  for (const auto& [follower, leader] : problem.ties) {
    if (const auto place = ini_place(ini, follower)) {
      ini.set(place->first, place->second, num6(model::get_parameter(r.model, follower)), "tied to " + leader);
    }
  }
  const std::string sec = "fit.model";
  ini.set(sec, "source", fmt::format("mcg-fit {}", k_version));
  ini.set(sec, "converged", r.trustworthy() ? "yes" : "no");
  ini.set(sec, "reason", n.converged && !r.warnings.empty()
                             ? fmt::format("{}, but the numbers are not trustworthy (see the warnings)", n.reason)
                             : n.reason);
  for (std::size_t w = 0; w < r.warnings.size(); ++w) ini.set(sec, fmt::format("warning{}", w + 1), r.warnings[w]);
  ini.set(sec, "se_widening", num6(r.se_widening),
          "standard errors times this for the residuals' autocorrelation: sqrt((1 + rho) / (1 - rho))");
  ini.set(sec, "iterations", static_cast<double>(n.iterations));
  ini.set(sec, "evaluations", static_cast<double>(n.evaluations));
  std::string free;
  for (const auto& name : n.names) free += (free.empty() ? "" : " ") + name;
  ini.set(sec, "free", free);
  for (const auto& [follower, leader] : problem.ties) ini.set(sec, "tie." + follower, leader);
  for (std::size_t i = 0; i < n.names.size(); ++i) {
    const auto k = static_cast<Eigen::Index>(i);
    ini.set(sec, n.names[i], num6(n.values[k]));
    ini.set(sec, n.names[i] + ".se", num6(r.reported_se(i)));
  }
  for (std::size_t i = 0; i < n.names.size(); ++i) {
    std::string row;
    for (std::size_t j = 0; j < n.names.size(); ++j) {
      row += (j == 0 ? "" : " ") + fmt::format("{:.3f}", n.correlation(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)));
    }
    ini.set(sec, "correlation." + n.names[i], row, i == 0 ? "rows of the correlation matrix, columns in the order of free" : "");
  }
  for (std::size_t f = 0; f < r.runs.size(); ++f) {
    const auto& run = r.runs[f];
    ini.set(sec, fmt::format("file{}", f + 1), run.source);
    for (std::size_t k = 0; k < run.outputs.size(); ++k) {
      ini.set(sec, fmt::format("file{}.fit_{}", f + 1, run.outputs[k]), fmt::format("{:.2f}", run.fit_percent[k]),
              "% (NRMSE, as MATLAB compare)");
      ini.set(sec, fmt::format("file{}.rms_{}", f + 1, run.outputs[k]), num6(run.rms[k]));
    }
  }
  ini.write(out);
}

}  // namespace

void run_friction(const FrictionRunOptions& options, std::ostream& out) {
  if (options.files.empty()) fail("friction: no input files");
  const model::Params base = model::from_ini(config::Ini::load_all(options.config));
  if (options.linear && (options.fit.torque_column.empty() || options.fit.position_column.empty())) {
    fail("--linear: needs --torque (a force column, N) and --position (m)");
  }
  const FrictionResult result = fit_friction(read_all(options.files), base, options.fit);
  config::Ini ini;
  if (!options.linear && result.motor) {
    write_friction(ini, "motor", *result.motor, "state 0");
    write_friction(ini, "generator", *result.motor, "= motor (equivalent machines)");
  }
  if (!options.linear && result.clutch_disengaged) {
    write_friction(ini, "clutch_disengaged", *result.clutch_disengaged, "state 1 - motor");
  }
  if (!options.linear && result.clutch_engaged) {
    write_friction(ini, "clutch_engaged", *result.clutch_engaged, "state 2 - motor - generator");
  }
  const std::string sec = "fit.friction";
  ini.set(sec, "source", fmt::format("mcg-fit {}", k_version));
  ini.set(sec, "order", static_cast<double>(options.fit.order));
  for (const auto& st : result.states) {
    const std::string p = fmt::format("state{}.", st.clutch);
    ini.set(sec, p + "windows", static_cast<double>(st.windows), "quasi-steady windows while moving");
    ini.set(sec, p + "breakaways", static_cast<double>(st.breakaways), "starts from rest");
    const bool lin = options.linear;
    const char* const torque_unit = lin ? "N" : "N m";
    const char* const torque_key = lin ? "_N" : "_Nm";
    ini.set(sec, p + (lin ? "speed_range_m_s" : "speed_range_rad_s"),
            fmt::format("{} {}", num6(st.omega_min_rad_s), num6(st.omega_max_rad_s)));
    ini.set(sec, p + "torque_from",
            !options.fit.torque_column.empty() ? "column " + options.fit.torque_column
                                               : (st.from_current ? "current" : "voltage balance"));
    ini.set(sec, p + "total_Ts" + torque_key, num6(st.total.value.Ts_Nm), se_comment(st.total.se.Ts_Nm, torque_unit));
    ini.set(sec, p + "total_Tc" + torque_key, num6(st.total.value.Tc_Nm), se_comment(st.total.se.Tc_Nm, torque_unit));
    if (lin) {
      static const char* const keys[3] = {"total_visc1_N_s_m", "total_visc2_N_s2_m2", "total_visc3_N_s3_m3"};
      static const char* const units[3] = {"N s/m", "N s^2/m^2", "N s^3/m^3"};
      for (std::size_t c = 0; c < static_cast<std::size_t>(options.fit.order); ++c) {
        ini.set(sec, p + keys[c], num6(st.total.value.viscous[c]), se_comment(st.total.se.viscous[c], units[c]));
      }
    }
    if (std::isfinite(st.inertia)) {
      ini.set(sec, p + (lin ? "mass_kg" : "inertia_kg_m2"), num6(st.inertia), se_comment(st.inertia_se, lin ? "kg" : "kg m^2"));
    }
    if (std::isfinite(st.offset)) {
      ini.set(sec, p + "offset" + torque_key, num6(st.offset), se_comment(st.offset_se, torque_unit));
    }
  }
  ini.write(out);
}

namespace {

/// Phase RMS (degrees) above which a fit without a delay is checked against the alternatives.
constexpr double k_tf_phase_warn_deg = 5.0;

/// The mcg-fit tf command line of `o` on `file`.
std::string tf_command(const TfFitOptions& o, const std::string& file) {
  std::string cmd = fmt::format("mcg-fit tf --poles {}", o.poles);
  if (o.zeros > 0) cmd += fmt::format(" --zeros {}", o.zeros);
  if (o.f_min_hz > 0.0) cmd += fmt::format(" --f-min {}", config::format_number(o.f_min_hz));
  if (o.f_max_hz < 1e300) cmd += fmt::format(" --f-max {}", config::format_number(o.f_max_hz));
  if (!o.use_coherence) cmd += " --no-coherence";
  if (o.fit_delay) cmd += " --delay";
  return cmd + (file == "-" ? "" : " " + file);
}

void check_phase_residual(const FrequencyResponse& fr, const TfRunOptions& options, const TfFit& fit, std::ostream& err) {
  if (options.fit.fit_delay || !(fit.rms_phase_deg > k_tf_phase_warn_deg)) return;
  std::vector<TfFitOptions> alternatives;
  TfFitOptions delayed = options.fit;
  delayed.fit_delay = true;
  alternatives.push_back(delayed);
  if (options.fit.poles < 12) {
    TfFitOptions more = options.fit;
    ++more.poles;
    alternatives.push_back(more);
  }
  double best_rms = fit.rms_phase_deg;
  std::string best;
  for (const TfFitOptions& alt : alternatives) {
    try {
      const TfFit f = fit_tf(fr, alt);
      if (f.rms_phase_deg < 0.5 * best_rms) {
        best_rms = f.rms_phase_deg;
        best = tf_command(alt, options.file);
      }
    } catch (const Error&) {
      // An alternative that cannot be fitted (too few points for more poles) is no advice.
    }
  }
  if (best.empty()) return;
  err << fmt::format(
      "mcg-fit: warning: the fit leaves {:.3g} degrees RMS of phase (sampled data lag: a zero-order hold alone "
      "by half a sample period); `{}` leaves {:.3g}\n",
      fit.rms_phase_deg, best, best_rms);
}

}  // namespace

namespace {

/// The fit's `[plant] maps` and the words for its comment: the response's units (its metadata or
/// --units), canonical when they are a plant's; refused when neither says.
std::pair<std::string, std::string> fitted_units(const FrequencyResponse& fr, const std::string& given) {
  const auto known = [](const std::string& text) { return boardunits::parse_plant_units(text); };
  const auto canonical = [&](const std::string& text) {
    const auto u = known(text);
    return u ? boardunits::units_text(*u) : text;
  };
  if (!given.empty() && !known(given) && given.find("->") == std::string::npos) {
    fail(
        "--units: {} are not units of a response: give IN -> OUT (v -> rpm, duty -> rpm, v -> omega) or "
        "rpm/V, "
        "rad/s/V, rpm/duty",
        quote(given));
  }
  if (!given.empty() && !fr.units.empty() && canonical(given) != canonical(fr.units)) {
    fail("--units: {} disagrees with the response's {} ({})", quote(given), quote(fr.units), fr.source);
  }
  const std::string text = given.empty() ? fr.units : given;
  if (text.empty()) {
    fail(
        "{}: the response does not say its units (no '# response: IN -> OUT' line, as mcg-sweep bode writes "
        "it): "
        "give --units, e.g. --units 'v -> rpm'",
        fr.source);
  }
  if (const auto u = known(text)) return {boardunits::units_text(*u), boardunits::units_words(*u)};
  return {text, "units mcg-design does not convert"};
}

/// [plant] and the Bode form's numbers of [fit.tf], the same for both kinds of data.
config::Ini plant_ini(const TfFit& fit, const TfFitOptions& o, const std::string& maps,
                      const std::string& words) {
  config::Ini ini;
  ini.set("plant", "tf", format_factored(fit), fmt::format("{}, {}", maps, words));
  std::string num;
  std::string den;
  for (double c : fit.tf.num) num += (num.empty() ? "" : " ") + config::format_number(c);
  for (double c : fit.tf.den) den += (den.empty() ? "" : " ") + config::format_number(c);
  ini.set("plant", "num", num, "descending powers of s");
  ini.set("plant", "den", den, "descending powers of s");
  ini.set("plant", "domain", "s");
  const bool physical = maps == boardunits::units_text({});
  ini.set("plant", "maps", maps,
          fmt::format("{}: mcg-design {}applies the loop chain", words,
                      physical ? "" : "converts it to rad/s per V and "));
  if (o.fit_delay) ini.set("plant", "delay_s", num6(fit.delay_s), se_comment(fit.delay_se, "s"));
  const std::string sec = "fit.tf";
  ini.set(sec, "source", fmt::format("mcg-fit {}", k_version));
  ini.set(sec, "poles", static_cast<double>(o.poles));
  ini.set(sec, "zeros", static_cast<double>(o.zeros));
  ini.set(sec, "gain", num6(fit.gain), se_comment(fit.gain_se, ""));
  const auto corners = [&](const std::vector<Factor>& list, const char* what) {
    for (std::size_t k = 0; k < list.size(); ++k) {
      const Factor& f = list[k];
      const std::string key = fmt::format("{}{}", what, k + 1);
      ini.set(sec, key + "_rad_s", num6(f.corner_rad_s),
              fmt::format("{}{}", se_comment(f.corner_se, "rad/s"),
                          f.complex_pair ? ", complex pair" : (f.unstable ? ", right half-plane" : "")));
      if (f.complex_pair) ini.set(sec, key + "_zeta", num6(f.zeta), se_comment(f.zeta_se, ""));
    }
  };
  corners(fit.poles, "pole");
  corners(fit.zeros, "zero");
  return ini;
}

/// The time-domain fit of run_tf.
void run_tf_time(const table::Table& table, const TfRunOptions& options, std::ostream& out,
                 std::ostream& err) {
  if (options.band_given) {
    fail("{}: --f-min, --f-max and --no-coherence apply to a frequency response; this is a time-domain run",
         table.source);
  }
  const std::string in = options.in_column.empty() ? "v" : options.in_column;
  const std::string out_col = options.out_column.empty()
                                  ? (table.has("rpm") || !table.has("omega") ? "rpm" : "omega")
                                  : options.out_column;
  const TimeSeries run = read_time_series(table, in, out_col);
  if (!run.skipped_note.empty()) err << "mcg-fit: note: " << run.skipped_note << '\n';
  FrequencyResponse columns;
  columns.source = run.source;
  columns.units = fmt::format("{} -> {}", in, out_col);
  const auto [maps, words] = fitted_units(columns, options.units);
  const TimeTfFit fit = fit_tf_time(run, options.fit);
  std::optional<double> held_out;
  if (!options.validate.empty()) {
    const TimeSeries other = read_time_series(table::read_path(options.validate), in, out_col);
    if (!other.skipped_note.empty()) err << "mcg-fit: note: " << other.skipped_note << '\n';
    held_out = validation_fit_percent(fit, other);
  }
  config::Ini ini = plant_ini(fit.fit, options.fit, maps, words);
  const std::string sec = "fit.tf";
  ini.set(sec, "data", fmt::format("time series, output error: {} -> {}", in, out_col));
  ini.set(sec, "samples", static_cast<double>(fit.fit.points));
  ini.set(sec, "dt_s", num6(run.dt_s), "s");
  ini.set(sec, "skipped_rows", static_cast<double>(run.skipped), "leading rows without a measured value");
  if (run.window_samples > 0) {
    ini.set(sec, "output_window_s", num6(static_cast<double>(run.window_samples) * run.dt_s),
            "the model's output averaged over the rpm_estimator's window");
  }
  ini.set(sec, "u_ref", num6(fit.u_ref),
          se_comment(fit.u_ref_se, in + ": the run starts settled at this input"));
  ini.set(sec, "y0", num6(fit.y0), se_comment(fit.y0_se, out_col + " there"));
  ini.set(sec, "fit_percent", num6(fit.fit_percent), "100 (1 - |y - y_hat| / |y - mean y|)");
  ini.set(sec, "rms", num6(fit.rms), out_col + ", y - y_hat");
  if (held_out) {
    ini.set(sec, "validate", options.validate);
    ini.set(sec, "validate_fit_percent", num6(*held_out), "the held-out run, its offset re-estimated");
  }
  ini.set(sec, "iterations", static_cast<double>(fit.fit.nls.iterations));
  ini.write(out);
}

}  // namespace

void run_tf(const TfRunOptions& options, std::ostream& out, std::ostream& err) {
  const table::Table table = table::read_path(options.file);
  if (!table.has("f_hz") && table.has("t")) {
    run_tf_time(table, options, out, err);
    return;
  }
  if (!options.in_column.empty() || !options.out_column.empty() || !options.validate.empty()) {
    fail("{}: --in, --out and --validate apply to a time-domain run; this is a frequency response",
         table.source);
  }
  const FrequencyResponse fr = read_frequency_response(table);
  const TfFit fit = fit_tf(fr, options.fit);
  const auto [maps, words] = fitted_units(fr, options.units);
  check_phase_residual(fr, options, fit, err);
  config::Ini ini = plant_ini(fit, options.fit, maps, words);
  const std::string sec = "fit.tf";
  ini.set(sec, "points", static_cast<double>(fit.points));
  ini.set(sec, "rms_mag_db", num6(fit.rms_mag_db));
  ini.set(sec, "rms_phase_deg", num6(fit.rms_phase_deg));
  ini.set(sec, "iterations", static_cast<double>(fit.nls.iterations));
  ini.write(out);
}

namespace {

/// One measured run of `mcg-fit model` as the options shape it.
Run load_model_run(const std::string& path, const ModelRunOptions& options, const model::Params& params) {
  Run run = make_run(select_time(table::read_path(path), options.from_s, options.to_s), options.outputs, params);
  run.gear_ratio = options.gear_ratio;
  return run;
}

std::vector<std::pair<std::string, std::string>> parse_ties(const std::vector<std::string>& items) {
  std::vector<std::pair<std::string, std::string>> ties;
  for (const auto& item : items) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == item.size()) fail("--tie: expected FOLLOWER=LEADER: {}", quote(item));
    ties.emplace_back(item.substr(0, eq), item.substr(eq + 1));
  }
  return ties;
}

void report_untrustworthy(const FitResult& r, const std::string& what, std::ostream& err) {
  for (const auto& w : r.warnings) err << fmt::format("mcg-fit: warning: {}{}\n", what, w);
}

}  // namespace

int run_model(const ModelRunOptions& options, std::ostream& out, std::ostream& err) {
  const config::Ini ini = config::Ini::load_all(options.config);
  model::Model base = model::model_from_ini(ini);
  const std::vector<std::string> fixed = fix_parameters(base, options.fix);
  FitProblem problem;
  problem.bounds = read_bounds(ini, base);
  if (options.list) {
    for (auto p : model::parameters(base)) {
      if (const auto it = problem.bounds.find(p.name); it != problem.bounds.end()) std::tie(p.lower, p.upper) = it->second;
      out << fmt::format("{} = {} ; {}, {}..{}\n", p.name, config::format_number(p.value), p.unit,
                         num6(p.lower), num6(p.upper));
    }
    return 0;
  }
  if (options.files.empty()) fail("model: no input files");
  if (!(options.from_s < options.to_s)) fail("--from {} s is not before --to {} s", options.from_s, options.to_s);
  problem.model = base;
  problem.ties = parse_ties(options.tie);
  problem.sim.max_step_s = options.max_step_s;
  problem.nls.max_evaluations = options.max_evaluations;
  const auto infos = model::parameters(base);
  const auto check_names = [&](const std::vector<std::string>& names) {
    for (const auto& name : names) {
      if (std::none_of(infos.begin(), infos.end(), [&](const auto& p) { return p.name == name; })) {
        fail("unknown parameter {} (see mcg-fit model --list)", quote(name));
      }
      if (std::find(fixed.begin(), fixed.end(), name) != fixed.end()) fail("parameter {} is fixed (--fix) and free", quote(name));
    }
  };
  check_names(options.free);

  if (options.evaluate) {
    std::vector<Run> runs;
    for (const auto& f : options.files) runs.push_back(load_model_run(f, options, base.params));
    model::Model m = base;
    for (const auto& [follower, leader] : problem.ties) model::set_parameter(m, follower, model::get_parameter(m, leader));
    const auto fits = evaluate_model(m, runs, problem.sim);
    config::Ini res;
    const std::string sec = "fit.evaluate";
    res.set(sec, "source", fmt::format("mcg-fit {}", k_version));
    for (std::size_t f = 0; f < fits.size(); ++f) {
      res.set(sec, fmt::format("file{}", f + 1), fits[f].source);
      for (std::size_t k = 0; k < fits[f].outputs.size(); ++k) {
        res.set(sec, fmt::format("file{}.fit_{}", f + 1, fits[f].outputs[k]), fmt::format("{:.2f}", fits[f].fit_percent[k]),
                "% (NRMSE, as MATLAB compare)");
        res.set(sec, fmt::format("file{}.rms_{}", f + 1, fits[f].outputs[k]), num6(fits[f].rms[k]));
      }
    }
    res.write(out);
    return 0;
  }

  if (!options.batch) {
    for (const auto& f : options.files) problem.runs.push_back(load_model_run(f, options, base.params));
    if (options.free.empty()) {
      problem.free = default_free(problem.runs, fixed, problem.ties);
    } else {
      problem.free = options.free;
    }
    problem.nls.threads = parallel::worker_count(options.threads, problem.free.size());
    const FitResult result = fit_model(problem);
    write_model_ini(result, problem, out);
    report_untrustworthy(result, "", err);
    if (!result.nls.converged) {
      err << fmt::format("mcg-fit: error: the fit did not converge: {} (after {} iterations)\n", result.nls.reason,
                         result.nls.iterations);
      return 3;
    }
    if (!result.trustworthy()) {
      err << fmt::format("mcg-fit: error: the fit converged but its numbers are not trustworthy ({} warnings)\n",
                         result.warnings.size());
      return 3;
    }
    return 0;
  }

  // Batch: one independent fit per file, in parallel, rows in input order.
  struct Outcome {
    std::optional<FitResult> result;
    std::string error;
  };
  const std::size_t count = options.files.size();
  std::vector<Outcome> outcomes(count);
  std::atomic<std::size_t> done{0};
  std::mutex progress_mutex;
  const bool progress = stderr_is_terminal() && &err == &std::cerr;
  // The runs first: the default free set depends on what all of them measure.
  std::vector<std::optional<Run>> runs(count);
  std::vector<Run> loaded;
  for (std::size_t k = 0; k < count; ++k) {
    try {
      runs[k] = load_model_run(options.files[k], options, base.params);
      loaded.push_back(*runs[k]);
    } catch (const Error& e) {
      outcomes[k].error = e.what();
    }
  }
  problem.free = options.free.empty() ? default_free(loaded, fixed, problem.ties) : options.free;
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
      err << fmt::format("\rmcg-fit: model: {}/{} files", finished, count) << std::flush;
    }
  });
  if (progress) err << '\n';

  std::vector<std::string> outputs = options.outputs;
  if (outputs.empty()) {
    for (const auto& o : outcomes) {
      if (!o.result) continue;
      for (const auto& name : o.result->runs[0].outputs) {
        if (std::find(outputs.begin(), outputs.end(), name) == outputs.end()) outputs.push_back(name);
      }
    }
  }
  table::Writer w(out);
  w.meta("source", fmt::format("mcg-fit {} model --batch", k_version));
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
  int status = 0;
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
        if (it != run.outputs.end()) fit = run.fit_percent[static_cast<std::size_t>(it - run.outputs.begin())];
      }
      row.push_back(fit);
    }
    row.push_back(o.result && o.result->trustworthy() ? 1.0 : 0.0);
    row.push_back(o.result ? static_cast<double>(o.result->nls.iterations) : nan);
    w.row(row);
  }
  w.finish();
  for (std::size_t k = 0; k < count; ++k) {
    const auto& o = outcomes[k];
    if (!o.result) {
      err << fmt::format("mcg-fit: error: {}\n", o.error);
      status = 1;
    } else if (!o.result->nls.converged) {
      err << fmt::format("mcg-fit: error: {}: the fit did not converge: {}\n", input_name(options.files[k]),
                         o.result->nls.reason);
      if (status == 0) status = 3;
    } else if (!o.result->trustworthy()) {
      report_untrustworthy(*o.result, input_name(options.files[k]) + ": ", err);
      err << fmt::format("mcg-fit: error: {}: the fit converged but its numbers are not trustworthy\n",
                         input_name(options.files[k]));
      if (status == 0) status = 3;
    }
  }
  return status;
}

}  // namespace mcg::fit
