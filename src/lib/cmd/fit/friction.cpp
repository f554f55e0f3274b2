// mcg-fit friction: the runs read, fit_friction, the stacked frictions written as INI.
#include "cmd/fit/friction.hpp"

#include <fmt/format.h>

#include <cmath>

#include "cmd/fit/ini_text.hpp"
#include "common/error.hpp"
#include "common/range.hpp"
#include "config/ini.hpp"
#include "mcg/version.hpp"
#include "measurement/measurement.hpp"
#include "model/effects/compiled.hpp"
#include "model/model.hpp"
#include "table/table.hpp"

namespace mcg::cmd {

using fit::fit_friction;
using fit::FrictionResult;
using fit::FrictionTerm;

namespace {

std::vector<table::Table> read_all(const std::vector<std::string>& files) {
  std::vector<table::Table> tables;
  tables.reserve(files.size());
  for (const auto& f : files) tables.push_back(table::read_path(f));
  return tables;
}

void write_friction(config::Ini& ini, const std::string& section, const FrictionTerm& term,
                    std::string_view origin) {
  // A friction level cannot be negative (the model rejects it); a negative difference of two
  // totals is written as 0 and the estimate kept in the comment.
  const auto level = [&](const char* key, double value, double se, const std::string& note) {
    if (value >= 0.0) {
      ini.set(section, key, num6(value), se_comment(se, "N m" + note));
    } else {
      ini.set(section, key, "0",
              fmt::format("estimate {} {} is below 0{}", num6(value), se_comment(se, "N m"), note));
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

}  // namespace

void FitFriction::define(CLI::App& app) {
  FitFrictionOptions& friction = options;
  CLI::App* fr = &app;
  fr->add_option("--config", friction.config, "INI parameter set (R, Kt, Ke, J; repeatable, later files win)")
      ->allow_extra_args(false);
  fr->add_option("--order", friction.fit.order, "order of the viscous polynomial")
      ->check(mcg::Range(1, 3))
      ->capture_default_str();
  fr->add_option("--settle", friction.fit.settle_s, "time skipped after a jump of the drive, s")
      ->check(mcg::Range(0.0, 100.0))
      ->capture_default_str();
  fr->add_option("--jump", friction.fit.jump,
                 "change of the drive's command between rows that counts as a jump, in its unit "
                 "(default 0.05 V; with --current or --torque 5 % of its largest value, above its noise)")
      ->check(mcg::Range(0.0, 1e12));
  fr->add_option("--window", friction.fit.window_s, "averaging window, s")
      ->check(mcg::Range(0.002, 100.0))
      ->capture_default_str();
  fr->add_flag("!--no-current", friction.fit.use_current,
               "ignore a measured current (use the voltage balance)");
  fr->add_flag("!--no-static", friction.fit.static_friction,
               "runs never rest: no static level (Ts written = Tc)");
  fr->add_flag("--current", friction.fit.drive.current,
               "current-driven drive: the i column is the current loop's command, A (its torque Kt i)");
  fr->add_option("--torque", friction.fit.drive.torque_column,
                 "column holding the drive torque itself (N m at the measured shaft; N with --linear)")
      ->excludes("--current");
  fr->add_option("--position", friction.fit.position_column,
                 "column holding the position (rad; m with --linear): speed by differences");
  fr->add_flag("--fit-inertia", friction.fit.fit_inertia, "estimate the inertia (mass) with the friction");
  fr->add_flag("--offset", friction.fit.offset, "estimate a constant drive bias with the friction");
  fr->add_option("--gear-ratio", friction.fit.gear_ratio_override,
                 "motor turns per turn of the shaft whose speed was measured (default: the runs' "
                 "gear_ratio, else the INI's [measurement], else 1)")
      ->check(mcg::Range(1e-6, 1e6));
  fr->add_flag("--linear", friction.linear, "linear axis: m, N, N s/m, kg; results in [fit.friction] only");
  fr->add_option("files", friction.files, "runs with t, v, clutch, r_load, rpm [, i] ('-' = stdin)")
      ->required();
}

int FitFriction::run(Io& io) {
  if (options.files.empty()) fail("friction: no input files");
  const config::Ini config = config::Ini::load_all(options.config);
  const model::Params base = model::from_ini(config);
  options.fit.gear_ratio_ini = measurement::speed_path_from_ini(config).gear_ratio;
  options.fit.coast = model::Compiled(model::model_from_ini(config)).circuit.coast;
  if (options.linear && (options.fit.drive.torque_column.empty() || options.fit.position_column.empty())) {
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
  ini.set(sec, "source", fmt::format("{} {}", io.tool, k_version));
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
            !options.fit.drive.torque_column.empty() ? "column " + options.fit.drive.torque_column
                                                     : (st.from_current ? "current" : "voltage balance"));
    ini.set(sec, p + "total_Ts" + torque_key, num6(st.total.value.Ts_Nm),
            se_comment(st.total.se.Ts_Nm, torque_unit));
    ini.set(sec, p + "total_Tc" + torque_key, num6(st.total.value.Tc_Nm),
            se_comment(st.total.se.Tc_Nm, torque_unit));
    if (lin) {
      static const char* const keys[3] = {"total_visc1_N_s_m", "total_visc2_N_s2_m2", "total_visc3_N_s3_m3"};
      static const char* const units[3] = {"N s/m", "N s^2/m^2", "N s^3/m^3"};
      for (std::size_t c = 0; c < static_cast<std::size_t>(options.fit.order); ++c) {
        ini.set(sec, p + keys[c], num6(st.total.value.viscous[c]),
                se_comment(st.total.se.viscous[c], units[c]));
      }
    }
    if (std::isfinite(st.inertia)) {
      ini.set(sec, p + (lin ? "mass_kg" : "inertia_kg_m2"), num6(st.inertia),
              se_comment(st.inertia_se, lin ? "kg" : "kg m^2"));
    }
    if (std::isfinite(st.offset)) {
      ini.set(sec, p + "offset" + torque_key, num6(st.offset), se_comment(st.offset_se, torque_unit));
    }
    ini.set(sec, p + "blocks", static_cast<double>(st.blocks), "quasi-steady stretches, split at 2 s");
    // Each regressed value's two standard errors: the reported one is the larger.
    std::vector<std::string> names{std::string("Tc") + torque_key};
    for (int c = 1; c <= options.fit.order; ++c) names.push_back(fmt::format("visc{}", c));
    if (std::isfinite(st.inertia)) names.emplace_back(lin ? "mass_kg" : "inertia_kg_m2");
    if (std::isfinite(st.offset)) names.push_back(std::string("offset") + torque_key);
    for (std::size_t c = 0; c < names.size() && c < st.se_ols.size(); ++c) {
      ini.set(sec, p + "se_" + names[c], fmt::format("{} {}", num6(st.se_ols[c]), num6(st.se_jackknife[c])),
              "OLS over the windows, jackknife over the blocks (nan: too few)");
    }
  }
  ini.write(io.out);
  return 0;
}

}  // namespace mcg::cmd
