// Friction identification: the report's friction values come back from simulated runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "common/error.hpp"
#include "fit/friction.hpp"
#include "test_fit_support.hpp"
#include "test_support_error.hpp"

namespace mcg::fit {
namespace {

using testing::measure;
using testing::Program;

/// The report's procedure in one run per clutch state: a slow voltage ramp through the
/// breakaway (static and Coulomb), then a staircase up to `top_V` (viscous), back through
/// zero, and the same in the negative direction.
model::Inputs friction_run(int clutch, double ramp_to_V, double top_V, double r_load_ohm = model::k_open_circuit) {
  Program p;
  for (const double d : {1.0, -1.0}) {
    p.hold(0.0, 0.3, clutch, r_load_ohm);
    p.ramp(0.0, d * ramp_to_V, 3.0, clutch, r_load_ohm);
    for (double v = 1.0; v <= top_V + 1e-9; v += 1.0) p.hold(d * v, 0.6, clutch, r_load_ohm);
  }
  return p.inputs;
}

struct Expected {
  double Ts, Tc, c1, c2, c3;
};

void expect_friction(const model::Friction& got, const model::Friction& se, const Expected& want, double tol_ts,
                     double tol_tc, double tol_c1, double tol_c2, double tol_c3, const char* what) {
  SCOPED_TRACE(what);
  EXPECT_NEAR(got.Ts_Nm, want.Ts, tol_ts);
  EXPECT_NEAR(got.Tc_Nm, want.Tc, tol_tc);
  EXPECT_NEAR(got.viscous[0], want.c1, tol_c1);
  EXPECT_NEAR(got.viscous[1], want.c2, tol_c2);
  EXPECT_NEAR(got.viscous[2], want.c3, tol_c3);
  // The stated standard errors are honest: the truth lies within 4 of them.
  EXPECT_NEAR(got.Ts_Nm, want.Ts, 4.0 * se.Ts_Nm + 1e-12);
  EXPECT_NEAR(got.Tc_Nm, want.Tc, 4.0 * se.Tc_Nm + 1e-12);
}

class FitFriction : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const model::Model rig;
    runs = new std::vector<table::Table>{measure(rig, friction_run(0, 0.6, 14.0), 1),
                                         measure(rig, friction_run(1, 0.7, 14.0), 2),
                                         measure(rig, friction_run(2, 1.6, 14.0), 3)};
  }
  static void TearDownTestSuite() {
    delete runs;
    runs = nullptr;
  }
  static std::vector<table::Table>* runs;
};
std::vector<table::Table>* FitFriction::runs = nullptr;

/// Kinetic friction curve sign(w) (Tc + P(|w|)) of a term, N m.
double curve(const model::Friction& f, double w) { return f.kinetic_Nm(w); }

// The report's values (model::builtin_rig(): the motor's tuned m-file values Ts 5.5872e-3,
// Tc 2.541594e-3 N m and viscous cubic 58.2e-3 (2.07e-4 w - 3.048e-7 w^2 + 1.8472e-10 w^3)
// = table 11-2's 1.205e-5 w - 1.7739e-8 w^2 + 1.0751e-11 w^3; the clutch rows of tables
// 11-1/11-2) come back through the stacking. Tolerances per parameter: static levels are
// bracketed by a slow ramp (0.2 V/s) and read from a noisy current; the clutch values are
// differences of two measured totals; the cubic term is weakly determined below 240 rad/s,
// so the curve itself is checked at 20..200 rad/s as well.
TEST_F(FitFriction, ReportValuesComeBackFromStaircaseWithCurrent) {
  const auto result = fit_friction(*runs, model::builtin_rig());
  ASSERT_EQ(result.states.size(), 3U);
  ASSERT_TRUE(result.motor && result.clutch_disengaged && result.clutch_engaged);
  const model::Params rig = model::builtin_rig();
  const auto& m = rig.motor.friction;
  const auto& d = rig.clutch_disengaged;
  const auto& e = rig.clutch_engaged;
  expect_friction(result.motor->value, result.motor->se, {m.Ts_Nm, m.Tc_Nm, m.viscous[0], m.viscous[1], m.viscous[2]},
                  2e-4, 5e-5, 1e-6, 5e-9, 1.5e-11, "motor");
  expect_friction(result.clutch_disengaged->value, result.clutch_disengaged->se,
                  {d.Ts_Nm, d.Tc_Nm, d.viscous[0], d.viscous[1], d.viscous[2]}, 2e-4, 3e-5, 1.5e-6, 1.5e-8, 4e-11,
                  "clutch disengaged");
  expect_friction(result.clutch_engaged->value, result.clutch_engaged->se,
                  {e.Ts_Nm, e.Tc_Nm, e.viscous[0], e.viscous[1], e.viscous[2]}, 4e-4, 8e-5, 3e-6, 3e-8, 8e-11,
                  "clutch engaged");
  for (double w = 20.0; w <= 200.0; w += 30.0) {
    EXPECT_NEAR(curve(result.motor->value, w), curve(m, w), 0.01 * curve(m, w)) << w;
    const double total2 = 2.0 * curve(m, w) + curve(e, w);
    const double got2 = 2.0 * curve(result.motor->value, w) + curve(result.clutch_engaged->value, w);
    EXPECT_NEAR(got2, total2, 0.01 * total2) << w;
  }
  EXPECT_EQ(result.states[2].breakaways, 2U);
  EXPECT_TRUE(result.states[0].from_current);
  // The estimates are written into the parameter set, the generator taking the motor's.
  EXPECT_EQ(result.params.motor.friction.Tc_Nm, result.motor->value.Tc_Nm);
  EXPECT_EQ(result.params.generator.friction.Ts_Nm, result.motor->value.Ts_Nm);
  EXPECT_EQ(result.params.clutch_engaged.viscous[1], result.clutch_engaged->value.viscous[1]);
}

// Without a current column the voltage balance T = Kt (v - Ke w) / R gives the same values;
// a generator load (5.6 ohm across the generator in state 2) is subtracted from the model.
TEST_F(FitFriction, VoltageBalanceAndGeneratorLoad) {
  const model::Model rig;
  std::vector<table::Table> no_current{measure(rig, friction_run(0, 0.6, 14.0), 4, false),
                                       measure(rig, friction_run(2, 1.6, 14.0, 5.6), 5, false)};
  const auto result = fit_friction(no_current, rig.params);
  ASSERT_TRUE(result.motor && result.clutch_engaged);
  EXPECT_FALSE(result.clutch_disengaged.has_value());
  EXPECT_FALSE(result.states[0].from_current);
  const auto& m = rig.params.motor.friction;
  const auto& e = rig.params.clutch_engaged;
  expect_friction(result.motor->value, result.motor->se, {m.Ts_Nm, m.Tc_Nm, m.viscous[0], m.viscous[1], m.viscous[2]},
                  2e-4, 5e-5, 1e-6, 5e-9, 1.5e-11, "motor");
  expect_friction(result.clutch_engaged->value, result.clutch_engaged->se,
                  {e.Ts_Nm, e.Tc_Nm, e.viscous[0], e.viscous[1], e.viscous[2]}, 4e-4, 1e-4, 4e-6, 4e-8, 1e-10,
                  "clutch engaged, 5.6 ohm load");
  // The disengaged clutch keeps the base value when no state-1 run is given.
  EXPECT_EQ(result.params.clutch_disengaged.Ts_Nm, rig.params.clutch_disengaged.Ts_Nm);
}

// A run that never rests (it starts moving at once and stays above 4 V): no static level
// unless asked to do without; then Coulomb and viscous terms still come back.
TEST(FitFrictionNoStatic, RunThatNeverRests) {
  Program p;
  for (double v = 4.0; v <= 14.0; v += 1.0) p.hold(v, 0.6, 0);
  const std::vector<table::Table> runs{measure(model::Model{}, p.inputs, 9)};
  try {
    fit_friction(runs, model::builtin_rig());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "clutch state 0: no start from rest: static friction cannot be estimated (--no-static skips it)");
  }
  FrictionOptions options;
  options.static_friction = false;
  options.order = 2;
  const auto result = fit_friction(runs, model::builtin_rig(), options);
  ASSERT_TRUE(result.motor.has_value());
  const auto& m = model::builtin_rig().motor.friction;
  EXPECT_EQ(result.motor->value.Ts_Nm, result.motor->value.Tc_Nm);
  EXPECT_EQ(result.states[0].breakaways, 0U);
  // A quadratic over 60..230 rad/s stands in for the cubic: the curve matches within 2 %.
  for (double w = 70.0; w <= 220.0; w += 50.0) {
    EXPECT_NEAR(result.motor->value.kinetic_Nm(w), m.kinetic_Nm(w), 0.02 * m.kinetic_Nm(w)) << w;
  }
}

// Behind a driver that coasts in the PWM off-time the back-emf opposes the drive only in the
// on-time: the voltage balance Kt (v - (1 - coast (1 - |v| / supply_V)) Ke w) / R gives the
// friction back from a staircase at low duty (speeds far above the braking v / Ke); taken as
// braking, the same runs read the missing back-emf as a large negative viscous term.
TEST(FitFrictionCoast, TheBalanceOfACoastingDriver) {
  model::Model rig;
  rig.effects.push_back(model::parse_effect("pwm_coast:coast=1"));
  Program p;
  for (const double d : {1.0, -1.0}) {
    p.hold(0.0, 0.3, 0);
    for (double v = 1.0; v <= 4.0 + 1e-9; v += 0.5) p.hold(d * v, 0.6, 0);
  }
  const std::vector<table::Table> runs{measure(rig, p.inputs, 21, false)};
  FrictionOptions options;
  options.static_friction = false;
  options.order = 1;
  options.coast = 1.0;
  const auto coasting = fit_friction(runs, rig.params, options);
  ASSERT_TRUE(coasting.motor.has_value());
  const StateFriction& st = coasting.states[0];
  const model::Friction& truth = rig.params.motor.friction;
  // A line over the staircase's speeds stands in for the rig's cubic: within 2 % there.
  for (const double w :
       {st.omega_min_rad_s, 0.5 * (st.omega_min_rad_s + st.omega_max_rad_s), st.omega_max_rad_s}) {
    EXPECT_NEAR(coasting.motor->value.kinetic_Nm(w), truth.kinetic_Nm(w), 0.02 * truth.kinetic_Nm(w)) << w;
  }
  options.coast = 0.0;
  const auto braking = fit_friction(runs, rig.params, options);
  ASSERT_TRUE(braking.motor.has_value());
  EXPECT_LT(braking.motor->value.viscous[0], -10.0 * truth.viscous[0]);
}

// Coarse starts from rest (steps of 4, 6 and -5 V, each bracketing the breakaway between 0
// and its level) beside the slow ramps' narrow brackets: the static level follows the ramps,
// as a plain mean of the brackets' midpoints (about 2.6 V of drive) would not.
TEST(FitFrictionStatic, NarrowBracketsOutweighCoarseSteps) {
  Program p;
  p.hold(0.0, 0.3, 0).hold(4.0, 0.6, 0).hold(0.0, 0.6, 0).hold(6.0, 0.6, 0).hold(0.0, 0.6, 0);
  p.hold(-5.0, 0.6, 0).hold(0.0, 0.6, 0);
  const model::Model rig;
  const std::vector<table::Table> runs{measure(rig, p.inputs, 11),
                                       measure(rig, friction_run(0, 0.6, 14.0), 12)};
  const auto result = fit_friction(runs, model::builtin_rig());
  ASSERT_TRUE(result.motor.has_value());
  EXPECT_EQ(result.states[0].breakaways, 5U);
  const double Ts = rig.params.motor.friction.Ts_Nm;
  EXPECT_NEAR(result.motor->value.Ts_Nm, Ts, 0.05 * Ts);
  EXPECT_NEAR(result.motor->value.Ts_Nm, Ts, 4.0 * result.motor->se.Ts_Nm);
  EXPECT_LT(result.motor->se.Ts_Nm, 0.05 * Ts);
}

std::string error_of(const std::vector<table::Table>& runs, const FrictionOptions& options = {}) {
  return test::error_of([&] { fit_friction(runs, model::builtin_rig(), options); });
}

TEST(FitFrictionErrors, BadDataIsNamed) {
  const model::Model rig;
  // 0.3 V cannot break the motor free (Ts R / Kt = 0.375 V).
  const auto stuck = measure(rig, Program{}.hold(0.0, 0.2, 0).ramp(0.0, 0.3, 2.0, 0).inputs, 6, false);
  EXPECT_EQ(error_of({stuck}), "clutch state 0: the shaft never leaves stiction (largest drive torque at rest 0.004463 N m)");
  // A ramp and a single level: speeds at one or two levels only.
  const auto narrow = measure(rig, Program{}.hold(0.0, 0.2, 0).ramp(0.0, 0.6, 2.0, 0).hold(3.0, 1.0, 0).inputs, 7);
  EXPECT_EQ(error_of({narrow}).substr(0, 62), "clutch state 0: no excitation in the needed range: 2 distinct ");
  // Without clutch and load columns the run is the motor alone: the same stuck motor.
  auto alone = stuck;
  for (const char* name : {"clutch", "r_load"}) {
    const auto at = std::find(alone.names.begin(), alone.names.end(), name) - alone.names.begin();
    alone.names.erase(alone.names.begin() + at);
    alone.columns.erase(alone.columns.begin() + at);
  }
  EXPECT_EQ(error_of({alone}), error_of({stuck}));
  auto missing = stuck;
  missing.names.erase(missing.names.begin() + 1);
  missing.columns.erase(missing.columns.begin() + 1);
  EXPECT_EQ(error_of({missing}), "sim.csv: missing column 'v' (has: t,clutch,r_load,rpm)");
  auto short_run = measure(rig, Program{}.hold(1.0, 0.05, 0).inputs, 8);
  EXPECT_EQ(error_of({short_run}), "sim.csv: too short: 50 rows (at least 100 needed)");
  FrictionOptions bad;
  bad.order = 4;
  EXPECT_EQ(error_of({stuck}, bad), "--order must be 1, 2 or 3");
}

// A current-driven axis as a servo logs it: the drive torque itself and the encoder's
// position, no speed, no machine constants. The inertia and a (zero) offset are estimated
// with the friction, the speed is the position's central difference.
TEST(FitFrictionDirect, TorqueAndPositionColumnsWithInertia) {
  const model::Model rig;
  Program p;
  for (const double v : {3.0, 8.0, -5.0, 12.0, -10.0, 6.0, -2.0, 14.0, -14.0, 4.0}) {
    p.hold(v, 0.5, 0).ramp(v, -0.5 * v, 0.4, 0);
  }
  const model::Outputs out = model::simulate(rig, p.inputs);
  table::Table t;
  t.source = "servo.csv";
  std::vector<double> torque, position;
  for (std::size_t k = 0; k < out.i_A.size(); ++k) {
    torque.push_back(rig.params.motor.Kt_Nm_A * out.i_A[k]);
    position.push_back(std::floor(out.theta_rad[k] / (2.0 * M_PI) * 2048.0) * 2.0 * M_PI / 2048.0);
  }
  t.set("t", p.inputs.t_s);
  t.set("theta", position);
  t.set("torque", torque);
  FrictionOptions options;
  options.drive.torque_column = "torque";
  options.position_column = "theta";
  options.fit_inertia = true;
  options.offset = true;
  options.static_friction = false;
  options.settle_s = 0.0;
  options.window_s = 0.02;
  const FrictionResult r = fit_friction({t}, rig.params, options);
  ASSERT_EQ(r.states.size(), 1U);
  const auto& st = r.states[0];
  EXPECT_NEAR(st.inertia, rig.params.motor.J_kg_m2, 0.03 * rig.params.motor.J_kg_m2);
  EXPECT_NEAR(st.total.value.Tc_Nm, rig.params.motor.friction.Tc_Nm, 0.05 * rig.params.motor.friction.Tc_Nm);
  EXPECT_NEAR(st.total.value.viscous[0], rig.params.motor.friction.viscous[0], 0.15 * rig.params.motor.friction.viscous[0]);
  EXPECT_NEAR(st.offset, 0.0, 4.0 * st.offset_se);
  EXPECT_GT(st.inertia_se, 0.0);
}

// A gearmotor's servo logs the torque and the position at its output shaft: the friction is the
// motor shaft's (speed times the ratio, torque over it), as DriveInput reads a torque column in
// mcg-fit model and gap. Read undivided, Tc and J came out 30 times the motor's.
TEST(FitFrictionDirect, ATorqueColumnActsAtTheMeasuredShaft) {
  const model::Model rig;
  const double gear = 30.0;
  Program p;
  for (const double v : {3.0, 8.0, -5.0, 12.0, -10.0, 6.0, -2.0, 14.0, -14.0, 4.0}) {
    p.hold(v, 0.5, 0).ramp(v, -0.5 * v, 0.4, 0);
  }
  const model::Outputs out = model::simulate(rig, p.inputs);
  table::Table t;
  t.source = "gearmotor.csv";
  std::vector<double> torque, position;
  for (std::size_t k = 0; k < out.i_A.size(); ++k) {
    torque.push_back(gear * rig.params.motor.Kt_Nm_A * out.i_A[k]);
    position.push_back(out.theta_rad[k] / gear);
  }
  t.set("t", p.inputs.t_s);
  t.set("theta", position);
  t.set("torque", torque);
  FrictionOptions options;
  options.drive.torque_column = "torque";
  options.position_column = "theta";
  options.gear_ratio_override = gear;
  options.fit_inertia = true;
  options.static_friction = false;
  options.settle_s = 0.0;
  options.window_s = 0.02;
  const FrictionResult r = fit_friction({t}, rig.params, options);
  ASSERT_EQ(r.states.size(), 1U);
  const auto& st = r.states[0];
  EXPECT_NEAR(st.inertia, rig.params.motor.J_kg_m2, 0.03 * rig.params.motor.J_kg_m2);
  EXPECT_NEAR(st.total.value.Tc_Nm, rig.params.motor.friction.Tc_Nm, 0.05 * rig.params.motor.friction.Tc_Nm);
}

// A current-driven drive's i is the drive torque Kt i, whatever --no-current says; without an
// i column it names the missing column.
TEST(FitFrictionDirect, ACurrentDrivenDrivesThroughItsCommand) {
  const model::Model rig;
  Program p;
  for (const double v : {3.0, 8.0, -5.0, 12.0, -10.0, 6.0, -2.0, 14.0, -14.0, 4.0}) p.hold(v, 0.5, 0);
  const model::Outputs out = model::simulate(rig, p.inputs);
  table::Table t;
  t.source = "servo.csv";
  t.set("t", p.inputs.t_s);
  t.set("omega", out.omega_rad_s);
  t.set("i", out.i_A);
  FrictionOptions options;
  options.drive.current = true;
  options.use_current = false;
  options.order = 1;
  options.static_friction = false;
  const FrictionResult r = fit_friction({t}, rig.params, options);
  ASSERT_EQ(r.states.size(), 1U);
  EXPECT_TRUE(r.states[0].from_current);
  EXPECT_NEAR(r.states[0].total.value.Tc_Nm, rig.params.motor.friction.Tc_Nm,
              0.1 * rig.params.motor.friction.Tc_Nm);
  table::Table no_i = t;
  no_i.names.pop_back();
  no_i.columns.pop_back();
  EXPECT_EQ(test::error_of([&] { fit_friction({no_i}, rig.params, options); }),
            "servo.csv: missing column 'i' (has: t,omega)");
}

// On a current-driven drive the steps of the command are the jumps (not v, which such a drive
// need not log): the quasi-steady windows skip the acceleration after each step. With an
// inertia in the configuration that is a tenth of the shaft's, a window inside that transient
// misreads J dw/dt as friction; the command's own steps start the settling time, and the
// friction comes back within 1 % (0.3 %). Taken as never jumping (as v, which is 0 throughout,
// made it), the same run is off by more than 4 % (6 %). A noisy command (a logged current) jumps
// only at its steps.
TEST(FitFrictionDirect, ACurrentDrivesStepsAreJumps) {
  model::Model rig;
  rig.params.motor.friction.viscous = {3e-5, 0.0, 0.0};  // J / c1 = 0.24 s: settled within 1.2 s
  model::Inputs in;
  for (const double level : {0.0, 0.1, 0.25, 0.4, 0.15, 0.0, -0.1, -0.3, -0.4, -0.2, 0.3, -0.25}) {
    for (int k = 0; k < 2000; ++k) {
      in.t_s.push_back(1e-3 * static_cast<double>(in.t_s.size()));
      in.v_V.push_back(0.0);
      in.clutch.push_back(0.0);
      in.r_load_ohm.push_back(model::k_open_circuit);
      in.i_cmd_A.push_back(level);
    }
  }
  const model::Outputs out = model::simulate(rig, in);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.002);
  std::vector<double> logged = in.i_cmd_A;
  for (double& i : logged) i += noise(rng);
  table::Table t;
  t.source = "servo.csv";
  t.set("t", in.t_s);
  t.set("omega", out.omega_rad_s);
  t.set("i", logged);
  model::Params given = rig.params;
  given.motor.J_kg_m2 /= 10.0;
  FrictionOptions options;
  options.drive.current = true;
  options.order = 1;
  options.static_friction = false;
  options.settle_s = 1.2;
  const model::Friction& truth = rig.params.motor.friction;
  const FrictionResult r = fit_friction({t}, given, options);
  ASSERT_EQ(r.states.size(), 1U);
  EXPECT_NEAR(r.states[0].total.value.Tc_Nm, truth.Tc_Nm, 0.01 * truth.Tc_Nm);
  EXPECT_NEAR(r.states[0].total.value.viscous[0], truth.viscous[0], 0.01 * truth.viscous[0]);
  const double windows = static_cast<double>(r.states[0].windows);
  options.jump = 1e9;
  const FrictionResult blind = fit_friction({t}, given, options);
  ASSERT_EQ(blind.states.size(), 1U);
  const double off_tc = std::abs(blind.states[0].total.value.Tc_Nm / truth.Tc_Nm - 1.0);
  const double off_c1 = std::abs(blind.states[0].total.value.viscous[0] / truth.viscous[0] - 1.0);
  EXPECT_GT(std::max(off_tc, off_c1), 0.04);
  // The steps skip their settling time, and the noise skips nothing: about half the windows stay.
  EXPECT_LT(windows, static_cast<double>(blind.states[0].windows) - 30.0);
  EXPECT_GT(windows, 0.3 * static_cast<double>(blind.states[0].windows));
}

/// Holds of a driven shaft whose friction each hold sees shifted by its own bias (a real
/// shaft's friction varies with position and temperature): the windows of a hold err together.
/// The OLS error takes the ~19 windows of a hold as independent and is several times too small;
/// the reported error (the jackknife over the holds) covers the truth as often as an honest
/// one: over 24 seeds the RMS of (estimate - truth) / se is near 1 (the OLS error's: over 2.5).
TEST(FitFrictionDirect, StandardErrorsSeeWhatAHoldsWindowsShare) {
  const double tc = 0.01;
  const double c1 = 1e-4;
  double z2_tc = 0.0;
  double z2_c1 = 0.0;
  double z2_ols = 0.0;
  double ratio = 0.0;
  const int seeds = 24;
  for (int seed = 1; seed <= seeds; ++seed) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed));
    std::normal_distribution<double> bias(0.0, 0.05 * tc);
    std::normal_distribution<double> noise(0.0, 0.02 * tc);
    std::vector<double> t, v, theta, torque;
    double x = 0.0;
    double level = 0.0;
    for (const double w :
         {20.0, -40.0, 60.0, -80.0, 100.0, -120.0, 140.0, -160.0, 180.0, -200.0, 30.0, -70.0}) {
      const double b = bias(rng);
      for (int k = 0; k < 1000; ++k) {
        t.push_back(0.002 * static_cast<double>(t.size()));
        v.push_back(level);
        x += 0.002 * w;
        theta.push_back(x);
        torque.push_back((w > 0 ? 1.0 : -1.0) * (tc + c1 * std::abs(w)) + b + noise(rng));
      }
      level += 1.0;
    }
    table::Table tab;
    tab.source = "holds.csv";
    tab.set("t", t);
    tab.set("v", v);
    tab.set("theta", theta);
    tab.set("torque", torque);
    FrictionOptions options;
    options.order = 1;
    options.drive.torque_column = "torque";
    options.position_column = "theta";
    options.static_friction = false;
    const FrictionResult r = fit_friction({tab}, model::Params{}, options);
    ASSERT_EQ(r.states.size(), 1U);
    const auto& st = r.states[0];
    ASSERT_EQ(st.blocks, 12U);
    ASSERT_EQ(st.se_jackknife.size(), 2U);
    z2_tc += std::pow((st.total.value.Tc_Nm - tc) / st.total.se.Tc_Nm, 2);
    z2_c1 += std::pow((st.total.value.viscous[0] - c1) / st.total.se.viscous[0], 2);
    z2_ols += std::pow((st.total.value.Tc_Nm - tc) / st.se_ols[0], 2);
    ratio += st.se_jackknife[0] / st.se_ols[0] / seeds;
  }
  EXPECT_LT(std::sqrt(z2_tc / seeds), 1.6);
  EXPECT_LT(std::sqrt(z2_c1 / seeds), 1.6);
  EXPECT_GT(std::sqrt(z2_ols / seeds), 2.5);
  EXPECT_GT(ratio, 2.0);
}

}  // namespace
}  // namespace mcg::fit
