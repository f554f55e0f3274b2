// Friction from quasi-steady windows (Coulomb and viscous) and starts from rest (static).
#include "fit/friction.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "common/demand.hpp"
#include "common/error.hpp"
#include "common/units.hpp"
#include "fit/nls.hpp"
#include "measurement/measurement.hpp"
#include "model/effects/compiled.hpp"

namespace mcg::fit {

namespace {

/// A stretch of at least this long at rest precedes a start that counts as a breakaway.
constexpr double k_rest_min_s = 0.02;
/// Motion shows in the encoder estimate this long after it began (window + first count).
constexpr double k_detect_lag_s = 0.015;
/// A measured current is averaged over this many trailing samples before its largest value at
/// rest is taken (noise / sqrt(3)); short enough to follow a staircase step. A drive torque
/// from the voltage balance is noise-free and used sample by sample.
constexpr std::size_t k_smooth_samples = 3;
constexpr std::size_t k_min_rows = 100;
/// A quasi-steady stretch longer than this is split into blocks of it for the jackknife: a
/// hold's windows share its drive level and the speed's quantisation at that speed, so they err
/// together; a long slow ramp passes through many speeds and would otherwise be one block.
constexpr double k_block_s = 2.0;
/// Fewer blocks than this give a jackknife error too coarse to stand beside the OLS one.
constexpr std::size_t k_min_jackknife_blocks = 5;

struct Window {
  double omega_rad_s;
  double torque_Nm;
  bool from_current;
  double accel_rad_s2;  ///< (w_end - w_start) / window
  std::size_t block;    ///< the quasi-steady stretch (at most k_block_s long) it belongs to
};

struct Breakaway {
  double lower_Nm;
  double upper_Nm;
};

struct StateData {
  std::vector<Window> windows;
  std::size_t blocks = 0;  ///< distinct Window::block values (ids are shared by the states)
  std::vector<Breakaway> breakaways;
  double max_drive_Nm = 0.0;
};

int sign_of(double x) { return (x > 0.0) - (x < 0.0); }

/// Largest `d * torque` over the samples [from, to).
double largest(const std::vector<double>& torque, int d, std::size_t from, std::size_t to) {
  double best = -1e300;
  for (std::size_t k = from; k < to; ++k) best = std::max(best, d * torque[k]);
  return best;
}

void collect(const table::Table& logged, const model::Params& p, const FrictionOptions& options,
             std::map<int, StateData>& states, std::size_t& block) {
  table::require_increasing(logged, "t");
  if (logged.rows() < k_min_rows)
    fail("{}: too short: {} rows (at least {} needed)", logged.source, logged.rows(), k_min_rows);
  const table::Table table = with_speed_from_position(logged, options.position_column);
  const DriveInput& drive_input = options.drive;
  if (drive_input.current && !drive_input.torque_column.empty())
    fail("a drive is current- or torque-driven, not both");
  model::Inputs in;
  in.t_s = table.col("t");
  const std::size_t n = table.rows();
  const bool direct = !drive_input.torque_column.empty();
  if (!table.has("v") && table.has("duty")) {
    in.v_V = table.col("duty");
    for (double& v : in.v_V) v *= p.supply_V;
  } else if (!drive_input.voltage() && !table.has("v")) {
    in.v_V.assign(n, 0.0);
  } else {
    in.v_V = table.col("v");
  }
  // A run without clutch and load columns is the motor alone, as in make_run.
  in.clutch = table.has("clutch") ? table.col("clutch") : std::vector<double>(n, 0.0);
  in.r_load_ohm = table.has("r_load") ? table.col("r_load") : std::vector<double>(n, model::k_open_circuit);
  model::validate_inputs(in, table.source, table.first_line);
  std::vector<double> omega;
  if (table.has("rpm") || !table.has("omega")) {
    omega = table.col("rpm");
    for (double& w : omega) w *= k_rad_s_per_rpm;
  } else {
    omega = table.col("omega");
  }
  const auto stated =
      measurement::speed_path_stated(table.meta.get("gear_ratio"), std::nullopt, table.source);
  const double gear = measurement::settle_gear_ratio(stated.gear_ratio, options.gear_ratio_ini,
                                                     options.gear_ratio_override, table.source);
  for (double& w : omega) w *= gear;
  // A current-driven drive's `i` is its command: the drive torque, not a reading to do without.
  const std::vector<double>* current = drive_input.current                     ? &table.col("i")
                                       : options.use_current && table.has("i") ? &table.col("i")
                                                                               : nullptr;
  const std::vector<double>* current_gen = options.use_current && table.has("i_gen") ? &table.col("i_gen") : nullptr;
  const std::vector<double>* torque = direct ? &table.col(drive_input.torque_column) : nullptr;
  // The drive's own command as logged: its steps are the transients the windows skip.
  const std::vector<double>& command = direct ? *torque : drive_input.current ? table.col("i") : in.v_V;
  const model::DriveKind kind = direct                ? model::DriveKind::torque
                                : drive_input.current ? model::DriveKind::current
                                                      : model::DriveKind::voltage;
  const double jump =
      options.jump ? *options.jump : drive_jump(command, kind, k_friction_jump_V, k_friction_jump_share);

  const auto& m = p.motor;
  std::vector<double> drive(n);
  std::vector<bool> measured(n);
  // Behind a coasting driver the back-emf opposes the drive only in the on-time (the plant's own
  // share, CircuitTerms::emf_share).
  model::CircuitTerms driver;
  driver.coast = options.coast;
  for (std::size_t k = 0; k < n; ++k) {
    const double v = std::clamp(in.v_V[k], -p.supply_V, p.supply_V);
    if (torque != nullptr) {
      // The logged torque acts at the measured shaft: the motor's is it over the gear ratio.
      measured[k] = std::isfinite((*torque)[k]);
      drive[k] = (*torque)[k] / gear;
      continue;
    }
    measured[k] = current != nullptr && std::isfinite((*current)[k]);
    drive[k] = measured[k]
                   ? m.Kt_Nm_A * (*current)[k]
                   : m.Kt_Nm_A * (v - driver.emf_share(v / p.supply_V) * m.Ke_V_s_rad * omega[k]) / m.R_ohm;
  }

  // Quasi-steady windows.
  double event_t = in.t_s[0];
  double block_t = in.t_s[0];
  ++block;
  std::size_t start = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const bool changed =
        k > 0 && (std::abs(command[k] - command[k - 1]) > jump || in.clutch[k] != in.clutch[k - 1] ||
                  in.r_load_ohm[k] != in.r_load_ohm[k - 1]);
    if (changed) event_t = in.t_s[k];
    if (changed || in.t_s[k] - block_t >= k_block_s) {
      block_t = in.t_s[k];
      ++block;
    }
    const bool usable = in.t_s[k] - event_t >= options.settle_s && std::isfinite(omega[k]);
    if (!usable || changed) {
      start = k + 1;
      continue;
    }
    if (in.t_s[k] - in.t_s[start] < options.window_s) continue;
    const int d = sign_of(omega[start]);
    bool moving = d != 0;
    for (std::size_t j = start; j <= k && moving; ++j) moving = sign_of(omega[j]) == d && std::isfinite(drive[j]);
    if (moving) {
      const int clutch = static_cast<int>(in.clutch[k]);
      const double count = static_cast<double>(k - start + 1);
      double w = 0.0;
      double tau = 0.0;
      double gen = 0.0;
      bool all_measured = true;
      bool gen_measured = clutch == 2 && current_gen != nullptr;
      for (std::size_t j = start; j <= k; ++j) {
        w += omega[j];
        tau += drive[j];
        all_measured = all_measured && measured[j];
        if (gen_measured) {
          gen_measured = std::isfinite((*current_gen)[j]);
          gen += p.generator.Kt_Nm_A * (*current_gen)[j];
        }
      }
      w /= count;
      tau /= count;
      const double j_shaft = m.J_kg_m2 + (clutch == 2 ? p.generator.J_kg_m2 : 0.0);
      const double accel = (omega[k] - omega[start]) / (in.t_s[k] - in.t_s[start]);
      double load = 0.0;
      if (clutch == 2 && std::isfinite(in.r_load_ohm[k])) {
        load = gen_measured ? gen / count
                            : p.generator.Kt_Nm_A * p.generator.Ke_V_s_rad * w / (p.generator.R_ohm + in.r_load_ohm[k]);
      }
      const double inertial = options.fit_inertia ? 0.0 : j_shaft * accel;
      auto& st = states[clutch];
      if (st.windows.empty() || st.windows.back().block != block) ++st.blocks;
      st.windows.push_back({w, tau - inertial - load, all_measured, accel, block});
    }
    start = k + 1;
  }

  // Starts from rest, judged on the drive torque smoothed where it is a noisy measurement.
  std::vector<double> held(n);
  for (std::size_t k = 0; k < n; ++k) {
    std::size_t count = 1;
    held[k] = drive[k];
    for (std::size_t j = 1; measured[k] && j < k_smooth_samples && j <= k && measured[k - j]; ++j, ++count) {
      held[k] += drive[k - j];
    }
    held[k] /= static_cast<double>(count);
  }
  std::size_t rest_start = 0;
  bool resting = false;
  for (std::size_t k = 0; k < n; ++k) {
    auto& st = states[static_cast<int>(in.clutch[k])];
    const bool at_rest = omega[k] == 0.0;
    if (at_rest) st.max_drive_Nm = std::max(st.max_drive_Nm, std::abs(drive[k]));
    if (k > 0 && in.clutch[k] != in.clutch[k - 1]) resting = false;
    if (at_rest) {
      if (!resting) rest_start = k;
      resting = true;
      continue;
    }
    if (resting && std::isfinite(omega[k]) && in.t_s[k] - in.t_s[rest_start] >= k_rest_min_s) {
      const int d = sign_of(omega[k]);
      std::size_t split = k;
      while (split > rest_start && in.t_s[k] - in.t_s[split - 1] <= k_detect_lag_s) --split;
      // A start with no drive torque toward it (a coast read as rest between encoder counts)
      // brackets nothing.
      if (split > rest_start && largest(held, d, split, k + 1) > 0.0) {
        const double lower = largest(held, d, rest_start, split);
        const double upper = largest(held, d, split, k + 1);
        st.breakaways.push_back({std::min(lower, upper), std::max(lower, upper)});
      }
    }
    resting = false;
  }
}

/// Number of clusters of |w| separated by more than 2 % of the top speed (and 2 % of their
/// own): in the speed's own units, so a linear axis in m/s counts like a shaft in rad/s.
std::size_t distinct_speeds(std::vector<double> speeds) {
  std::sort(speeds.begin(), speeds.end());
  std::size_t levels = speeds.empty() ? 0 : 1;
  const double floor = speeds.empty() ? 0.0 : 0.02 * speeds.back();
  for (std::size_t k = 1; k < speeds.size(); ++k) {
    if (speeds[k] - speeds[k - 1] > std::max(floor, 0.02 * speeds[k])) ++levels;
  }
  return levels;
}

StateFriction estimate(int clutch, const StateData& data, const FrictionOptions& options) {
  StateFriction out;
  out.clutch = clutch;
  if (data.windows.empty()) {
    if (data.breakaways.empty()) {
      fail("clutch state {}: the shaft never leaves stiction (largest drive torque at rest {:.4g} N m)", clutch,
           data.max_drive_Nm);
    }
    fail("clutch state {}: no quasi-steady stretch while moving (runs too fast for the {} s settling time?)", clutch,
         options.settle_s);
  }
  if (data.breakaways.empty() && options.static_friction) {
    fail("clutch state {}: no start from rest: static friction cannot be estimated (--no-static skips it)", clutch);
  }

  std::vector<double> speeds;
  for (const auto& w : data.windows) speeds.push_back(std::abs(w.omega_rad_s));
  out.omega_min_rad_s = *std::min_element(speeds.begin(), speeds.end());
  out.omega_max_rad_s = *std::max_element(speeds.begin(), speeds.end());
  const std::size_t needed = static_cast<std::size_t>(options.order) + 1;
  const std::size_t levels = distinct_speeds(speeds);
  if (levels < needed || data.windows.size() <= needed) {
    fail("clutch state {}: no excitation in the needed range: {} distinct speeds ({:.3g}..{:.3g} rad/s), "
         "a polynomial of order {} needs {}",
         clutch, levels, out.omega_min_rad_s, out.omega_max_rad_s, options.order, needed);
  }

  const auto poly = static_cast<Eigen::Index>(needed);
  const Eigen::Index col_inertia = options.fit_inertia ? poly : -1;
  const Eigen::Index col_offset = options.offset ? poly + (options.fit_inertia ? 1 : 0) : -1;
  const Eigen::Index cols = poly + (options.fit_inertia ? 1 : 0) + (options.offset ? 1 : 0);
  if (static_cast<Eigen::Index>(data.windows.size()) <= cols) {
    fail("clutch state {}: {} windows for {} unknowns: no excitation in the needed range", clutch,
         data.windows.size(), cols);
  }
  // The regression on the windows, leaving out those of block `skip` (none: every window).
  const auto regress = [&](std::size_t skip, Eigen::MatrixXd& a, Eigen::VectorXd& b) {
    std::vector<const Window*> used;
    std::vector<double> used_speeds;
    for (const auto& w : data.windows) {
      if (w.block == skip) continue;
      used.push_back(&w);
      used_speeds.push_back(std::abs(w.omega_rad_s));
    }
    const auto rows = static_cast<Eigen::Index>(used.size());
    if (rows <= cols || distinct_speeds(used_speeds) < needed) return false;
    a.resize(rows, cols);
    b.resize(rows);
    for (Eigen::Index r = 0; r < rows; ++r) {
      const Window& w = *used[static_cast<std::size_t>(r)];
      const double s = w.omega_rad_s > 0.0 ? 1.0 : -1.0;
      const double x = std::abs(w.omega_rad_s);
      double xp = 1.0;
      for (Eigen::Index c = 0; c < poly; ++c, xp *= x) a(r, c) = s * xp;
      if (col_inertia >= 0) a(r, col_inertia) = w.accel_rad_s2;
      if (col_offset >= 0) a(r, col_offset) = 1.0;
      b[r] = w.torque_Nm;
    }
    return true;
  };
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  MCG_DEMAND(regress(std::numeric_limits<std::size_t>::max(), a, b));
  out.from_current =
      std::all_of(data.windows.begin(), data.windows.end(), [](const Window& w) { return w.from_current; });
  const Eigen::VectorXd coef = a.colPivHouseholderQr().solve(b);
  Eigen::VectorXd se;
  Eigen::MatrixXd corr;
  double sigma = 0.0;
  covariance_statistics(a, a * coef - b, se, corr, sigma);
  // The OLS errors take the windows as independent; windows of one stretch err together (its
  // drive level, the speed's quantisation at its speed), which the jackknife over the stretches
  // sees: var = (g - 1)/g sum (coef_(i) - mean)^2 over the g fits that leave out block i.
  out.blocks = data.blocks;
  out.se_ols.assign(se.begin(), se.end());
  out.se_jackknife.assign(static_cast<std::size_t>(se.size()), std::numeric_limits<double>::quiet_NaN());
  if (data.blocks >= k_min_jackknife_blocks) {
    std::vector<Eigen::VectorXd> fits;
    std::size_t last = std::numeric_limits<std::size_t>::max();
    for (const auto& w : data.windows) {
      if (w.block == last) continue;
      last = w.block;
      Eigen::MatrixXd ai;
      Eigen::VectorXd bi;
      if (!regress(w.block, ai, bi)) {
        fits.clear();
        break;
      }
      fits.push_back(ai.colPivHouseholderQr().solve(bi));
    }
    if (!fits.empty()) {
      const auto g = static_cast<double>(fits.size());
      Eigen::VectorXd mean = Eigen::VectorXd::Zero(cols);
      for (const auto& f : fits) mean += f / g;
      Eigen::VectorXd var = Eigen::VectorXd::Zero(cols);
      for (const auto& f : fits) var += (f - mean).cwiseAbs2();
      var *= (g - 1.0) / g;
      for (Eigen::Index c = 0; c < cols; ++c) {
        out.se_jackknife[static_cast<std::size_t>(c)] = std::sqrt(var[c]);
        se[c] = std::max(se[c], std::sqrt(var[c]));
      }
    }
  }
  out.total.value.Tc_Nm = coef[0];
  out.total.se.Tc_Nm = se[0];
  for (Eigen::Index c = 1; c < poly; ++c) {
    out.total.value.viscous[static_cast<std::size_t>(c - 1)] = coef[c];
    out.total.se.viscous[static_cast<std::size_t>(c - 1)] = se[c];
  }
  if (col_inertia >= 0) {
    out.inertia = coef[col_inertia];
    out.inertia_se = se[col_inertia];
  }
  if (col_offset >= 0) {
    out.offset = coef[col_offset];
    out.offset_se = se[col_offset];
  }

  if (!options.static_friction) {
    out.total.value.Ts_Nm = out.total.value.Tc_Nm;
    out.total.se.Ts_Nm = out.total.se.Tc_Nm;
  } else {
    // Each start from rest brackets the breakaway between the largest drive torque held and
    // the torque that moved the shaft: a uniform interval of variance width^2 / 12. The
    // intervals are combined by their precision, so a slow ramp's narrow bracket outweighs a
    // staircase's coarse ones (a plain mean lands between the staircase's steps). The error is
    // a typical bracket's, not shrunk by their number (every bracket shares the detection's
    // bias), grown by the scatter beyond what the widths explain (Birge ratio), since the real
    // breakaway varies with the shaft's position.
    double weights = 0.0;
    double sum = 0.0;
    // A bracket narrower than 5 % of its level is not more exact: a real breakaway varies that
    // much with the shaft's position, and a start seen only after the detection lag brackets
    // the torque after the step on both sides.
    const auto variance = [](const Breakaway& e) {
      const double floor = 0.05 * std::abs(0.5 * (e.lower_Nm + e.upper_Nm));
      return (std::pow(e.upper_Nm - e.lower_Nm, 2) + floor * floor + 1e-300) / 12.0;
    };
    for (const auto& e : data.breakaways) {
      weights += 1.0 / variance(e);
      sum += 0.5 * (e.lower_Nm + e.upper_Nm) / variance(e);
    }
    const double mean = sum / weights;
    double chi2 = 0.0;
    for (const auto& e : data.breakaways) {
      chi2 += std::pow(0.5 * (e.lower_Nm + e.upper_Nm) - mean, 2) / variance(e);
    }
    const auto count = static_cast<double>(data.breakaways.size());
    const double birge2 = count > 1 ? std::max(1.0, chi2 / (count - 1.0)) : 1.0;
    out.total.value.Ts_Nm = mean;
    out.total.se.Ts_Nm = std::sqrt(birge2 * count / weights);
  }
  out.windows = data.windows.size();
  out.breakaways = data.breakaways.size();
  return out;
}

/// a - k b with standard errors in quadrature (k b counts b's error k times: b is one estimate).
FrictionTerm minus(const FrictionTerm& a, const FrictionTerm& b, double k = 1.0) {
  FrictionTerm out;
  const auto diff = [k](double x, double y) { return x - k * y; };
  const auto quad = [k](double x, double y) { return std::sqrt(x * x + k * k * y * y); };
  out.value.Ts_Nm = diff(a.value.Ts_Nm, b.value.Ts_Nm);
  out.value.Tc_Nm = diff(a.value.Tc_Nm, b.value.Tc_Nm);
  out.se.Ts_Nm = quad(a.se.Ts_Nm, b.se.Ts_Nm);
  out.se.Tc_Nm = quad(a.se.Tc_Nm, b.se.Tc_Nm);
  for (std::size_t c = 0; c < 3; ++c) {
    out.value.viscous[c] = diff(a.value.viscous[c], b.value.viscous[c]);
    out.se.viscous[c] = quad(a.se.viscous[c], b.se.viscous[c]);
  }
  return out;
}

}  // namespace

FrictionResult fit_friction(const std::vector<table::Table>& runs, const model::Params& base,
                            const FrictionOptions& options) {
  if (options.order < 1 || options.order > 3) fail("--order must be 1, 2 or 3");
  if (runs.empty()) fail("no runs given");
  std::map<int, StateData> data;
  std::size_t block = 0;
  for (const auto& table : runs) collect(table, base, options, data, block);

  FrictionResult result;
  result.params = base;
  std::map<int, FrictionTerm> total;
  for (const auto& [clutch, d] : data) {
    if (d.windows.empty() && d.breakaways.empty() && d.max_drive_Nm == 0.0) continue;
    result.states.push_back(estimate(clutch, d, options));
    total[clutch] = result.states.back().total;
  }

  FrictionTerm motor{base.motor.friction, {}};
  FrictionTerm generator{base.generator.friction, {}};
  double generator_factor = 1.0;
  if (total.count(0) != 0) {
    motor = total[0];
    generator = motor;
    generator_factor = 2.0;
    result.motor = motor;
    result.params.motor.friction = motor.value;
    result.params.generator.friction = motor.value;
  }
  if (total.count(1) != 0) {
    result.clutch_disengaged = minus(total[1], motor);
    result.params.clutch_disengaged = result.clutch_disengaged->value;
  }
  if (total.count(2) != 0) {
    // total2 - motor - generator; when the generator is the motor's estimate the two
    // subtractions share one error, so it counts twice.
    FrictionTerm engaged = minus(total[2], motor, generator_factor);
    if (generator_factor == 1.0) engaged = minus(engaged, generator);
    result.clutch_engaged = engaged;
    result.params.clutch_engaged = engaged.value;
  }
  return result;
}

}  // namespace mcg::fit
