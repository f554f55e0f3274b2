// The effect catalog: parsing, and each effect's physics against its closed form.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "common/error.hpp"
#include "config/ini.hpp"
#include "model/effects/compiled.hpp"
#include "model/model.hpp"
#include "support/inputs.hpp"
#include "test_support_error.hpp"

namespace mcg::model {
namespace {

Model with(const std::string& spec) {
  Model m;
  m.effects.push_back(parse_effect(spec));
  return m;
}

std::string error_of(const std::string& spec) {
  return test::error_of([&] { parse_effect(spec, "--effect"); });
}

TEST(ModelEffects, EachTermShapeStartsOneEffectWithItsOwnParameters) {
  // One owner: the discrepancy's seeds follow the plans, so two effects claiming one shape
  // would make the seed depend on the catalog's order.
  std::vector<TermShape> claimed;
  for (const auto& e : effect_catalog()) {
    for (const TermSeed& rule : e.plan.seeded_by) {
      EXPECT_NE(rule.shape, TermShape::none) << e.name;
      EXPECT_EQ(std::count(claimed.begin(), claimed.end(), rule.shape), 0)
          << e.name << " claims a claimed shape";
      claimed.push_back(rule.shape);
      ASSERT_NE(rule.start, nullptr) << e.name;
      // A term of either sign (a harmonic's amplitude is positive): the effect takes one at
      // least, and names only its own keys.
      std::size_t taken = 0;
      for (double c : {-0.01, 0.01}) {
        const auto start = rule.start(TermValues{c, 3.0, 0.5}, builtin_rig());
        taken += start.empty() ? 0U : 1U;
        for (const auto& [key, value] : start) {
          EXPECT_NO_THROW(default_effect(e.name).get(key)) << e.name << "." << key;
          EXPECT_TRUE(std::isfinite(value)) << e.name << "." << key;
        }
      }
      EXPECT_GE(taken, 1U) << e.name;
    }
  }
  for (TermShape s : {TermShape::sign, TermShape::abs_current_sign, TermShape::angle_harmonic,
                      TermShape::current_drop, TermShape::drive_dead_band}) {
    EXPECT_EQ(std::count(claimed.begin(), claimed.end(), s), 1) << static_cast<int>(s);
  }
}

TEST(ModelEffects, EveryModuleIsCompleteAndItsPlanNamesItsParameters) {
  std::vector<std::string> names;
  for (const auto& e : effect_catalog()) {
    EXPECT_EQ(std::count(names.begin(), names.end(), e.name), 0) << e.name << " registered twice";
    names.push_back(e.name);
    EXPECT_NE(e.compile, nullptr) << e.name;
    EXPECT_FALSE(e.summary.empty()) << e.name;
    EXPECT_FALSE(e.equation.empty()) << e.name;
    auto has = [&](const std::string& key) {
      return std::any_of(e.params.begin(), e.params.end(), [&](const auto& p) { return p.name == key; });
    };
    for (const auto& p : e.params) {
      EXPECT_LE(p.lower, p.default_value) << e.name << "." << p.name;
      EXPECT_GE(p.upper, p.default_value) << e.name << "." << p.name;
      EXPECT_FALSE(p.unit.empty()) << e.name << "." << p.name;
    }
    if (!e.plan.candidate) continue;
    ASSERT_EQ(e.plan.free.size(), e.plan.grid.size()) << e.name;
    for (std::size_t k = 0; k < e.plan.free.size(); ++k) {
      EXPECT_TRUE(has(e.plan.free[k])) << e.name << " plan frees unknown " << e.plan.free[k];
      for (double v : e.plan.grid[k]) {
        const auto& p = *std::find_if(e.params.begin(), e.params.end(),
                                      [&](const auto& q) { return q.name == e.plan.free[k]; });
        EXPECT_TRUE(v >= p.lower && v <= p.upper) << e.name << "." << p.name << " grid value " << v;
      }
    }
    if (!e.plan.angle_order_key.empty()) {
      EXPECT_TRUE(has(e.plan.angle_order_key)) << e.name;
    }
  }
  // The nominal refit is the diagnosis' reference, never a candidate.
  ASSERT_NE(find_effect("param_mismatch"), nullptr);
  EXPECT_FALSE(find_effect("param_mismatch")->plan.candidate);
}

TEST(ModelEffects, FrictionPlansSayWhatTheyAreAndStartFromTheData) {
  std::vector<std::string> friction;
  for (const EffectSpec& spec : effect_catalog()) {
    if (spec.plan.friction) friction.push_back(spec.name);
  }
  EXPECT_EQ(friction,
            (std::vector<std::string>{"stribeck", "friction_levels", "friction_asymmetry", "friction_load"}))
      << "in the catalog's order";
  const Params p = builtin_rig();
  const double stall_Nm = p.motor.Kt_Nm_A * p.supply_V / p.motor.R_ohm;
  DataFriction seen;
  seen.coulomb_Nm = 3e-3;
  seen.static_excess_Nm = -1.0;  // below the model's own: starts at its floor, 1e-4 stall torque
  seen.viscous_Nm_s_rad = 2e-6;
  seen.asymmetry_Nm = -4e-4;
  const EffectPlan& levels = find_effect("friction_levels")->plan;
  EXPECT_EQ(levels.data_start(seen, p), (std::vector<double>{3e-3, 1e-4 * stall_Nm, 2e-6}));
  const EffectPlan& asymmetry = find_effect("friction_asymmetry")->plan;
  EXPECT_TRUE(asymmetry.data_start(seen, p).empty()) << "one direction does not determine it";
  seen.both_directions = true;
  EXPECT_EQ(asymmetry.data_start(seen, p), (std::vector<double>{-4e-4}));
  EXPECT_EQ(find_effect("stribeck")->plan.data_start, nullptr);
}

TEST(ModelEffects, ParseFillsDefaultsAndRoundTrips) {
  const Effect e = parse_effect("cogging:T_c_Nm=0.0021, phase_rad=-1.2");
  EXPECT_EQ(e.get("T_c_Nm"), 0.0021);
  EXPECT_EQ(e.get("N_per_rev"), 14.0);
  EXPECT_EQ(e.get("phase_rad"), -1.2);
  EXPECT_EQ(format_effect(e), "cogging:T_c_Nm=0.0021,N_per_rev=14,phase_rad=-1.2");
  const Effect back = parse_effect(format_effect(e));
  EXPECT_EQ(back.params, e.params);
  EXPECT_EQ(parse_effect("dead_time").get("tau_d_s"), 0.002);
}

// Another motor's size: an effect value beyond its default range is written with the [bounds]
// that hold it and reads back; without them it is refused, naming the range.
TEST(ModelEffects, ValuesBeyondTheDefaultRangeReadBackWithTheirBounds) {
  Model m;
  m.effects.push_back(default_effect("friction_asymmetry"));
  m.effects.back().set("dT_Nm", -3.2);  // as a fit with [bounds] leaves it
  config::Ini ini;
  model_to_ini(m, ini);
  std::ostringstream text;
  ini.write(text);
  EXPECT_NE(text.str().find("friction_asymmetry.dT_Nm = -3.2 0.05"), std::string::npos) << text.str();
  std::istringstream back(text.str());
  const Model read = model_from_ini(config::Ini::parse(back, "fit.ini"));
  ASSERT_NE(read.effect("friction_asymmetry"), nullptr);
  EXPECT_EQ(read.effect("friction_asymmetry")->get("dT_Nm"), -3.2);
  std::istringstream plain("[effect.friction_asymmetry]\ndT_Nm = -3.2\n");
  try {
    model_from_ini(config::Ini::parse(plain, "m.ini"));
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "m.ini:2: [effect.friction_asymmetry] dT_Nm: out of range [-0.05, 0.05]");
  }
}

// Any motor: an effect's torque levels may reach twice the motor's own stall torque in a fit
// (its viscous coefficient twice stall torque per no-load speed), so a motor 200 times the
// rig's stall torque is fitted without [bounds]; the rig's catalog ranges stand, and a fitted
// value beyond them reads back.
TEST(ModelEffects, TorqueLevelsAreBoundedByTheMotorsOwnSize) {
  Model big;
  big.params.motor.Kt_Nm_A *= 20.0;
  big.params.motor.Ke_V_s_rad *= 20.0;
  big.params.motor.R_ohm /= 10.0;
  for (const char* name : {"friction_levels", "friction_asymmetry", "dead_time"}) {
    big.effects.push_back(default_effect(name));
  }
  Model rig;
  rig.effects = big.effects;
  const double stall_Nm = big.params.motor.Kt_Nm_A * big.params.supply_V / big.params.motor.R_ohm;
  const double free_rad_s = big.params.supply_V / big.params.motor.Ke_V_s_rad;
  ASSERT_GT(2.0 * stall_Nm, 10.0);
  ASSERT_GT(2.0 * stall_Nm / free_rad_s, 1.0);
  auto info = [](const Model& m, const std::string& name) {
    for (const auto& p : parameters(m)) {
      if (p.name == name) return p;
    }
    ADD_FAILURE() << name;
    return ParamInfo{};
  };
  EXPECT_DOUBLE_EQ(info(big, "friction_levels.Tc_Nm").upper, 2.0 * stall_Nm);
  EXPECT_DOUBLE_EQ(info(big, "friction_levels.Tc_Nm").lower, 0.0);
  EXPECT_DOUBLE_EQ(info(big, "friction_levels.c1_Nm_s_rad").upper, 2.0 * stall_Nm / free_rad_s);
  EXPECT_DOUBLE_EQ(info(big, "friction_asymmetry.dT_Nm").lower, -2.0 * stall_Nm);
  EXPECT_DOUBLE_EQ(info(big, "friction_asymmetry.dT_Nm").upper, 2.0 * stall_Nm);
  EXPECT_DOUBLE_EQ(info(big, "dead_time.tau_d_s").upper, 0.05);
  EXPECT_DOUBLE_EQ(info(rig, "friction_levels.Tc_Nm").upper, 10.0);
  EXPECT_DOUBLE_EQ(info(rig, "friction_levels.c1_Nm_s_rad").upper, 1.0);

  Model fitted = big;
  set_parameter(fitted, "friction_levels.Tc_Nm", 0.8 * stall_Nm);
  config::Ini ini;
  model_to_ini(fitted, ini);
  std::ostringstream text;
  ini.write(text);
  std::istringstream back(text.str());
  const Model read = model_from_ini(config::Ini::parse(back, "big.ini"));
  EXPECT_DOUBLE_EQ(get_parameter(read, "friction_levels.Tc_Nm"), 0.8 * stall_Nm) << text.str();
}

TEST(ModelEffects, ParseErrorsNameTheBadText) {
  EXPECT_EQ(error_of("stribeck:v_s_rad_s=8a"), "--effect: stribeck.v_s_rad_s: invalid number '8a'");
  EXPECT_EQ(error_of("stribeck:v_s_rad_s"), "--effect: expected key=value, got 'v_s_rad_s'");
  EXPECT_EQ(error_of("stribeck:"), "--effect: no parameters after ':' in 'stribeck:'");
  EXPECT_EQ(error_of("stribeck:v_s_rad_s=1,v_s_rad_s=2"), "--effect: parameter 'v_s_rad_s' given twice");
  EXPECT_EQ(error_of("thermal:R_th_K_W=-1"),
            "--effect: thermal.R_th_K_W = -1 is out of range [0.1, 200] K/W");
  EXPECT_EQ(error_of("brush_drop:V_b_V=nan"), "--effect: brush_drop.V_b_V: invalid number 'nan'");
}

/// Steady state of the motor alone at v: returns (w, i).
std::pair<double, double> steady(const Model& m, double v) {
  const Outputs out = simulate(m, test::constant_inputs(v, 1.5, 1e-3, 0), {});
  return {out.omega_rad_s.back(), out.i_A.back()};
}

TEST(ModelEffects, StribeckLowersKineticFrictionAtLowSpeed) {
  // Steady state: Kt i = Tc + (Ts - Tc) exp(-(w/v_s)^d) + P(w).
  const Params p = builtin_rig();
  const Friction& f = p.motor.friction;
  const auto [w, i] = steady(with("stribeck:v_s_rad_s=12,shape_exp=2.2"), 0.6);
  EXPECT_NEAR(p.motor.Kt_Nm_A * i, f.kinetic_Nm(w) + (f.Ts_Nm - f.Tc_Nm) * std::exp(-std::pow(w / 12.0, 2.2)),
              1e-9);
  EXPECT_LT(w, steady(Model{}, 0.6).first);
}

TEST(ModelEffects, BrushDropOpposesTheCurrent) {
  // v = R i + Ke w + V_b tanh(i / 0.01 A) at steady state.
  const Params p = builtin_rig();
  const auto [w, i] = steady(with("brush_drop:V_b_V=1.1"), 6.0);
  EXPECT_NEAR(p.motor.R_ohm * i + p.motor.Ke_V_s_rad * w + 1.1 * std::tanh(i / 0.01), 6.0, 1e-6);
  EXPECT_NEAR(p.motor.Kt_Nm_A * i, p.motor.friction.kinetic_Nm(w), 1e-9);
}

TEST(ModelEffects, SupplySagDropsWithDutyAndCurrent) {
  // v_m = v - |v/20| R_s i.
  const Params p = builtin_rig();
  const auto [w, i] = steady(with("supply_sag:R_s_ohm=2.6"), 10.0);
  EXPECT_NEAR(p.motor.R_ohm * i + p.motor.Ke_V_s_rad * w, 10.0 - 0.5 * 2.6 * i, 1e-6);
}

TEST(ModelEffects, HbridgeDeadbandAndOnResistance) {
  const Params p = builtin_rig();
  // Inside the deadband nothing reaches the motor.
  const Outputs dead =
      simulate(with("hbridge:deadband=0.05,R_on_ohm=0.1"), test::constant_inputs(0.9, 0.2, 1e-3, 0), {});
  EXPECT_EQ(dead.i_A.back(), 0.0);
  EXPECT_EQ(dead.omega_rad_s.back(), 0.0);
  // Outside: d' = 0.5 - 0.05, and two switches in the path.
  const auto [w, i] = steady(with("hbridge:deadband=0.05,R_on_ohm=0.1"), 10.0);
  EXPECT_NEAR((p.motor.R_ohm + 0.2) * i + p.motor.Ke_V_s_rad * w, 0.45 * 20.0, 1e-6);
}

TEST(ModelEffects, DeadTimeShiftsTheResponseExactly) {
  // A 3 ms delay of a step at 0.100 s equals the undelayed step at 0.103 s.
  Inputs a = test::constant_inputs(0.0, 0.3, 1e-3, 2);
  Inputs b = a;
  for (std::size_t k = 0; k < a.t_s.size(); ++k) {
    a.v_V[k] = a.t_s[k] >= 0.1 - 1e-9 ? 8.0 : 0.0;
    b.v_V[k] = b.t_s[k] >= 0.103 - 1e-9 ? 8.0 : 0.0;
  }
  const Outputs delayed = simulate(with("dead_time:tau_d_s=0.003"), a, {});
  const Outputs shifted = simulate(Model{}, b, {});
  for (std::size_t k = 0; k < a.t_s.size(); ++k) EXPECT_NEAR(delayed.rpm[k], shifted.rpm[k], 1e-6);
  // Inside a row: a 2.5 ms delay lands half-way between rows.
  const Outputs half = simulate(with("dead_time:tau_d_s=0.0025"), a, {});
  EXPECT_EQ(half.i_A[102], 0.0);
  EXPECT_GT(half.i_A[103], 0.0);
}

TEST(ModelEffects, ParamMismatchScalesTheNominalParameters) {
  Model scaled = with("param_mismatch:Kt_scale=0.94,J_scale=1.12,coulomb_scale=1.2");
  Model explicit_model;
  for (Machine* m : {&explicit_model.params.motor, &explicit_model.params.generator}) {
    m->Kt_Nm_A *= 0.94;
    m->Ke_V_s_rad *= 0.94;
    m->J_kg_m2 *= 1.12;
    m->friction.Tc_Nm *= 1.2;
  }
  explicit_model.params.clutch_disengaged.Tc_Nm *= 1.2;
  explicit_model.params.clutch_engaged.Tc_Nm *= 1.2;
  const Outputs a = simulate(scaled, test::constant_inputs(7.0, 0.3, 1e-3, 2, 5.6), {});
  const Outputs b = simulate(explicit_model, test::constant_inputs(7.0, 0.3, 1e-3, 2, 5.6), {});
  EXPECT_EQ(a.rpm, b.rpm);
}

TEST(ModelEffects, CoggingShiftsTheBreakawayWithPosition) {
  // At theta = 0 the cogging torque is T_c sin(phase): with phase = pi/2 it adds T_c to the
  // drive, so breakaway needs Kt i > Ts - T_c, i.e. v > (Ts - T_c) R / Kt.
  const Params p = builtin_rig();
  const double v_break = (p.motor.friction.Ts_Nm - 2.2e-3) * p.motor.R_ohm / p.motor.Kt_Nm_A;
  const Model m = with("cogging:T_c_Nm=0.0022,N_per_rev=9,phase_rad=1.5707963267948966");
  EXPECT_EQ(simulate(m, test::constant_inputs(v_break * 0.99, 0.2, 1e-3, 0), {}).theta_rad.back(), 0.0);
  EXPECT_GT(simulate(m, test::constant_inputs(v_break * 1.01, 0.2, 1e-3, 0), {}).theta_rad.back(), 0.01);
  // At speed the ripple averages out: the mean speed is close to the nominal one.
  const Outputs fast = simulate(m, test::constant_inputs(8.0, 1.0, 1e-4, 0), {});
  const Outputs nominal = simulate(Model{}, test::constant_inputs(8.0, 1.0, 1e-4, 0), {});
  double mean = 0.0;
  for (std::size_t k = 5000; k < fast.rpm.size(); ++k) mean += fast.rpm[k] - nominal.rpm[k];
  EXPECT_NEAR(mean / 5001.0, 0.0, 1.0);
}

TEST(ModelEffects, ThermalRaisesTheResistanceOfAStalledWinding) {
  // Stalled (motor alone, 0.3 V < breakaway 0.375 V): dT settles where
  // dT = R_th i^2 R0 (1 + alpha dT) with i = v / (R0 (1 + alpha dT)).
  Model m = with("thermal:R_th_K_W=50,tau_th_s=0.5,alpha_per_K=0.00393");
  const Outputs out = simulate(m, test::constant_inputs(0.3, 10.0, 1e-2, 0), {});
  const double R0 = builtin_rig().motor.R_ohm;
  double dT = 0.0;
  for (int it = 0; it < 100; ++it) dT = 50.0 * 0.3 * 0.3 / (R0 * (1.0 + 0.00393 * dT));
  EXPECT_NEAR(out.i_A.back(), 0.3 / (R0 * (1.0 + 0.00393 * dT)), 1e-7);
  EXPECT_LT(out.i_A.back(), 0.3 / R0);
}

TEST(ModelEffects, ClutchComplianceTwistCarriesTheLoadTorque) {
  // Steady state engaged with a load: the spring carries the generator side's torque,
  // k phi = Kt i_g + F_g(w).
  Model m = with("clutch_compliance:k_Nm_per_rad=0.1,zeta=0.3");
  Plant plant(m, {}, 2);
  for (int k = 0; k < 1500; ++k) plant.step(1e-3, {9.0, 2, 5.6});
  const State s = plant.state();
  const Params p = builtin_rig();
  const double load = p.generator.Kt_Nm_A * s.i_gen_A + p.generator.friction.kinetic_Nm(s.omega_gen_rad_s);
  EXPECT_NEAR(s.omega_rad_s, s.omega_gen_rad_s, 1e-6);
  EXPECT_NEAR(0.1 * (s.theta_rad - s.theta_gen_rad), load, 1e-8);
}

TEST(ModelEffects, ClutchEngageLagSlipsThenLocks) {
  Model m = with("clutch_engage_lag:T_max_Nm=0.05,tau_s=0.02");
  Plant plant(m, {}, 1);
  for (int k = 0; k < 500; ++k) plant.step(1e-3, {8.0, 1, k_open_circuit});
  const double w_before = plant.state().omega_rad_s;
  // 1 ms after the command the capacity, 0.05 (1 - exp(-0.05)) = 2.4e-3 N m, cannot yet
  // break the generator free (5.6e-3 N m): the motor runs on alone.
  plant.step(1e-3, {8.0, 2, k_open_circuit});
  EXPECT_EQ(plant.state().omega_gen_rad_s, 0.0);
  EXPECT_GT(plant.state().omega_rad_s, 0.95 * w_before);
  // 10 ms after, the plates slip: the generator turns, slower than the motor, and the motor
  // has not dropped to the rigid engagement's half speed.
  for (int k = 0; k < 9; ++k) plant.step(1e-3, {8.0, 2, k_open_circuit});
  EXPECT_GT(plant.state().omega_gen_rad_s, 0.0);
  EXPECT_LT(plant.state().omega_gen_rad_s, plant.state().omega_rad_s);
  EXPECT_GT(plant.state().omega_rad_s, 0.6 * w_before);
  for (int k = 0; k < 300; ++k) plant.step(1e-3, {8.0, 2, k_open_circuit});
  EXPECT_EQ(plant.state().omega_rad_s, plant.state().omega_gen_rad_s);
  // Locked, it runs like the rigid rig.
  Plant rigid(Model{}, {}, 2);
  for (int k = 0; k < 1000; ++k) rigid.step(1e-3, {8.0, 2, k_open_circuit});
  for (int k = 0; k < 500; ++k) plant.step(1e-3, {8.0, 2, k_open_circuit});
  EXPECT_NEAR(plant.state().omega_rad_s, rigid.state().omega_rad_s, 1e-3);
}

TEST(ModelEffects, ModelIniCarriesEffects) {
  Model m = with("supply_sag:R_s_ohm=2.6");
  EXPECT_EQ(get_parameter(m, "supply_sag.R_s_ohm"), 2.6);
  const auto list = parameters(m);
  EXPECT_EQ(list.back().name, "supply_sag.R_s_ohm");
  EXPECT_EQ(list.back().unit, "ohm");
  EXPECT_EQ(list.back().upper, 20.0);
}

TEST(ModelEffects, UnknownEffectOrKeyIsAnErrorInEveryBuild) {
  Effect e = default_effect("stribeck");
  EXPECT_EQ(e.get("v_s_rad_s"), 10.0);
  EXPECT_EQ(test::error_of([&] { e.get("tau_d_s"); }), "effect 'stribeck' has no parameter 'tau_d_s'");
  EXPECT_EQ(test::error_of([&] { e.set("tau_d_s", 1.0); }), "effect 'stribeck' has no parameter 'tau_d_s'");
  const Effect unknown{"warp_drive", {}};
  EXPECT_EQ(test::error_of([&] { unknown.get("x"); }), "unknown effect 'warp_drive'");
}

// What each scale moves is read off param_mismatch's compile: the generator's constants and
// every friction element too, a level the built-in rig leaves at 0 included.
TEST(ModelEffects, MismatchScaleOfEachNominalParameterIsWhatCompileMoves) {
  EXPECT_EQ(mismatch_scale_of("motor.R_ohm"), "R_scale");
  EXPECT_EQ(mismatch_scale_of("generator.R_ohm"), "R_scale");
  EXPECT_EQ(mismatch_scale_of("generator.Ke_V_s_rad"), "Kt_scale");
  EXPECT_EQ(mismatch_scale_of("motor.J_kg_m2"), "J_scale");
  EXPECT_EQ(mismatch_scale_of("motor.L_H"), "L_scale");
  EXPECT_EQ(mismatch_scale_of("clutch_engaged.Tc_Nm"), "coulomb_scale");
  EXPECT_EQ(mismatch_scale_of("generator.Ts_Nm"), "static_scale");
  EXPECT_EQ(mismatch_scale_of("clutch_disengaged.visc3_Nm_s3_rad3"), "viscous_scale");
  EXPECT_EQ(mismatch_scale_of("drive.supply_V"), "");
  EXPECT_EQ(mismatch_scale_of("drive.dead_time_s"), "");
  for (const ParamInfo& info : parameters(Model{})) {
    const std::string scale = mismatch_scale_of(info.name);
    if (scale.empty()) continue;
    Model m;
    m.effects = {parse_effect("param_mismatch:" + scale + "=1.5")};
    set_parameter(m, info.name, 0.25);
    Model moved;
    moved.params = Compiled(m).p;
    EXPECT_DOUBLE_EQ(get_parameter(moved, info.name), 0.375) << info.name;
  }
}

}  // namespace
}  // namespace mcg::model
