// mcg-sim: read inputs, simulate open or closed loop, add measurement effects, write the table.
#include "sim/run.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <ostream>
#include <random>
#include <iostream>
#include <optional>

#include <unistd.h>

#include "boardunits/chain.hpp"
#include "boardunits/controller.hpp"
#include "common/demand.hpp"
#include "common/error.hpp"
#include "common/fd_input.hpp"
#include "common/tool.hpp"
#include "config/ini.hpp"
#include "link/capture_meta.hpp"
#include "mcg/version.hpp"
#include "mcg_protocol.h"  // MCG_FW_VERSION_*, MCG_MODE_OPEN
#include "model/model.hpp"
#include "sim/controller.hpp"
#include "measurement/measurement.hpp"
#include "sim/encoder.hpp"
#include "table/table.hpp"

namespace mcg::sim {

namespace {

std::string join(const std::vector<std::string>& parts, std::string_view sep) {
  std::string out;
  for (const auto& p : parts) {
    if (!out.empty()) out += sep;
    out += p;
  }
  return out;
}

/// The names of `paths` as metadata shows them (printable_name()).
std::vector<std::string> printable_names(const std::vector<std::string>& paths) {
  std::vector<std::string> names;
  for (const auto& p : paths) names.push_back(input_name(p));
  return names;
}

std::string coefficient_list(const std::vector<double>& v) {
  std::vector<std::string> parts;
  for (double x : v) parts.push_back(config::format_number(x));
  return join(parts, " ");
}

/// Throws the contract's message for a value that must be finite.
void require_finite_value(double x, const table::Reader& in, std::string_view name) {
  if (!std::isfinite(x)) {
    fail("{}:{}: column {}: {} is not allowed here", in.source(), in.line(), quote(name),
         std::isnan(x) ? "an unmeasured value (nan or empty)" : "an infinite value");
  }
}

/// Where each output column comes from: an input column, or one of the simulated values.
enum class Out {
  Input, Clutch, RLoad, Duty, V, Omega, Rpm, RpmTrue, I, IGen, VGen, Theta,
  RpmResidual, RpmResidualRms, IResidual, IResidualRms
};

/// Running RMS of a residual per regime (clutch state, load open or closed, direction of the
/// measured speed), the regimes mcg-fit gap breaks its residual into.
class RegimeRms {
 public:
  /// Adds residual `r` (ignored when not finite) in the regime of this row; returns the RMS of
  /// the regime so far (nan before its first finite residual).
  double add(int clutch, bool load_closed, double rpm_measured, double r) {
    const int dir = !std::isfinite(rpm_measured) || std::abs(rpm_measured) < 1.0 ? 1 : rpm_measured > 0.0 ? 2 : 0;
    Acc& a = m_acc[static_cast<std::size_t>((clutch * 2 + (load_closed ? 1 : 0)) * 3 + dir)];
    if (std::isfinite(r)) {
      a.sum_sq += r * r;
      ++a.n;
    }
    return a.n > 0 ? std::sqrt(a.sum_sq / static_cast<double>(a.n)) : std::numeric_limits<double>::quiet_NaN();
  }
  /// One line per regime seen: "clutch 2, load open, forward: 2.9 rpm RMS over 796 rows".
  void report(std::ostream& out, std::string_view what, std::string_view unit) const {
    static constexpr std::array<const char*, 3> k_dir{"reverse", "stopped", "forward"};
    for (std::size_t k = 0; k < m_acc.size(); ++k) {
      const Acc& a = m_acc[k];
      if (a.n == 0) continue;
      out << fmt::format("mcg-sim: {} residual, clutch {}, load {}, {}: {:.4g} {} RMS over {} rows\n", what,
                         k / 6, (k / 3) % 2 != 0 ? "closed" : "open", k_dir[k % 3],
                         std::sqrt(a.sum_sq / static_cast<double>(a.n)), unit, a.n);
    }
  }

 private:
  struct Acc {
    double sum_sq = 0.0;
    std::size_t n = 0;
  };
  std::array<Acc, 18> m_acc{};
};

struct OutColumn {
  Out what;
  std::size_t input = 0;   ///< for Out::Input
};

std::string design_text(const Controller& c, bool configured) {
  return fmt::format("{}{}: b = {}, a = {}, dt_s = {}, input_scale = {}, duty_full_scale = {}", c.type,
                     configured ? "" : " (built-in: the report's PI)", coefficient_list(c.b), coefficient_list(c.a),
                     config::format_number(c.dt_s), config::format_number(c.input_scale),
                     config::format_number(c.duty_full_scale));
}

/// The `controller` metadata of --loop board: the core, its registers, what they came from.
std::string board_text(const boardunits::BoardFixedPoint& q, const Controller& c, bool configured) {
  const std::string regs = q.mode == "p" ? fmt::format("kp = {}", q.regs.at(0))
                                         : fmt::format("b0 = {}, b1 = {}, b2 = {}", q.regs.at(0), q.regs.at(1),
                                                       q.regs.at(2));
  return fmt::format(
      "board: the firmware core {}.{}.{} (host build), mode {}, coef_frac = {}, {}, other registers at power-on; "
      "error from the encoder pulses of each 1 ms tick (2048 counts/rev, no direction); from {}",
      MCG_FW_VERSION_MAJOR, MCG_FW_VERSION_MINOR, MCG_FW_VERSION_PATCH, q.mode, q.coef_frac, regs,
      design_text(c, configured));
}

/// The `controller` metadata of --loop board on a capture's own registers.
std::string captured_text(const link::CapturedBoard& board) {
  return fmt::format(
      "board: the firmware core {}.{}.{} (host build), mode {}, the registers of the capture's board_config ({}); "
      "error from the encoder pulses of each 1 ms tick (2048 counts/rev, no direction)",
      MCG_FW_VERSION_MAJOR, MCG_FW_VERSION_MINOR, MCG_FW_VERSION_PATCH, board.mode_name, board.text);
}

/// The `controller` metadata of --loop equation.
std::string equation_text(const Controller& c, bool configured) {
  return fmt::format("equation: the difference equation in double, {}, round_output = {}, duty_resolution = {}; "
                     "error from the signed encoder counts of each sample (2048 counts/rev)",
                     design_text(c, configured), c.round_output ? 1 : 0, config::format_number(c.duty_resolution));
}

}  // namespace

void run(const RunOptions& opt, std::istream& in, const std::string& source, std::ostream& out,
         std::ostream& report) {
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
  const Controller controller = configured.value_or(report_pi());
  const bool on_board = opt.loop == "board";
  // What the board's core holds for the [controller] (or the report's PI): checked before any row.
  std::optional<boardunits::BoardFixedPoint> registers;
  if (on_board) {
    try {
      registers = configured ? boardunits::board_controller(ini)
                             : boardunits::board_fixed_point(controller.b, controller.a, controller.units());
    } catch (const Error& e) {
      fail("{} (--loop equation runs any difference equation)", e.what());
    }
    MCG_DEMAND(registers.has_value());
  }

  table::Reader reader(in, source);
  table::Writer writer(out);
  if (auto* live = dynamic_cast<FdInput*>(in.rdbuf())) live->before_wait([&writer] { writer.finish(); });
  if (!reader.next()) fail("{}: no data rows", source);

  // The columns are resolved at the first row, so that an input without rows says so first.
  // A board's capture states what the board ran when it started (board_config). Without a
  // [controller] of the user's, that decides: in mode open the rpm_cmd column drives nothing
  // (the measured duty does), in a closed-loop mode the board's own registers run the loop.
  const std::optional<link::CapturedBoard> captured = link::captured_board(reader.metadata(), source);
  const bool board_open = captured && captured->mode == MCG_MODE_OPEN && !configured;
  const bool closed = reader.find("rpm_cmd").has_value() && !opt.open_loop && !board_open;
  const bool captured_loop = closed && on_board && captured && !configured;
  const std::size_t t_col = reader.require("t");
  std::optional<std::size_t> drive_col;
  bool drive_is_duty = false;
  if (closed) {
    drive_col = reader.require("rpm_cmd");
  } else if (auto v = reader.find("v")) {
    drive_col = v;
  } else if (auto d = reader.find("duty")) {
    drive_col = d;
    drive_is_duty = true;
  } else {
    reader.require("v");  // throws the missing-column error naming the columns present
  }
  const std::optional<std::size_t> clutch_col = reader.find("clutch");
  const std::optional<std::size_t> r_load_col = reader.find("r_load");

  // The output: the input columns (replaced where the simulation writes the same name),
  // then the new ones.
  std::vector<std::string> names = reader.columns();
  std::vector<OutColumn> plan;
  for (std::size_t c = 0; c < names.size(); ++c) plan.push_back({Out::Input, c});
  const auto put = [&](std::string_view name, Out what) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it != names.end()) {
      plan[static_cast<std::size_t>(it - names.begin())] = {what, 0};
    } else {
      names.emplace_back(name);
      plan.push_back({what, 0});
    }
  };
  // --compare: the measured columns the model also writes stay, renamed, beside the model's.
  std::optional<std::size_t> rpm_measured_col;
  std::optional<std::size_t> i_measured_col;
  if (opt.compare) {
    for (auto [name, col] : {std::pair<const char*, std::optional<std::size_t>*>{"rpm", &rpm_measured_col},
                             {"i", &i_measured_col}}) {
      if (const auto c = reader.find(name)) {
        *col = c;
        names[*c] += "_measured";
      }
    }
    if (!rpm_measured_col && !i_measured_col) {
      fail("{}: --compare needs a measured run: no column 'rpm' or 'i' (columns: {})", source,
           join(reader.columns(), ", "));
    }
  }
  if (!clutch_col) put("clutch", Out::Clutch);
  if (!r_load_col) put("r_load", Out::RLoad);
  if (closed) {
    put("duty", Out::Duty);
    put("v", Out::V);
  }
  put("omega", Out::Omega);
  put("rpm", Out::Rpm);
  if (opt.encoder || (opt.compare && reader.metadata().get("rpm_estimator"))) put("rpm_true", Out::RpmTrue);
  put("i", Out::I);
  put("i_gen", Out::IGen);
  put("v_gen", Out::VGen);
  put("theta", Out::Theta);
  if (rpm_measured_col) {
    put("rpm_residual", Out::RpmResidual);
    put("rpm_residual_rms", Out::RpmResidualRms);
  }
  if (i_measured_col) {
    put("i_residual", Out::IResidual);
    put("i_residual_rms", Out::IResidualRms);
  }

  table::Metadata meta = reader.metadata();
  const double t_first = reader[t_col];
  // Compared with a capture, the model's speed is measured as the capture's was.
  const std::optional<std::string> capture_estimator =
      opt.compare && !opt.encoder ? meta.get("rpm_estimator") : std::nullopt;
  const bool encoder = opt.encoder || capture_estimator.has_value();
  const CountEstimator estimator = capture_estimator
                                       ? measurement::parse_rpm_estimator(*capture_estimator, source + ": rpm_estimator")
                                       : CountEstimator{opt.window_s, opt.counts_per_rev};
  const bool noisy = opt.noise_i_A > 0.0 || opt.noise_v_gen_V > 0.0;
  const measurement::CurrentChain adc = measurement::board_current_chain();
  meta.set("source", fmt::format("mcg-sim {}", k_version));
  meta.set("model", opt.configs.empty() ? std::string("built-in rig (the report's, tuned friction)")
                                        : join(printable_names(opt.configs), " + "));
  std::vector<std::string> effect_texts;
  for (const auto& e : model.effects) effect_texts.push_back(model::format_effect(e));
  meta.set("effects", effect_texts.empty() ? std::string("none") : join(effect_texts, "; "));
  const std::string drive_name = closed ? "rpm_cmd" : (drive_is_duty ? "duty" : "v");
  meta.set("timing", fmt::format("{}, clutch, r_load of row n act over [t(n), t(n+1)); rpm, i, v_gen sampled at t(n){}",
                                 drive_name, closed ? "; duty, v: the controller's output at t(n), held to t(n+1)" : ""));
  meta.set("initial_state", fmt::format("at rest, t = {}", config::format_number(t_first)));
  if (!capture_estimator) meta.erase("rpm_estimator");
  if (!capture_estimator) meta.erase("encoder");
  meta.erase("i_measurement");
  meta.erase("v_gen_measurement");
  meta.erase("seed");
  if (opt.compare) {
    meta.set("compare", "rpm_measured, i_measured: the input's measurements; X_residual = X_measured - X (the "
                        "model's); X_residual_rms: the running RMS of the residual in the row's regime (clutch, "
                        "load, direction of the measured speed)");
  }
  if (opt.encoder) {
    meta.set("rpm_estimator", format_rpm_estimator(estimator));
    meta.set("encoder", opt.counts_per_rev == boardunits::k_board_counts_per_rev
                            ? std::string(boardunits::k_board_encoder_text)
                            : fmt::format("{} counts/rev", config::format_number(opt.counts_per_rev)));
  }
  if (noisy || opt.adc) {
    measurement::CurrentChain chain = opt.adc ? adc : measurement::CurrentChain{};
    chain.simulated = !opt.adc;
    if (opt.noise_i_A > 0.0) chain.sigma_A = opt.noise_i_A;
    meta.set("i_measurement", measurement::format_i_measurement(chain));
  }
  if (opt.noise_v_gen_V > 0.0) {
    meta.set("v_gen_measurement", fmt::format("noise sigma {} V", config::format_number(opt.noise_v_gen_V)));
  }
  if (noisy) meta.set("seed", std::to_string(opt.seed));
  if (closed) {
    meta.set("controller", captured_loop ? captured_text(*captured)
                           : on_board    ? board_text(*registers, controller, configured.has_value())
                                         : equation_text(controller, configured.has_value()));
  }
  // Replaying a capture, the model starts as the capture found the rig: at its first measured
  // speed (the estimator's first window, a few rows in), and in a closed loop with the
  // controller's output at the capture's first duty. Until that row the rows wait, with the
  // metadata, which states the start (at most k_start_rows rows).
  const std::optional<std::size_t> duty_measured_col = closed ? reader.find("duty") : std::nullopt;
  const bool start_measured = opt.compare && rpm_measured_col.has_value() && (!closed || duty_measured_col);
  constexpr std::size_t k_start_rows = 256;
  double omega0_rad_s = 0.0;
  double duty0 = 0.0;
  const auto begin_output = [&](double rpm0, double t_rpm0) {
    if (rpm0 != 0.0) {
      omega0_rad_s = rad_s_from_rpm(rpm0);
      meta.set("initial_state",
               fmt::format("the motor at {} rpm (rpm_measured at t = {}){}, t = {}", config::format_number(rpm0),
                           config::format_number(t_rpm0),
                           closed ? fmt::format(", the controller's output at duty {} (the capture's first)",
                                                config::format_number(duty0))
                                  : "",
                           config::format_number(t_first)));
    }
    writer.metadata(meta);
    writer.header(names);
  };

  model::SimOptions sim_opt;
  sim_opt.max_step_s = opt.max_step_s;
  StreamingRpmEstimator rpm_estimator(estimator);
  RegimeRms rpm_regimes;
  RegimeRms i_regimes;
  std::mt19937_64 rng(opt.seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  const double supply = model.params.supply_V;
  std::optional<ClosedLoop> loop;
  std::optional<model::Plant> plant;
  model::Drive drive;
  std::vector<double> row(names.size());
  double t_prev = 0.0;
  bool first = true;
  // One input row into the model and out: the state at t_n, then the row's inputs.
  const auto emit = [&](const std::vector<double>& in_row) {
    const double t = in_row[t_col];
    const double drive_value = in_row[*drive_col];
    const double clutch = clutch_col ? in_row[*clutch_col] : static_cast<double>(opt.clutch);
    const double r_load = r_load_col ? in_row[*r_load_col] : opt.r_load_ohm;
    const int clutch_state = static_cast<int>(clutch);

    // Row n's output is the state at t_n, just before row n's inputs (and a clutch or relay
    // switch at t_n) act.
    model::State s;
    double duty = 0.0;
    if (closed) {
      if (!loop) {
        loop.emplace(model,
                     captured_loop ? board_loop_controller(captured->mode, captured->registers)
                     : on_board    ? board_loop_controller(*registers)
                                   : equation_loop_controller(controller),
                     sim_opt, clutch_state);
        if (omega0_rad_s != 0.0) loop->start_at(omega0_rad_s, duty0);
      }
      loop->row(t, drive_value, clutch_state, r_load);
      s = loop->state();
      duty = loop->duty();
    } else {
      if (!plant) {
        plant.emplace(model, sim_opt, clutch_state);
        plant->start_at(omega0_rad_s);
      }
      if (!first) plant->step(t - t_prev, drive);
      s = plant->state();
      drive = model::Drive{drive_is_duty ? drive_value * supply : drive_value, clutch_state, r_load};
    }
    const double rpm_true = rpm_from_rad_s(s.omega_rad_s);
    const double rpm = encoder ? rpm_estimator.push(t, s.theta_rad) : rpm_true;
    double i_meas = s.i_A;
    double v_gen = s.v_gen_V;
    if (opt.noise_i_A > 0.0) i_meas += opt.noise_i_A * unit(rng);
    if (opt.noise_v_gen_V > 0.0) v_gen += opt.noise_v_gen_V * unit(rng);
    if (opt.adc) i_meas = adc.quantise(i_meas);

    const double rpm_measured = rpm_measured_col ? in_row[*rpm_measured_col] : rpm;
    const bool load_closed = std::isfinite(r_load);
    double rpm_residual = 0.0;
    double rpm_residual_rms = 0.0;
    double i_residual = 0.0;
    double i_residual_rms = 0.0;
    if (rpm_measured_col) {
      rpm_residual = rpm_measured - rpm;
      rpm_residual_rms = rpm_regimes.add(clutch_state, load_closed, rpm_measured, rpm_residual);
    }
    if (i_measured_col) {
      i_residual = in_row[*i_measured_col] - i_meas;
      i_residual_rms = i_regimes.add(clutch_state, load_closed, rpm_measured, i_residual);
    }
    for (std::size_t c = 0; c < plan.size(); ++c) {
      switch (plan[c].what) {
        case Out::Input: row[c] = in_row[plan[c].input]; break;
        case Out::Clutch: row[c] = clutch; break;
        case Out::RLoad: row[c] = r_load; break;
        case Out::Duty: row[c] = duty; break;
        case Out::V: row[c] = duty * supply; break;
        case Out::Omega: row[c] = s.omega_rad_s; break;
        case Out::Rpm: row[c] = rpm; break;
        case Out::RpmTrue: row[c] = rpm_true; break;
        case Out::I: row[c] = i_meas; break;
        case Out::IGen: row[c] = s.i_gen_A; break;
        case Out::VGen: row[c] = v_gen; break;
        case Out::Theta: row[c] = s.theta_rad; break;
        case Out::RpmResidual: row[c] = rpm_residual; break;
        case Out::RpmResidualRms: row[c] = rpm_residual_rms; break;
        case Out::IResidual: row[c] = i_residual; break;
        case Out::IResidualRms: row[c] = i_residual_rms; break;
      }
    }
    writer.row(row);
    t_prev = t;
    first = false;
  };

  std::vector<std::vector<double>> waiting;  // rows before the model's start (start_measured)
  bool started = !start_measured;
  if (started) begin_output(0.0, t_first);
  double t_checked = 0.0;
  bool first_checked = true;
  do {
    // The checks of one row, in the order a whole-table check reports them.
    const double t = reader[t_col];
    require_finite_value(t, reader, "t");
    if (!first_checked && !(t > t_checked)) {
      fail("{}:{}: column 't': {} does not increase (previous row: {})", source, reader.line(),
           fmt::format("{:.10g}", t), fmt::format("{:.10g}", t_checked));
    }
    const double drive_value = reader[*drive_col];
    require_finite_value(drive_value, reader, reader.columns()[*drive_col]);
    const double clutch = clutch_col ? reader[*clutch_col] : static_cast<double>(opt.clutch);
    if (clutch_col) require_finite_value(clutch, reader, "clutch");
    const double r_load = r_load_col ? reader[*r_load_col] : opt.r_load_ohm;
    if (!(clutch == 0.0 || clutch == 1.0 || clutch == 2.0)) {
      fail("{}:{}: column 'clutch': {} is not a clutch state (0, 1 or 2)", source, reader.line(),
           config::format_number(clutch));
    }
    if (std::isnan(r_load) || r_load < 0.0) {
      fail("{}:{}: column 'r_load': {} is not a load (>= 0 ohm, inf = open circuit)", source, reader.line(),
           config::format_number(r_load));
    }
    if (closed && on_board && !board_takes_command(drive_value)) {
      fail(
          "{}:{}: column 'rpm_cmd': {} is not a command the board takes (0 = off, or a whole rpm in "
          "{}; --loop equation takes any)",
          source, reader.line(), config::format_number(drive_value), board_command_range_text());
    }
    t_checked = t;
    first_checked = false;
    if (started) {
      emit(reader.row());
      continue;
    }
    waiting.push_back(reader.row());
    if (waiting.size() == 1 && duty_measured_col) {
      duty0 = reader[*duty_measured_col];
      if (!std::isfinite(duty0)) duty0 = 0.0;
    }
    const double rpm0 = reader[*rpm_measured_col];
    if (std::isfinite(rpm0) || waiting.size() >= k_start_rows) {
      begin_output(std::isfinite(rpm0) ? rpm0 : 0.0, t);
      for (const auto& w : waiting) emit(w);
      waiting.clear();
      started = true;
    }
  } while (reader.next());
  if (!started) {
    begin_output(0.0, t_first);
    for (const auto& w : waiting) emit(w);
  }
  writer.finish();
  if (rpm_measured_col) rpm_regimes.report(report, "rpm", "rpm");
  if (i_measured_col) i_regimes.report(report, "i", "A");
}

void run_stdio(const RunOptions& options) {
  FdInput input(STDIN_FILENO, "<stdin>");
  std::istream in(&input);
  run(options, in, "<stdin>", std::cout);
}

}  // namespace mcg::sim
