// mcg-sim: read inputs, simulate open or closed loop, add measurement effects, write the table.
#include "sim/run.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <numbers>
#include <optional>
#include <ostream>
#include <random>

#include "boardunits/chain.hpp"
#include "boardunits/controller.hpp"
#include "common/demand.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "common/fd_input.hpp"
#include "common/tool.hpp"
#include "config/ini.hpp"
#include "link/capture_meta.hpp"
#include "mcg/version.hpp"
#include "mcg_protocol.h"  // MCG_FW_VERSION_*, MCG_MODE_OPEN
#include "measurement/measurement.hpp"
#include "model/load.hpp"
#include "model/model.hpp"
#include "sim/controller.hpp"
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
  void report(Diagnostics& diag, std::string_view what, std::string_view unit) const {
    static constexpr std::array<const char*, 3> k_dir{"reverse", "stopped", "forward"};
    for (std::size_t k = 0; k < m_acc.size(); ++k) {
      const Acc& a = m_acc[k];
      if (a.n == 0) continue;
      diag.report(fmt::format("{} residual, clutch {}, load {}, {}: {:.4g} {} RMS over {} rows", what, k / 6,
                              (k / 3) % 2 != 0 ? "closed" : "open", k_dir[k % 3],
                              std::sqrt(a.sum_sq / static_cast<double>(a.n)), unit, a.n));
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

/// The closed loop's controller: the [controller] of the configs (or the report's PI) and,
/// with --loop board, what the board's core holds for it (checked before any row).
struct LoopSetup {
  std::optional<Controller> configured;
  Controller controller;
  bool on_board = false;
  std::optional<boardunits::BoardFixedPoint> registers;
};

LoopSetup loop_setup(const config::Ini& ini, const RunOptions& opt) {
  LoopSetup l;
  l.configured = controller_from_ini(ini);
  l.controller = l.configured.value_or(report_pi());
  l.on_board = opt.loop == "board";
  if (l.on_board) {
    try {
      l.registers = l.configured
                        ? boardunits::board_controller(ini)
                        : boardunits::board_fixed_point(l.controller.b, l.controller.a, l.controller.units());
    } catch (const Error& e) {
      fail("{} (--loop equation runs any difference equation)", e.what());
    }
    MCG_DEMAND(l.registers.has_value());
  }
  return l;
}

/// The input's columns, resolved at its first row, and the output's: the input columns
/// (replaced where the simulation writes the same name), then the new ones.
struct Columns {
  std::optional<link::CapturedBoard> captured;  ///< what a board's capture ran (board_config)
  bool closed = false;                          ///< rpm_cmd drives a closed loop
  bool captured_loop = false;                   ///< the capture's own registers run it
  std::size_t t = 0;
  std::optional<std::size_t> drive;
  bool drive_is_duty = false;
  std::optional<std::size_t> clutch;
  std::optional<std::size_t> r_load;
  std::optional<std::size_t> rpm_measured;  ///< --compare
  std::optional<std::size_t> i_measured;    ///< --compare
  std::vector<std::string> names;
  std::vector<OutColumn> plan;
};

/// The input columns the run reads. A board's capture states what the board ran when it
/// started (board_config). Without a [controller] of the user's, that decides: in mode open the
/// rpm_cmd column drives nothing (the measured duty does), in a closed-loop mode the board's own
/// registers run the loop.
Columns input_columns(const table::Reader& reader, const RunOptions& opt, const LoopSetup& l,
                      const std::string& source) {
  Columns c;
  c.captured = link::captured_board(reader.metadata(), source);
  const bool board_open = c.captured && c.captured->mode == MCG_MODE_OPEN && !l.configured;
  c.closed = reader.find("rpm_cmd").has_value() && !opt.open_loop && !board_open;
  c.captured_loop = c.closed && l.on_board && c.captured && !l.configured;
  c.t = reader.require("t");
  if (c.closed) {
    c.drive = reader.require("rpm_cmd");
  } else if (auto v = reader.find("v")) {
    c.drive = v;
  } else if (auto d = reader.find("duty")) {
    c.drive = d;
    c.drive_is_duty = true;
  } else {
    reader.require("v");  // throws the missing-column error naming the columns present
  }
  c.clutch = reader.find("clutch");
  c.r_load = reader.find("r_load");
  return c;
}

/// The output's columns and where each comes from.
void plan_output(Columns& c, const table::Reader& reader, const RunOptions& opt, const std::string& source) {
  c.names = reader.columns();
  for (std::size_t k = 0; k < c.names.size(); ++k) c.plan.push_back({Out::Input, k});
  const auto put = [&](std::string_view name, Out what) {
    const auto it = std::find(c.names.begin(), c.names.end(), name);
    if (it != c.names.end()) {
      c.plan[static_cast<std::size_t>(it - c.names.begin())] = {what, 0};
    } else {
      c.names.emplace_back(name);
      c.plan.push_back({what, 0});
    }
  };
  // --compare: the measured columns the model also writes stay, renamed, beside the model's.
  if (opt.compare) {
    for (auto [name, col] : {std::pair<const char*, std::optional<std::size_t>*>{"rpm", &c.rpm_measured},
                             {"i", &c.i_measured}}) {
      if (const auto k = reader.find(name)) {
        *col = k;
        c.names[*k] += "_measured";
      }
    }
    if (!c.rpm_measured && !c.i_measured) {
      fail("{}: --compare needs a measured run: no column 'rpm' or 'i' (columns: {})", source,
           join(reader.columns(), ", "));
    }
  }
  if (!c.clutch) put("clutch", Out::Clutch);
  if (!c.r_load) put("r_load", Out::RLoad);
  if (c.closed) {
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
  if (c.rpm_measured) {
    put("rpm_residual", Out::RpmResidual);
    put("rpm_residual_rms", Out::RpmResidualRms);
  }
  if (c.i_measured) {
    put("i_residual", Out::IResidual);
    put("i_residual_rms", Out::IResidualRms);
  }
}

/// How the model's speed is measured: compared with a capture, as the capture's was.
struct Estimation {
  std::optional<std::string> capture_estimator;
  bool encoder = false;
  CountEstimator estimator;
};

Estimation estimation(const table::Metadata& meta, const RunOptions& opt, const std::string& source) {
  Estimation e;
  e.capture_estimator = opt.compare && !opt.encoder ? meta.get("rpm_estimator") : std::nullopt;
  e.encoder = opt.encoder || e.capture_estimator.has_value();
  e.estimator = e.capture_estimator
                    ? measurement::parse_rpm_estimator(*e.capture_estimator, source + ": rpm_estimator")
                    : CountEstimator{opt.window_s, opt.counts_per_rev};
  return e;
}

/// The output's metadata: the input's, with what this run simulated and how.
table::Metadata output_metadata(table::Metadata meta, const RunOptions& opt, const model::Model& model,
                                const LoopSetup& l, const Columns& c, const Estimation& est, double t_first) {
  const bool noisy = opt.noise_i_A > 0.0 || opt.noise_v_gen_V > 0.0;
  meta.set("source", fmt::format("{} {}", opt.tool, k_version));
  meta.set("model", opt.configs.empty() ? std::string("built-in rig (the report's, tuned friction)")
                                        : join(printable_names(opt.configs), " + "));
  std::vector<std::string> effect_texts;
  for (const auto& e : model.effects) effect_texts.push_back(model::format_effect(e));
  meta.set("effects", effect_texts.empty() ? std::string("none") : join(effect_texts, "; "));
  const std::string drive_name = c.closed ? "rpm_cmd" : (c.drive_is_duty ? "duty" : "v");
  meta.set(
      "timing",
      fmt::format("{}, clutch, r_load of row n act over [t(n), t(n+1)); rpm, i, v_gen sampled at t(n){}",
                  drive_name, c.closed ? "; duty, v: the controller's output at t(n), held to t(n+1)" : ""));
  meta.set("initial_state", fmt::format("at rest, t = {}", config::format_number(t_first)));
  if (!est.capture_estimator) meta.erase("rpm_estimator");
  if (!est.capture_estimator) meta.erase("encoder");
  meta.erase("i_measurement");
  meta.erase("v_gen_measurement");
  meta.erase("seed");
  if (opt.compare) {
    meta.set("compare", "rpm_measured, i_measured: the input's measurements; X_residual = X_measured - X (the "
                        "model's); X_residual_rms: the running RMS of the residual in the row's regime (clutch, "
                        "load, direction of the measured speed)");
  }
  if (opt.encoder) {
    meta.set("rpm_estimator", format_rpm_estimator(est.estimator));
    meta.set("encoder", opt.counts_per_rev == boardunits::k_board_counts_per_rev
                            ? std::string(boardunits::k_board_encoder_text)
                            : fmt::format("{} counts/rev", config::format_number(opt.counts_per_rev)));
  }
  if (noisy || opt.adc) {
    measurement::CurrentChain chain =
        opt.adc ? measurement::board_current_chain() : measurement::CurrentChain{};
    chain.simulated = !opt.adc;
    if (opt.noise_i_A > 0.0) chain.sigma_A = opt.noise_i_A;
    meta.set("i_measurement", measurement::format_i_measurement(chain));
  }
  if (opt.noise_v_gen_V > 0.0) {
    meta.set("v_gen_measurement", fmt::format("noise sigma {} V", config::format_number(opt.noise_v_gen_V)));
  }
  if (noisy) meta.set("seed", std::to_string(opt.seed));
  if (c.closed) {
    meta.set("controller", c.captured_loop ? captured_text(*c.captured)
                           : l.on_board    ? board_text(*l.registers, l.controller, l.configured.has_value())
                                           : equation_text(l.controller, l.configured.has_value()));
  }
  return meta;
}

/// The checks of one input row, in the order a whole-table check reports them.
void check_row(const table::Reader& reader, const Columns& c, const RunOptions& opt, bool on_board,
               std::optional<double> t_previous) {
  const std::string& source = reader.source();
  const double t = reader[c.t];
  require_finite_value(t, reader, "t");
  if (t_previous && !(t > *t_previous)) {
    fail("{}:{}: column 't': {} does not increase (previous row: {})", source, reader.line(),
         fmt::format("{:.10g}", t), fmt::format("{:.10g}", *t_previous));
  }
  const double drive_value = reader[*c.drive];
  require_finite_value(drive_value, reader, reader.columns()[*c.drive]);
  const double clutch = c.clutch ? reader[*c.clutch] : static_cast<double>(opt.clutch);
  if (c.clutch) require_finite_value(clutch, reader, "clutch");
  const double r_load = c.r_load ? reader[*c.r_load] : opt.r_load_ohm;
  if (!(clutch == 0.0 || clutch == 1.0 || clutch == 2.0)) {
    fail("{}:{}: column 'clutch': {} is not a clutch state (0, 1 or 2)", source, reader.line(),
         config::format_number(clutch));
  }
  if (std::isnan(r_load) || r_load < 0.0) {
    fail("{}:{}: column 'r_load': {} is not a load (>= 0 ohm, inf = open circuit)", source, reader.line(),
         config::format_number(r_load));
  }
  if (c.closed && on_board && !board_takes_command(drive_value)) {
    fail(
        "{}:{}: column 'rpm_cmd': {} is not a command the board takes (0 = off, or a whole rpm in "
        "{}; --loop equation takes any)",
        source, reader.line(), config::format_number(drive_value), board_command_range_text());
  }
}

/// The model run row by row: one input row in, the state at its time (measured as the options
/// say) and the row's inputs out.
class Simulation {
 public:
  Simulation(const RunOptions& opt, const model::Model& model, const LoopSetup& l, const Columns& c,
             const Estimation& est, const measurement::SpeedPath& speed, table::Writer& writer)
      : m_gear_ratio(*speed.gear_ratio),
        m_rpm_filter(*speed.filter),
        m_omega_filter(*speed.filter),
        m_opt(opt),
        m_model(model),
        m_loop_setup(l),
        m_c(c),
        m_encoder(est.encoder),
        m_estimator(est.estimator),
        m_writer(writer),
        m_rng(opt.seed),
        m_row(c.names.size()) {
    m_sim.max_step_s = opt.max_step_s;
    m_sim.circuit_bound = false;
  }

  /// Starts the model at `omega0_rad_s`, a closed loop's controller output at duty `duty0`.
  void start_at(double omega0_rad_s, double duty0) {
    m_omega0_rad_s = omega0_rad_s;
    m_duty0 = duty0;
  }

  void emit(const std::vector<double>& in_row) {
    const double t = in_row[m_c.t];
    const double drive_value = in_row[*m_c.drive];
    const double clutch = m_c.clutch ? in_row[*m_c.clutch] : static_cast<double>(m_opt.clutch);
    const double r_load = m_c.r_load ? in_row[*m_c.r_load] : m_opt.r_load_ohm;
    const int clutch_state = static_cast<int>(clutch);
    double duty = 0.0;
    const model::State s = advance(t, drive_value, clutch_state, r_load, duty);
    // The measured shaft (behind the gear ratio), its speed through the stated filter.
    const double omega_out = m_omega_filter.push(t, s.omega_rad_s / m_gear_ratio);
    const double theta_out = s.theta_rad / m_gear_ratio;
    const double rpm_true = rpm_from_rad_s(s.omega_rad_s / m_gear_ratio);
    const double rpm = m_rpm_filter.push(t, m_encoder ? m_estimator.push(t, theta_out) : rpm_true);
    double i_meas = s.i_A;
    double v_gen = s.v_gen_V;
    if (m_opt.noise_i_A > 0.0) i_meas += m_opt.noise_i_A * m_unit(m_rng);
    if (m_opt.noise_v_gen_V > 0.0) v_gen += m_opt.noise_v_gen_V * m_unit(m_rng);
    if (m_opt.adc) i_meas = m_adc.quantise(i_meas);

    const double rpm_measured = m_c.rpm_measured ? in_row[*m_c.rpm_measured] : rpm;
    const bool load_closed = std::isfinite(r_load);
    double rpm_residual = 0.0;
    double rpm_residual_rms = 0.0;
    double i_residual = 0.0;
    double i_residual_rms = 0.0;
    if (m_c.rpm_measured) {
      rpm_residual = rpm_measured - rpm;
      rpm_residual_rms = m_rpm_regimes.add(clutch_state, load_closed, rpm_measured, rpm_residual);
    }
    if (m_c.i_measured) {
      i_residual = in_row[*m_c.i_measured] - i_meas;
      i_residual_rms = m_i_regimes.add(clutch_state, load_closed, rpm_measured, i_residual);
    }
    const double supply = m_model.params.supply_V;
    for (std::size_t k = 0; k < m_c.plan.size(); ++k) {
      double& x = m_row[k];
      switch (m_c.plan[k].what) {
        case Out::Input:
          x = in_row[m_c.plan[k].input];
          break;
        case Out::Clutch:
          x = clutch;
          break;
        case Out::RLoad:
          x = r_load;
          break;
        case Out::Duty:
          x = duty;
          break;
        case Out::V:
          x = duty * supply;
          break;
        case Out::Omega:
          x = omega_out;
          break;
        case Out::Rpm:
          x = rpm;
          break;
        case Out::RpmTrue:
          x = rpm_true;
          break;
        case Out::I:
          x = i_meas;
          break;
        case Out::IGen:
          x = s.i_gen_A;
          break;
        case Out::VGen:
          x = v_gen;
          break;
        case Out::Theta:
          x = theta_out;
          break;
        case Out::RpmResidual:
          x = rpm_residual;
          break;
        case Out::RpmResidualRms:
          x = rpm_residual_rms;
          break;
        case Out::IResidual:
          x = i_residual;
          break;
        case Out::IResidualRms:
          x = i_residual_rms;
          break;
      }
    }
    m_writer.row(m_row);
    m_t_prev = t;
    m_first = false;
  }

  /// The RMS of the residuals per regime, one report line each.
  void report(Diagnostics& diag) const {
    if (m_c.rpm_measured) m_rpm_regimes.report(diag, "rpm", "rpm");
    if (m_c.i_measured) m_i_regimes.report(diag, "i", "A");
  }

 private:
  /// Row n's output is the state at t_n, just before row n's inputs (and a clutch or relay
  /// switch at t_n) act.
  model::State advance(double t, double drive_value, int clutch_state, double r_load, double& duty) {
    if (m_c.closed) {
      if (!m_closed) {
        m_closed.emplace(m_model,
                         m_c.captured_loop
                             ? board_loop_controller(m_c.captured->mode, m_c.captured->registers)
                         : m_loop_setup.on_board ? board_loop_controller(*m_loop_setup.registers)
                                                 : equation_loop_controller(m_loop_setup.controller),
                         m_sim, clutch_state);
        if (m_omega0_rad_s != 0.0) m_closed->start_at(m_omega0_rad_s, m_duty0);
      }
      m_closed->row(t, drive_value, clutch_state, r_load);
      duty = m_closed->duty();
      return m_closed->state();
    }
    if (!m_plant) {
      m_plant.emplace(m_model, m_sim, clutch_state);
      m_plant->start_at(m_omega0_rad_s);
    }
    if (!m_first) m_plant->step(t - m_t_prev, m_drive);
    const model::State s = m_plant->state();
    m_drive = model::Drive{m_c.drive_is_duty ? drive_value * m_model.params.supply_V : drive_value,
                           clutch_state, r_load};
    return s;
  }

  double m_gear_ratio;
  measurement::SpeedFilterStream m_rpm_filter;
  measurement::SpeedFilterStream m_omega_filter;
  const RunOptions& m_opt;
  const model::Model& m_model;
  const LoopSetup& m_loop_setup;
  const Columns& m_c;
  bool m_encoder;
  StreamingRpmEstimator m_estimator;
  table::Writer& m_writer;
  model::SimOptions m_sim;
  measurement::CurrentChain m_adc = measurement::board_current_chain();
  RegimeRms m_rpm_regimes;
  RegimeRms m_i_regimes;
  std::mt19937_64 m_rng;
  std::normal_distribution<double> m_unit{0.0, 1.0};
  std::optional<ClosedLoop> m_closed;
  std::optional<model::Plant> m_plant;
  model::Drive m_drive;
  std::vector<double> m_row;
  double m_omega0_rad_s = 0.0;
  double m_duty0 = 0.0;
  double m_t_prev = 0.0;
  bool m_first = true;
};

}  // namespace

void run(const RunOptions& opt, std::istream& in, const std::string& source, std::ostream& out,
         Diagnostics* diag) {
  const config::Ini ini = config::Ini::load_all(opt.configs);
  const model::Model model = model::load_model(ini, opt.effects);
  const LoopSetup l = loop_setup(ini, opt);

  table::Reader reader(in, source);
  table::Writer writer(out);
  if (auto* live = dynamic_cast<FdInput*>(in.rdbuf())) live->before_wait([&writer] { writer.finish(); });
  if (!reader.next()) fail("{}: no data rows", source);
  // The columns are resolved at the first row, so that an input without rows says so first.
  Columns c = input_columns(reader, opt, l, source);
  plan_output(c, reader, opt, source);
  const double t_first = reader[c.t];
  const Estimation est = estimation(reader.metadata(), opt, source);
  table::Metadata meta = output_metadata(reader.metadata(), opt, model, l, c, est, t_first);
  // The shaft the speed columns measure and their filter: the input capture's statement, else
  // the INI's [measurement] (mcg-csv(5)); the output states them when they are not the identity.
  const measurement::SpeedPath speed = measurement::settle_speed_path(
      measurement::speed_path_stated(reader.metadata().get("gear_ratio"),
                                     reader.metadata().get("speed_filter"), source),
      measurement::speed_path_from_ini(ini), std::nullopt, source);
  const bool geared = *speed.gear_ratio != 1.0;
  const bool filtered = speed.filter->kind != measurement::SpeedFilter::Kind::none;
  if (c.closed && (geared || filtered)) {
    fail(
        "{}: a closed loop reads the motor's own encoder: a gear ratio or speed filter between the motor "
        "and the measured speed ([measurement], # gear_ratio, # speed_filter) is for open-loop runs",
        source);
  }
  meta.erase("gear_ratio");
  meta.erase("speed_filter");
  if (geared) meta.set("gear_ratio", measurement::format_gear_ratio(*speed.gear_ratio));
  if (filtered) meta.set("speed_filter", measurement::format_speed_filter(*speed.filter));
  Simulation sim(opt, model, l, c, est, speed, writer);

  // Replaying a capture, the model starts as the capture found the rig: at its first measured
  // speed (the estimator's first window, a few rows in), and in a closed loop with the
  // controller's output at the capture's first duty. Until that row the rows wait, with the
  // metadata, which states the start (at most k_start_rows rows).
  const std::optional<std::size_t> duty_measured_col = c.closed ? reader.find("duty") : std::nullopt;
  const bool start_measured = opt.compare && c.rpm_measured.has_value() && (!c.closed || duty_measured_col);
  constexpr std::size_t k_start_rows = 256;
  double duty0 = 0.0;
  const auto begin_output = [&](double rpm0, double t_rpm0) {
    if (rpm0 != 0.0) {
      sim.start_at(rad_s_from_rpm(rpm0) * *speed.gear_ratio, duty0);
      meta.set(
          "initial_state",
          fmt::format("the motor at {} rpm (rpm_measured at t = {}){}, t = {}", config::format_number(rpm0),
                      config::format_number(t_rpm0),
                      c.closed ? fmt::format(", the controller's output at duty {} (the capture's first)",
                                             config::format_number(duty0))
                               : "",
                      config::format_number(t_first)));
    }
    writer.metadata(meta);
    writer.header(c.names);
  };

  std::vector<std::vector<double>> waiting;  // rows before the model's start (start_measured)
  bool started = !start_measured;
  if (started) begin_output(0.0, t_first);
  std::optional<double> t_checked;
  do {
    check_row(reader, c, opt, l.on_board, t_checked);
    t_checked = reader[c.t];
    if (started) {
      sim.emit(reader.row());
      continue;
    }
    waiting.push_back(reader.row());
    if (waiting.size() == 1 && duty_measured_col) {
      duty0 = reader[*duty_measured_col];
      if (!std::isfinite(duty0)) duty0 = 0.0;
    }
    const double rpm0 = reader[*c.rpm_measured];
    if (std::isfinite(rpm0) || waiting.size() >= k_start_rows) {
      begin_output(std::isfinite(rpm0) ? rpm0 : 0.0, reader[c.t]);
      for (const auto& w : waiting) sim.emit(w);
      waiting.clear();
      started = true;
    }
  } while (reader.next());
  if (!started) {
    begin_output(0.0, t_first);
    for (const auto& w : waiting) sim.emit(w);
  }
  writer.finish();
  if (diag != nullptr) sim.report(*diag);
}

void run_stdio(const RunOptions& options, Diagnostics& diag) {
  FdInput input(STDIN_FILENO, "<stdin>");
  std::istream in(&input);
  run(options, in, "<stdin>", std::cout, &diag);
}

}  // namespace mcg::sim
