// The rig model: parameters, INI round trip, named parameters, closed forms of the physics.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <sstream>

#include "common/error.hpp"
#include "config/ini.hpp"
#include "model/model.hpp"

namespace mcg::model {
namespace {

/// A step of `level_V` at t = 0, sampled at `dt_s` for `duration_s`.
Inputs step_inputs(double level_V, double duration_s, double dt_s, int clutch, double r_load) {
  Inputs in;
  const auto n = static_cast<std::size_t>(std::llround(duration_s / dt_s)) + 1;
  for (std::size_t k = 0; k < n; ++k) {
    in.t_s.push_back(static_cast<double>(k) * dt_s);
    in.v_V.push_back(level_V);
    in.clutch.push_back(clutch);
    in.r_load_ohm.push_back(r_load);
  }
  return in;
}

TEST(ModelParams, BuiltinRigIsTheReportsTunedRig) {
  const Params p = builtin_rig();
  EXPECT_DOUBLE_EQ(p.motor.R_ohm, 3.91);
  EXPECT_DOUBLE_EQ(p.motor.Kt_Nm_A, 0.0582);
  EXPECT_DOUBLE_EQ(p.motor.J_kg_m2, 7.06e-6);
  EXPECT_DOUBLE_EQ(p.motor.friction.Ts_Nm, 5.5872e-3);
  EXPECT_DOUBLE_EQ(p.motor.friction.Tc_Nm, 2.541594e-3);
  EXPECT_NEAR(p.motor.friction.viscous[0], 1.20474e-5, 1e-10);  // table 11-2: 1.205e-5
  EXPECT_NEAR(p.motor.friction.viscous[1], -1.77394e-8, 1e-13);  // table 11-2: -1.7739e-8
  EXPECT_NEAR(p.motor.friction.viscous[2], 1.07507e-11, 1e-16);  // table 11-2: 1.0751e-11
  EXPECT_DOUBLE_EQ(p.supply_V, 20.0);
  // The report's 950 rad/s electrical pole, R/L.
  EXPECT_NEAR(p.motor.R_ohm / p.motor.L_H, 950.0, 5.0);
}

TEST(ModelParams, IniRoundTripIsExact) {
  Model m;
  m.params.motor.R_ohm = 4.0123456789;
  m.params.clutch_engaged.viscous[1] = 1.234e-9;
  m.effects.push_back(parse_effect("stribeck:v_s_rad_s=8,shape_exp=1.5"));
  config::Ini ini;
  model_to_ini(m, ini);
  std::istringstream text(ini.str());
  const Model back = model_from_ini(config::Ini::parse(text, "round.ini"));
  const auto a = parameters(m);
  const auto b = parameters(back);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].name, b[k].name);
    EXPECT_EQ(a[k].value, b[k].value) << a[k].name;
  }
}

TEST(ModelParams, IniErrorsNameFileLineAndKey) {
  std::istringstream bad_key("[motor]\nR_ohm = 3\nR_ohms = 4\n");
  EXPECT_THROW(
      {
        try {
          from_ini(config::Ini::parse(bad_key, "p.ini"));
        } catch (const Error& e) {
          EXPECT_STREQ(e.what(), "p.ini:3: [motor] R_ohms: unknown parameter");
          throw;
        }
      },
      Error);
  std::istringstream negative("[generator]\nJ_kg_m2 = -1\n");
  EXPECT_THROW(
      {
        try {
          from_ini(config::Ini::parse(negative, "p.ini"));
        } catch (const Error& e) {
          EXPECT_STREQ(e.what(), "p.ini:2: [generator] J_kg_m2: must be a finite number > 0");
          throw;
        }
      },
      Error);
}

TEST(ModelParams, NamedParametersSetAndGet) {
  Model m;
  m.effects.push_back(default_effect("cogging"));
  set_parameter(m, "motor.J_kg_m2", 8e-6);
  set_parameter(m, "clutch_engaged.Tc_Nm", 3e-3);
  set_parameter(m, "cogging.N_per_rev", 12);
  EXPECT_EQ(m.params.motor.J_kg_m2, 8e-6);
  EXPECT_EQ(m.params.clutch_engaged.Tc_Nm, 3e-3);
  EXPECT_EQ(m.effects[0].get("N_per_rev"), 12.0);
  EXPECT_EQ(get_parameter(m, "cogging.N_per_rev"), 12.0);
  EXPECT_THROW(set_parameter(m, "stribeck.v_s_rad_s", 1.0), Error);
  EXPECT_THROW(set_parameter(m, "motor.X", 1.0), Error);
  const auto list = parameters(m);
  EXPECT_EQ(list.front().name, "motor.R_ohm");
  EXPECT_EQ(list.back().name, "cogging.phase_rad");
}

TEST(ModelPhysics, MotorAloneSteadyStateBalancesTorqueAndVoltage) {
  // At steady state: Kt i = Tc + P(w) and v = R i + Ke w.
  const Params p = builtin_rig();
  const Outputs out = simulate(Model{}, step_inputs(6.0, 1.0, 1e-3, 0, k_open_circuit));
  const double w = out.omega_rad_s.back();
  const double i = out.i_A.back();
  EXPECT_NEAR(p.motor.Kt_Nm_A * i, p.motor.friction.kinetic_Nm(w), 1e-9);
  EXPECT_NEAR(p.motor.R_ohm * i + p.motor.Ke_V_s_rad * w, 6.0, 1e-6);
}

TEST(ModelPhysics, BodyStaysAtRestBelowBreakaway) {
  // Coupled breakaway: (Ts_m + Ts_clutch + Ts_g) R / Kt = 1.2137 V (report: 1.216 V simulated).
  const Params p = builtin_rig();
  const double Ts = p.motor.friction.Ts_Nm + p.clutch_engaged.Ts_Nm + p.generator.friction.Ts_Nm;
  const double v_break = Ts / p.motor.Kt_Nm_A * p.motor.R_ohm;
  EXPECT_NEAR(v_break, 1.2137, 1e-3);
  const Outputs below = simulate(Model{}, step_inputs(v_break * 0.999, 0.5, 1e-3, 2, k_open_circuit));
  for (double w : below.omega_rad_s) EXPECT_EQ(w, 0.0);
  for (double th : below.theta_rad) EXPECT_EQ(th, 0.0);
  const Outputs above = simulate(Model{}, step_inputs(v_break * 1.01, 0.5, 1e-3, 2, k_open_circuit));
  EXPECT_GT(above.omega_rad_s.back(), 1.0);
}

TEST(ModelInputs, ValidationNamesTheLineAndColumn) {
  Inputs in = step_inputs(1.0, 0.003, 1e-3, 2, k_open_circuit);
  auto message = [](const Inputs& bad) {
    try {
      validate_inputs(bad, "run.csv", 10);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message(in), "");
  Inputs t = in;
  t.t_s[2] = t.t_s[1];
  EXPECT_EQ(message(t), "run.csv:12: column 't': 0.001 does not increase (previous row: 0.001)");
  Inputs v = in;
  v.v_V[1] = std::nan("");
  EXPECT_EQ(message(v), "run.csv:11: column 'v': an unmeasured value (nan or empty) is not allowed here");
  Inputs c = in;
  c.clutch[3] = 1.5;
  EXPECT_EQ(message(c), "run.csv:13: column 'clutch': 1.5 is not a clutch state (0, 1 or 2)");
  Inputs r = in;
  r.r_load_ohm[0] = -5.6;
  EXPECT_EQ(message(r), "run.csv:10: column 'r_load': -5.6 is not a load (>= 0 ohm, inf = open circuit)");
  EXPECT_EQ(message(Inputs{}), "run.csv: no data rows");
}

}  // namespace
}  // namespace mcg::model
