// mcg-sim's library side: the encoder estimator, the controller emulation, the closed loop and run().
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>
#include <numbers>
#include <sstream>

#include "board/board.hpp"
#include "boardunits/fixed_point.hpp"
#include "common/error.hpp"
#include "host_board.h"
#include "mcg_protocol.h"
#include "config/ini.hpp"
#include "sim/controller.hpp"
#include "sim/encoder.hpp"
#include "sim/run.hpp"
#include "table/table.hpp"

namespace mcg::sim {
namespace {

constexpr double k_two_pi = 2.0 * std::numbers::pi;

TEST(SimEncoder, ParsesAndFormatsTheContractText) {
  const CountEstimator e = parse_rpm_estimator("counts over 0.005 s window, 2048 counts/rev");
  EXPECT_EQ(e.window_s, 0.005);
  EXPECT_EQ(e.counts_per_rev, 2048.0);
  EXPECT_DOUBLE_EQ(e.rpm_per_count(), 5.859375);
  EXPECT_EQ(format_rpm_estimator(e), "counts over 0.005 s window, 2048 counts/rev");
  try {
    parse_rpm_estimator("average over 5 ms", "run.csv: rpm_estimator");
    FAIL();
  } catch (const Error& err) {
    EXPECT_STREQ(err.what(),
                 "run.csv: rpm_estimator: expected 'counts over <W> s window, <N> counts/rev', got 'average over 5 ms'");
  }
}

TEST(SimEncoder, CountsLikeARealCounter) {
  // floor(theta N / 2 pi), also below zero.
  EXPECT_EQ(encoder_count(0.0, 2048), 0.0);
  EXPECT_EQ(encoder_count(k_two_pi / 2048 * 0.999, 2048), 0.0);
  EXPECT_EQ(encoder_count(k_two_pi / 2048 * 1.001, 2048), 1.0);
  EXPECT_EQ(encoder_count(-1e-9, 2048), -1.0);
  // Constant 1000 rpm sampled at 1 ms: 1000/60 * 2048 * 0.005 = 170.67 counts per window,
  // so the estimate alternates between 170 and 171 counts and averages to the true speed.
  std::vector<double> t, theta;
  for (int k = 0; k <= 3000; ++k) {
    t.push_back(k * 1e-3);
    theta.push_back(1000.0 / 60.0 * k_two_pi * k * 1e-3);
  }
  const auto rpm = estimate_rpm(t, theta, {});
  double sum = 0.0;
  for (std::size_t k = 5; k < rpm.size(); ++k) {
    const double counts = rpm[k] / 5.859375;
    EXPECT_TRUE(counts == 170.0 || counts == 171.0) << counts;
    sum += rpm[k];
  }
  EXPECT_NEAR(sum / static_cast<double>(rpm.size() - 5), 1000.0, 0.1);
  // During the first window the shaft was at rest before t0.
  EXPECT_EQ(rpm[0], 0.0);
  EXPECT_EQ(rpm[2] / 5.859375, encoder_count(theta[2], 2048));
}

TEST(SimEncoder, UnevenSamplingInterpolatesTheAngleAtTheWindowStart) {
  std::vector<double> t{0.0, 0.004, 0.0095, 0.0102};
  std::vector<double> theta{0.0, 4.0, 9.5, 10.2};   // 1000 rad/s
  const auto rpm = estimate_rpm(t, theta, {0.005, 2048});
  // At 0.0102 the window starts at 0.0052: angle 5.2 by interpolation.
  EXPECT_DOUBLE_EQ(rpm[3], (encoder_count(10.2, 2048) - encoder_count(5.2, 2048)) * 5.859375);
}

TEST(SimController, ReportPiDifferenceEquation) {
  // y_n = y_{n-1} + 11.645 e_n - 6.987 e_{n-1}, e in counts = rpm error * 512/60000.
  Controller c = report_pi();
  c.duty_resolution = 0.0;
  c.round_output = false;
  ControllerState s(c);
  const double e = 100.0 * 512.0 / 60000.0;
  EXPECT_NEAR(s.step(100.0) * 922.0, 11.645 * e, 1e-9);
  EXPECT_NEAR(s.step(100.0) * 922.0, 11.645 * e + 11.645 * e - 6.987 * e, 1e-9);
}

TEST(SimController, SaturatesWithoutWindingUpAndQuantises) {
  Controller c = report_pi();
  ControllerState s(c);
  for (int k = 0; k < 1000; ++k) EXPECT_LE(s.step(5000.0), 1.0);
  EXPECT_EQ(s.step(5000.0), 1.0);
  // Anti-windup: the recursion remembers 922, so a reversed error acts at once.
  const double after = s.step(-5000.0);
  EXPECT_LT(after, 1.0 - 0.5);
  // Duty resolution 0.2 %: every output is a multiple of 0.002.
  ControllerState q(c);
  for (int k = 0; k < 50; ++k) {
    const double d = q.step(37.0);
    EXPECT_NEAR(d / 0.002, std::round(d / 0.002), 1e-9);
  }
}

TEST(SimController, IniFormatRoundTripsAndRejectsBadValues) {
  config::Ini ini;
  Controller c = report_pi();
  c.b = {644.0};
  c.a = {1.0};
  c.type = "p";
  controller_to_ini(c, ini);
  std::istringstream text(ini.str());
  const auto back = controller_from_ini(config::Ini::parse(text, "p.ini"));
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->b, c.b);
  EXPECT_EQ(back->a, c.a);
  EXPECT_EQ(back->input_scale, c.input_scale);
  EXPECT_EQ(back->type, "p");
  std::istringstream bad("[controller]\nb = 1\na = 0 1\n");
  try {
    controller_from_ini(config::Ini::parse(bad, "c.ini"));
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "c.ini:3: [controller] a: needs a_0 != 0");
  }
  std::istringstream none("[motor]\nR_ohm = 4\n");
  EXPECT_FALSE(controller_from_ini(config::Ini::parse(none, "m.ini")).has_value());
}

ClosedLoopInputs step_command(double rpm, double duration_s) {
  ClosedLoopInputs in;
  for (int k = 0; k * 1e-3 <= duration_s + 1e-12; ++k) {
    in.t_s.push_back(k * 1e-3);
    in.rpm_cmd.push_back(rpm);
    in.clutch.push_back(2);
    in.r_load_ohm.push_back(model::k_open_circuit);
  }
  return in;
}

boardunits::BoardFixedPoint report_pi_registers() {
  const Controller c = report_pi();
  return *boardunits::board_fixed_point(c.b, c.a, c.units());
}

/// The emulated board (firmware core + plant) tick by tick: its registers written as
/// mcg-serial load writes them (staged, then one commit), rpm_cmd switching at `t_switch_s`; omega after each
/// tick.
std::vector<double> board_omega(const boardunits::BoardFixedPoint& q, const std::vector<double>& rpm_cmd) {
  board::EmulatedBoard board(board::BoardOptions{});
  const auto put = [](std::uint8_t reg, std::int32_t v) {
    ASSERT_EQ(host_board_reg_write(reg, static_cast<std::int16_t>(v)), MCG_ST_OK);
  };
  put(MCG_REG_COEF_FRAC, q.coef_frac);
  if (q.mode == "p") {
    put(MCG_REG_KP, q.regs[0]);
  } else {
    put(MCG_REG_B0, q.regs[0]);
    put(MCG_REG_B1, q.regs[1]);
    put(MCG_REG_B2, q.regs[2]);
  }
  put(MCG_REG_CLUTCH, MCG_CLUTCH_ENGAGED);
  put(MCG_REG_MODE, q.mode == "p" ? MCG_MODE_P : q.mode == "pi" ? MCG_MODE_PI : MCG_MODE_PID);
  put(MCG_REG_COMMIT, 1);
  std::vector<double> omega;
  for (double r : rpm_cmd) {
    put(MCG_REG_RPM_CMD, static_cast<std::int32_t>(r));
    board.tick();
    omega.push_back(board.plant_state().omega_rad_s);
  }
  return omega;
}

TEST(SimClosedLoop, TheBoardLoopIsTheEmulatedBoardTickForTick) {
  // A designed P (mcg-design p --pm 55) and the report's PI, 420 -> 520 rpm: mcg-sim's closed loop
  // runs the same core on the same counts, so the two traces are the same.
  for (const auto& q : {*boardunits::board_fixed_point({305.58319013538915}, {1.0}, {}), report_pi_registers()}) {
    ClosedLoopInputs in = step_command(420.0, 1.5);
    for (std::size_t k = 750; k < in.rpm_cmd.size(); ++k) in.rpm_cmd[k] = 520.0;
    const std::vector<double> board = board_omega(q, in.rpm_cmd);
    const auto model = simulate_closed_loop(model::Model{}, board_loop_controller(q), in);
    for (std::size_t k = 0; k + 1 < in.t_s.size(); ++k) {
      // Equal but for the rounding of the step lengths (t_n+1 - t_n is not exactly 1 ms in double).
      ASSERT_NEAR(model.plant.omega_rad_s[k + 1], board[k], 1e-9) << q.mode << " at t = " << in.t_s[k + 1];
    }
    EXPECT_NEAR(model.plant.rpm.back(), q.mode == "p" ? 460.0 : 520.0, 10.0) << q.mode;
  }
}

TEST(SimClosedLoop, ACommandOfZeroSwitchesTheBoardsControllerOff) {
  // 0 until 0.1 s (mode open, duty 0: at rest), 420 rpm until 0.8 s, then 0 again: the core
  // goes back to open loop at duty 0 and the motor coasts down.
  ClosedLoopInputs in = step_command(420.0, 1.2);
  for (std::size_t k = 0; k < in.t_s.size(); ++k) {
    if (k < 100 || k >= 800) in.rpm_cmd[k] = 0.0;
  }
  const auto out = simulate_closed_loop(model::Model{}, board_loop_controller(report_pi_registers()), in);
  for (std::size_t k = 0; k < 100; ++k) EXPECT_EQ(out.duty[k], 0.0) << k;
  EXPECT_EQ(out.plant.rpm[100], 0.0);
  EXPECT_GT(out.duty[101], 0.0);
  EXPECT_NEAR(out.plant.rpm[799], 420.0, 10.0);
  for (std::size_t k = 800; k < in.t_s.size(); ++k) EXPECT_EQ(out.duty[k], 0.0) << k;
  EXPECT_LT(out.plant.rpm.back(), 300.0);
  EXPECT_FALSE(board_takes_command(100.0));
  EXPECT_FALSE(board_takes_command(420.5));
  EXPECT_TRUE(board_takes_command(120.0) && board_takes_command(720.0) && board_takes_command(0.0));
  EXPECT_FALSE(board_takes_command(721.0));
}

TEST(SimClosedLoop, ReportPiOvershootsA100RpmStepAndSettles) {
  // The report: "Overshoot of the simulation is approximately 30 %" (design: 16 %).
  const auto out = simulate_closed_loop(model::Model{}, equation_loop_controller(report_pi()), step_command(100.0, 0.6));
  const double peak = *std::max_element(out.plant.rpm.begin(), out.plant.rpm.end());
  EXPECT_GT(peak, 116.0);
  double mean = 0.0;
  for (std::size_t k = 400; k < out.plant.rpm.size(); ++k) mean += out.plant.rpm[k];
  mean /= static_cast<double>(out.plant.rpm.size() - 400);
  EXPECT_NEAR(mean, 100.0, 3.0);
  // The duty is the controller's: multiples of 0.2 %, v = 20 V duty.
  for (std::size_t k = 0; k < out.duty.size(); ++k) {
    EXPECT_NEAR(out.duty[k] / 0.002, std::round(out.duty[k] / 0.002), 1e-9);
    EXPECT_DOUBLE_EQ(out.v_V[k], 20.0 * out.duty[k]);
  }
}

TEST(SimClosedLoop, RowsSparserThanTheTicksStillTickEveryMillisecond) {
  // Rows every 5 ms: the loop still runs at 1 ms and tracks the same way.
  ClosedLoopInputs sparse;
  const ClosedLoopInputs dense = step_command(300.0, 0.5);
  for (std::size_t k = 0; k < dense.t_s.size(); k += 5) {
    sparse.t_s.push_back(dense.t_s[k]);
    sparse.rpm_cmd.push_back(300.0);
    sparse.clutch.push_back(2);
    sparse.r_load_ohm.push_back(model::k_open_circuit);
  }
  const auto a = simulate_closed_loop(model::Model{}, board_loop_controller(report_pi_registers()), dense);
  const auto b = simulate_closed_loop(model::Model{}, board_loop_controller(report_pi_registers()), sparse);
  for (std::size_t k = 0; k < sparse.t_s.size(); ++k) EXPECT_NEAR(b.plant.rpm[k], a.plant.rpm[5 * k], 1e-6);
}

std::string run_text(const RunOptions& opt, const std::string& input) {
  std::istringstream in(input);
  std::ostringstream out;
  run(opt, in, "<stdin>", out);
  return out.str();
}

TEST(SimRun, NoiseIsReproducibleFromTheSeedAndRecorded) {
  std::string input = "# sample_period: 0.001\nt,v\n";
  for (int k = 0; k < 50; ++k) input += fmt::format("{},{}\n", k * 1e-3, 6.0);
  RunOptions opt;
  opt.noise_i_A = 0.003;
  opt.seed = 42;
  opt.tool = "mcg-sim";
  const std::string a = run_text(opt, input);
  EXPECT_EQ(a, run_text(opt, input));
  opt.seed = 43;
  EXPECT_NE(a, run_text(opt, input));
  std::istringstream text(a);
  const table::Table t = table::read(text, "out");
  EXPECT_EQ(t.meta.get("seed"), "42");
  EXPECT_EQ(t.meta.get("sample_period"), "0.001");
  EXPECT_EQ(t.meta.get("source"), fmt::format("mcg-sim {}", "0.1.0"));
  EXPECT_EQ(t.names, (std::vector<std::string>{"t", "v", "clutch", "r_load", "omega", "rpm", "i", "i_gen",
                                                "v_gen", "theta"}));
}

TEST(SimRun, AdcQuantisesTheCurrentLikeTheBoard) {
  std::string input = "t,v\n";
  for (int k = 0; k < 30; ++k) input += fmt::format("{},{}\n", k * 1e-3, 15.0);
  RunOptions opt;
  opt.adc = true;
  opt.clutch = 0;
  std::istringstream text(run_text(opt, input));
  const table::Table t = table::read(text, "out");
  for (double i : t.col("i")) {
    EXPECT_NEAR((i + 2.5) / (5.0 / 1024.0), std::round((i + 2.5) / (5.0 / 1024.0)), 1e-6);
    EXPECT_LE(i, 1023.0 * 5.0 / 1024.0 - 2.5 + 1e-9);
  }
  // The inrush (15 V / 3.91 ohm = 3.8 A) saturates at the top code: 2.4951 A.
  EXPECT_NEAR(*std::max_element(t.col("i").begin(), t.col("i").end()), 1023.0 * 5.0 / 1024.0 - 2.5, 1e-6);
}

TEST(SimRun, MeasuredMetadataOfReplacedColumnsIsDropped) {
  const std::string input =
      "# rpm_estimator: counts over 0.005 s window, 2048 counts/rev\n# i_measurement: shunt\nt,v,rpm,i\n0,1,5,0.1\n";
  std::istringstream text(run_text({}, input));
  const table::Table t = table::read(text, "out");
  EXPECT_FALSE(t.meta.get("rpm_estimator").has_value());
  EXPECT_FALSE(t.meta.get("i_measurement").has_value());
  EXPECT_EQ(t.col("rpm")[0], 0.0);
}

// The config file sets a 2 ms dead time, --effect the same effect with 4 ms: the option wins,
// in the metadata and in the motion (the shaft starts after 4 ms, not 2 ms).
TEST(SimRun, EffectOptionOverridesTheConfigSection) {
  const auto path = std::filesystem::temp_directory_path() / fmt::format("mcg_effect_override_{}.ini", ::getpid());
  {
    std::ofstream ini(path);
    ini << "[effect.dead_time]\ntau_d_s = 0.002\n";
  }
  std::string input = "t,v\n";
  for (int k = 0; k < 10; ++k) input += fmt::format("{},{}\n", k * 1e-3, 12.0);
  RunOptions from_config;
  from_config.configs = {path.string()};
  RunOptions overridden = from_config;
  overridden.effects = {"dead_time:tau_d_s=0.004"};
  std::istringstream config_text(run_text(from_config, input));
  std::istringstream override_text(run_text(overridden, input));
  std::filesystem::remove(path);
  const table::Table c = table::read(config_text, "config");
  const table::Table o = table::read(override_text, "override");
  EXPECT_EQ(c.meta.get("effects"), "dead_time:tau_d_s=0.002");
  EXPECT_EQ(o.meta.get("effects"), "dead_time:tau_d_s=0.004");
  // Row 3 (t = 3 ms): moving after the config's 2 ms, still at rest under the option's 4 ms.
  EXPECT_GT(c.col("omega")[3], 0.0);
  EXPECT_EQ(o.col("omega")[3], 0.0);
  EXPECT_EQ(o.col("omega")[4], 0.0);
  EXPECT_GT(o.col("omega")[6], 0.0);
}

}  // namespace
}  // namespace mcg::sim
