// The rig model against closed forms and against the report where the report is right.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>

#include "model/model.hpp"

namespace mcg::model {
namespace {

constexpr double k_rpm_per_rad_s = 30.0 / std::numbers::pi;

/// Rows every dt_s over [0, duration_s]; v, clutch and r_load given as functions of t.
Inputs program(double duration_s, double dt_s, const std::function<double(double)>& v,
               const std::function<int(double)>& clutch, const std::function<double(double)>& r_load) {
  Inputs in;
  const auto n = static_cast<std::size_t>(std::llround(duration_s / dt_s)) + 1;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * dt_s;
    in.t_s.push_back(t);
    in.v_V.push_back(v(t));
    in.clutch.push_back(clutch(t));
    in.r_load_ohm.push_back(r_load(t));
  }
  return in;
}

Inputs constant(double v, double duration_s, double dt_s, int clutch, double r_load = k_open_circuit) {
  return program(
      duration_s, dt_s, [v](double) { return v; }, [clutch](double) { return clutch; },
      [r_load](double) { return r_load; });
}

double rms_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) s += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(s / static_cast<double>(a.size()));
}

/// A 10 s program with stick-slip (slow, low and reversing voltages), clutch switching
/// 1 -> 2 -> 0 -> 1 -> 2 and load switching, sampled at an uneven 1 ms +- 0.3 ms.
Inputs stick_slip_program() {
  Inputs in;
  double t = 0.0;
  for (int k = 0; t <= 10.0; ++k) {
    const double v = t < 2.0   ? 1.6 * std::sin(2.0 * std::numbers::pi * 0.8 * t)
                     : t < 4.0 ? 6.0 + 5.0 * std::sin(2.0 * std::numbers::pi * 3.0 * t)
                     : t < 6.0 ? (std::fmod(t, 0.5) < 0.25 ? 1.0 : -9.0)
                     : t < 8.0 ? 0.9 + 0.6 * std::sin(2.0 * std::numbers::pi * 2.0 * t)
                               : 10.0 * std::sin(2.0 * std::numbers::pi * 0.7 * t);
    const int clutch = t < 1.3 ? 1 : t < 3.1 ? 2 : t < 4.6 ? 0 : t < 6.7 ? 1 : 2;
    const double r_load = std::fmod(t, 1.7) < 0.9 ? 5.6 : k_open_circuit;
    in.t_s.push_back(t);
    in.v_V.push_back(v);
    in.clutch.push_back(clutch);
    in.r_load_ohm.push_back(r_load);
    t += 1e-3 + 3e-4 * std::sin(1.3 * k);
  }
  return in;
}

TEST(ModelAccuracy, HalvingTheStepChangesRpmByLessThanFiveHundredthsRms) {
  const Inputs in = stick_slip_program();
  // The default step (1 ms, the circuits' decay taken exactly) against half of it.
  const SimOptions coarse;
  SimOptions fine;
  fine.max_step_s = 0.5e-3;
  const Outputs a = simulate(Model{}, in, coarse);
  const Outputs b = simulate(Model{}, in, fine);
  // The program does stick: some rows at rest, and the motor does reach high speed.
  std::size_t at_rest = 0;
  for (double w : a.omega_rad_s) at_rest += w == 0.0 ? 1 : 0;
  EXPECT_GT(at_rest, 500u);
  EXPECT_GT(*std::max_element(a.rpm.begin(), a.rpm.end()), 1500.0);
  const double rms = rms_difference(a.rpm, b.rpm);
  EXPECT_LT(rms, 0.05);
}

/// A motor alone (no clutch, no generator) with equal Kt and Ke and Coulomb and static levels.
Model motor_alone(double R_ohm, double L_H, double K, double J_kg_m2, double Tc_Nm, double Ts_Nm,
                  double supply_V) {
  Model m;
  Machine& mm = m.params.motor;
  mm.R_ohm = R_ohm;
  mm.L_H = L_H;
  mm.Kt_Nm_A = K;
  mm.Ke_V_s_rad = K;
  mm.J_kg_m2 = J_kg_m2;
  mm.friction.Tc_Nm = Tc_Nm;
  mm.friction.Ts_Nm = Ts_Nm;
  m.params.supply_V = supply_V;
  return m;
}

/// 10 s of levels in steps of `step_V` (-4..4 of them) that reverse and stop the motor, rows dt_s apart.
Inputs reversing_levels(double dt_s, double step_V) {
  return program(
      10.0, dt_s,
      [step_V](double t) {
        const double s =
            std::sin(2.0 * std::numbers::pi * 0.7 * t) + 0.6 * std::sin(2.0 * std::numbers::pi * 2.3 * t);
        return std::round(4.0 * s) * step_V;
      },
      [](double) { return 0; }, [](double) { return k_open_circuit; });
}

/// The run stops more than 20 rows and turns both ways faster than `rpm`.
void expect_stops_and_reverses(const Outputs& out, double rpm) {
  std::size_t at_rest = 0;
  for (double w : out.omega_rad_s) at_rest += w == 0.0 ? 1 : 0;
  EXPECT_GT(at_rest, 20u);
  EXPECT_GT(*std::max_element(out.rpm.begin(), out.rpm.end()), rpm);
  EXPECT_LT(*std::min_element(out.rpm.begin(), out.rpm.end()), -rpm);
}

// A 100:1 gearmotor at 50 Hz (L/R = 0.1 ms, mechanical time constant 33 ms) on levels that
// reverse and stop it: its circuit's decay is over within a quarter of the 1 ms step, so the
// fits' step is not held to half its L/R (SimOptions::circuit_bound), and the speed is still
// within 0.03 rpm RMS of 10 us steps.
TEST(ModelAccuracy, ACircuitOverWithinAStepDoesNotBoundTheFitsStep) {
  const Model m = motor_alone(10.0, 1e-3, 0.3476, 4e-4, 0.0109, 0.0109, 5.0);
  const Inputs in = reversing_levels(0.02, 1.2);
  const SimOptions fit;
  SimOptions unbound;
  unbound.circuit_bound = false;
  SimOptions fine;
  fine.max_step_s = 1e-5;
  const Outputs a = simulate(m, in, fit);
  const Outputs b = simulate(m, in, unbound);
  const Outputs c = simulate(m, in, fine);
  expect_stops_and_reverses(c, 100.0);
  EXPECT_EQ(a.rpm, b.rpm);
  EXPECT_LT(rms_difference(a.rpm, c.rpm), 0.03);
  // The rig's motor (L/R = 1.05 ms) is resolved: half its L/R.
  EXPECT_NE(simulate(Model{}, stick_slip_program(), fit).rpm,
            simulate(Model{}, stick_slip_program(), unbound).rpm);
}

// A 73:1 gearmotor (L/R = 0.5 ms, mechanical time constant 46 ms) logged at 100 Hz on levels
// that reverse and stop it: its circuit's decay spans half a 1 ms step but is over within a
// twentieth of a row, so the fits' step is the mechanical bound (1 ms), not half its L/R, and the
// motor's speed (up to 8000 rpm) is within 0.25 rpm RMS of 10 us steps (0.17 measured; 0.003
// rpm at the output shaft, against 1.3 rpm of one encoder count a row). Logged at 1 kHz, the
// same circuit is resolved.
TEST(ModelAccuracy, ACircuitOverWithinARowDoesNotBoundTheFitsStep) {
  const Model m = motor_alone(2.82, 1.41e-3, 0.0142, 3.27e-6, 0.0064, 0.0074, 12.0);
  SimOptions unbound;
  unbound.circuit_bound = false;
  SimOptions fine;
  fine.max_step_s = 1e-5;
  const Inputs slow = reversing_levels(0.01, 2.5);
  const Outputs a = simulate(m, slow, SimOptions{});
  const Outputs c = simulate(m, slow, fine);
  expect_stops_and_reverses(c, 3000.0);
  EXPECT_EQ(a.rpm, simulate(m, slow, unbound).rpm);
  EXPECT_LT(rms_difference(a.rpm, c.rpm), 0.25);
  const Inputs fast = reversing_levels(0.001, 2.5);
  EXPECT_NE(simulate(m, fast, SimOptions{}).rpm, simulate(m, fast, unbound).rpm);
}

// A cogging ripple of 40 cycles a revolution on the rig's motor alone, driven by a current
// that breaks it away and runs it between about 100 and 330 rad/s: the step follows the speed
// so that the ripple's phase moves at most 2 rad a step, also where no circuit bounds the
// step, and the speed is within 0.1 rpm RMS of 10 us steps. (Unresolved, at 1 ms steps and
// 13 rad a step, it was 15.3 rpm RMS off: more than the ripple's own 5.8 rpm.)
TEST(ModelAccuracy, ACoggingRippleIsResolvedWithoutACircuitToBoundTheStep) {
  Model m;
  Effect cog = default_effect("cogging");
  cog.set("T_c_Nm", 2e-3);
  cog.set("N_per_rev", 40.0);
  m.effects.push_back(cog);
  Inputs in = constant(0.0, 4.0, 0.02, 0);
  for (double t : in.t_s) in.i_cmd_A.push_back(0.11 + 0.05 * std::sin(2.0 * std::numbers::pi * 0.5 * t));
  SimOptions fine;
  fine.max_step_s = 1e-5;
  const Outputs a = simulate(m, in, {});
  const Outputs b = simulate(m, in, fine);
  const Outputs plain = simulate(Model{}, in, fine);
  const double ripple_rpm = rms_difference(b.rpm, plain.rpm);
  EXPECT_GT(*std::max_element(b.omega_rad_s.begin(), b.omega_rad_s.end()), 300.0);
  EXPECT_GT(ripple_rpm, 1.0);
  EXPECT_LT(rms_difference(a.rpm, b.rpm), 0.1);
}

TEST(ModelPhysics, StuckShaftNeitherCreepsNorChatters) {
  // Motor alone coasting down under 0.15 V: below Tc R / Kt = 0.171 V it cannot keep turning,
  // and at rest it holds Kt 0.15 / R = 2.2e-3 N m, well inside the static band (5.59e-3 N m).
  const Inputs in = program(
      1.0, 1e-3, [](double t) { return t < 0.3 ? 6.0 : 0.15; }, [](double) { return 0; },
      [](double) { return k_open_circuit; });
  const Outputs out = simulate(Model{}, in, {});
  const std::size_t last = out.theta_rad.size() - 1;
  EXPECT_EQ(out.omega_rad_s[last], 0.0);
  // Once at rest the angle never changes again and the speed never leaves zero.
  std::size_t first_rest = 0;
  while (out.omega_rad_s[first_rest] != 0.0 || in.t_s[first_rest] < 0.3) ++first_rest;
  for (std::size_t k = first_rest; k <= last; ++k) {
    EXPECT_EQ(out.omega_rad_s[k], 0.0);
    EXPECT_EQ(out.theta_rad[k], out.theta_rad[first_rest]);
  }
  // At rest the current settles to v / R: no back-EMF.
  EXPECT_NEAR(out.i_A[last], 0.15 / 3.91, 1e-9);
}

TEST(ModelPhysics, CoupledBreakawayVoltageOnASlowRampIsTheReports) {
  // (Ts_m + Ts_clutch + Ts_g) R / Kt = 18.0711e-3 * 3.91 / 0.0582 = 1.2140 V; the report's
  // Simulink model gave 1.216 V, the rig 1.25 V.
  const Inputs in = constant(0.0, 2.0, 1e-3, 2);
  Inputs ramp = in;
  for (std::size_t k = 0; k < ramp.t_s.size(); ++k) ramp.v_V[k] = 1.0 + 0.25 * ramp.t_s[k];
  const Outputs out = simulate(Model{}, ramp, {});
  std::size_t k = 0;
  while (out.omega_rad_s[k] == 0.0) ++k;
  const double v_break = ramp.v_V[k - 1];
  EXPECT_NEAR(v_break, 1.2140, 0.0015);
  EXPECT_NEAR(v_break, 1.216, 0.01);
}

TEST(ModelPhysics, CoupledIncrementalDcGainMatchesClosedFormAndReport) {
  // Steady state: Kt i = F(w), v = R i + Ke w, so dw/dv = 1 / (Ke + R F'(w) / Kt).
  const Params p = builtin_rig();
  const Friction F = [&] {
    Friction f;
    for (const Friction* e : {&p.motor.friction, &p.clutch_engaged, &p.generator.friction}) {
      for (std::size_t j = 0; j < 3; ++j) f.viscous[j] += e->viscous[j];
      f.Tc_Nm += e->Tc_Nm;
    }
    return f;
  }();
  const Outputs lo = simulate(Model{}, constant(7.5, 1.0, 1e-3, 2), {});
  const Outputs hi = simulate(Model{}, constant(8.5, 1.0, 1e-3, 2), {});
  const double gain = hi.omega_rad_s.back() - lo.omega_rad_s.back();
  const double w = 0.5 * (hi.omega_rad_s.back() + lo.omega_rad_s.back());
  const double dF = F.viscous[0] + 2.0 * F.viscous[1] * w + 3.0 * F.viscous[2] * w * w;
  EXPECT_NEAR(gain, 1.0 / (p.motor.Ke_V_s_rad + p.motor.R_ohm * dF / p.motor.Kt_Nm_A), 0.01);
  EXPECT_NEAR(gain, 16.557, 0.5);  // the report's second-order fit
}

TEST(ModelPhysics, CoupledStepTimeConstantIsJROverKtKeNotTheReports14ms) {
  // J R / (Kt Ke) = 14.12e-6 * 3.91 / 0.0582^2 = 16.30 ms; the report quotes 14.7 ms, which its
  // own parameters cannot give. The incremental step 6 -> 8 V has its 63 % point near 16 ms
  // (the electrical pole adds about L/R = 1 ms, viscous friction takes a little off).
  const Params p = builtin_rig();
  EXPECT_NEAR(2 * p.motor.J_kg_m2 * p.motor.R_ohm / (p.motor.Kt_Nm_A * p.motor.Ke_V_s_rad), 16.30e-3, 0.01e-3);
  const Inputs in = program(
      1.0, 1e-4, [](double t) { return t < 0.5 ? 6.0 : 8.0; }, [](double) { return 2; },
      [](double) { return k_open_circuit; });
  const Outputs out = simulate(Model{}, in, {});
  const std::size_t k0 = 5000;
  const double w0 = out.omega_rad_s[k0];
  const double w1 = out.omega_rad_s.back();
  std::size_t k = k0;
  while (out.omega_rad_s[k] < w0 + 0.632 * (w1 - w0)) ++k;
  const double t63 = in.t_s[k] - in.t_s[k0];
  EXPECT_GT(t63, 15.5e-3);
  EXPECT_LT(t63, 17.5e-3);
  EXPECT_GT(t63, 14.7e-3 * 1.05);
}

TEST(ModelPhysics, EngagementConservesAngularMomentum) {
  // Motor running in state 1, generator at rest; engage: w = Jm wm / (Jm + Jg) = wm / 2.
  Plant plant(Model{}, {}, 1);
  for (int k = 0; k < 500; ++k) plant.step(1e-3, {6.0, 1, k_open_circuit});
  const double wm = plant.state().omega_rad_s;
  EXPECT_EQ(plant.state().omega_gen_rad_s, 0.0);
  plant.step(1e-9, {6.0, 2, k_open_circuit});
  EXPECT_NEAR(plant.state().omega_rad_s, 0.5 * wm, 1e-6 * wm);
  EXPECT_EQ(plant.state().omega_gen_rad_s, plant.state().omega_rad_s);
}

TEST(ModelPhysics, DisengagedGeneratorCoastsDownUnderItsCoulombFriction) {
  // Without viscous friction the generator decelerates at Tc / Jg: it stops after Jg w0 / Tc.
  Model m;
  m.params.generator.friction.viscous = {0.0, 0.0, 0.0};
  Plant plant(m, {}, 2);
  for (int k = 0; k < 800; ++k) plant.step(1e-3, {8.0, 2, k_open_circuit});
  plant.step(1e-3, {8.0, 1, k_open_circuit});
  const double w0 = plant.state().omega_gen_rad_s;
  const double decel = m.params.generator.friction.Tc_Nm / m.params.generator.J_kg_m2;
  const double t_stop = w0 / decel;
  plant.step(0.5 * t_stop, {8.0, 1, k_open_circuit});
  EXPECT_NEAR(plant.state().omega_gen_rad_s, 0.5 * w0, 1e-6 * w0);
  EXPECT_NEAR(plant.state().v_gen_V, m.params.generator.Ke_V_s_rad * 0.5 * w0, 1e-6);
  EXPECT_EQ(plant.state().i_gen_A, 0.0);
  plant.step(0.5 * t_stop + 1e-4, {8.0, 1, k_open_circuit});
  EXPECT_EQ(plant.state().omega_gen_rad_s, 0.0);
  const double theta = plant.state().theta_gen_rad;
  plant.step(0.1, {8.0, 1, k_open_circuit});
  EXPECT_EQ(plant.state().theta_gen_rad, theta);
  EXPECT_GT(plant.state().omega_rad_s, 100.0);
}

TEST(ModelPhysics, LoadedGeneratorSteadyStateIsOhmsLaw) {
  const Outputs out = simulate(Model{}, constant(10.0, 1.0, 1e-3, 2, 5.6), {});
  const Params p = builtin_rig();
  const double w = out.omega_rad_s.back();
  EXPECT_NEAR(out.i_gen_A.back(), p.generator.Ke_V_s_rad * w / (p.generator.R_ohm + 5.6), 1e-7);
  EXPECT_NEAR(out.v_gen_V.back(), 5.6 * out.i_gen_A.back(), 1e-12);
  // Torque balance on the coupled shaft: Kt (i - i_gen) = F(w).
  const double F = p.motor.friction.kinetic_Nm(w) + p.clutch_engaged.kinetic_Nm(w) +
                   p.generator.friction.kinetic_Nm(w);
  EXPECT_NEAR(p.motor.Kt_Nm_A * (out.i_A.back() - out.i_gen_A.back()), F, 1e-8);
  // Open circuit: no current at all, v_gen is the EMF.
  const Outputs open = simulate(Model{}, constant(10.0, 0.5, 1e-3, 2), {});
  for (double i : open.i_gen_A) EXPECT_EQ(i, 0.0);
  EXPECT_NEAR(open.v_gen_V.back(), p.generator.Ke_V_s_rad * open.omega_rad_s.back(), 1e-12);
}

TEST(ModelPhysics, NegativeVoltageRunsBackwardsSymmetrically) {
  const Outputs fwd = simulate(Model{}, constant(5.0, 0.5, 1e-3, 1), {});
  const Outputs rev = simulate(Model{}, constant(-5.0, 0.5, 1e-3, 1), {});
  for (std::size_t k = 0; k < fwd.rpm.size(); ++k) {
    EXPECT_NEAR(fwd.rpm[k], -rev.rpm[k], 1e-9);
  }
}

TEST(ModelPhysics, BridgeSaturatesAtTheSupply) {
  const Outputs a = simulate(Model{}, constant(20.0, 0.3, 1e-3, 0), {});
  const Outputs b = simulate(Model{}, constant(35.0, 0.3, 1e-3, 0), {});
  EXPECT_EQ(a.rpm.back(), b.rpm.back());
  EXPECT_EQ(b.v_applied_V.back(), 20.0);
}

TEST(ModelPlant, SteppingInChunksEqualsSimulate) {
  const Inputs in = program(
      0.3, 1e-3, [](double t) { return t < 0.1 ? 4.0 : 9.0; }, [](double t) { return t < 0.2 ? 1 : 2; },
      [](double) { return 5.6; });
  const Outputs out = simulate(Model{}, in, {});
  Plant plant(Model{}, {}, 1);
  for (std::size_t k = 0; k + 1 < in.t_s.size(); ++k) {
    EXPECT_EQ(plant.state().omega_rad_s, out.omega_rad_s[k]);
    plant.step(in.t_s[k + 1] - in.t_s[k],
               {in.v_V[k], static_cast<int>(in.clutch[k]), in.r_load_ohm[k]});
  }
  Plant copy = plant;
  copy.step(0.01, {5.0, 2, 5.6});
  plant.step(0.01, {5.0, 2, 5.6});
  EXPECT_EQ(copy.state().theta_rad, plant.state().theta_rad);
}

TEST(ModelPhysics, OutputsAreInRadPerSecondAndRpm) {
  const Outputs out = simulate(Model{}, constant(6.0, 0.2, 1e-3, 0), {});
  EXPECT_NEAR(out.rpm.back(), out.omega_rad_s.back() * k_rpm_per_rad_s, 1e-9);
}

TEST(ModelPhysics, CurrentDrivenMotorFollowsTheMechanicalClosedForm) {
  // An ideal current loop holds i = i_cmd: J dw/dt = Kt i - Tc - c1 w, so from rest (once the
  // drive exceeds the breakaway) w(t) = w_inf (1 - exp(-t c1 / J)), w_inf = (Kt i - Tc) / c1,
  // with no electrical lag; the voltage the loop applies is R i + Ke w.
  Model m;
  Friction& f = m.params.motor.friction;
  f.viscous = {2e-5, 0.0, 0.0};
  const double i_cmd = 0.5;
  const Machine& mm = m.params.motor;
  const double w_inf = (mm.Kt_Nm_A * i_cmd - f.Tc_Nm) / f.viscous[0];
  const double tau = mm.J_kg_m2 / f.viscous[0];
  Inputs in = constant(0.0, 0.5, 1e-3, 0);
  in.i_cmd_A.assign(in.t_s.size(), i_cmd);
  const Outputs out = simulate(m, in);
  for (std::size_t k : {std::size_t{1}, std::size_t{50}, std::size_t{500}}) {
    const double w = w_inf * (1.0 - std::exp(-in.t_s[k] / tau));
    EXPECT_NEAR(out.omega_rad_s[k], w, 1e-6 * w_inf) << "row " << k;
    EXPECT_EQ(out.i_A[k], i_cmd) << "row " << k;
    EXPECT_NEAR(out.v_applied_V[k], mm.R_ohm * i_cmd + mm.Ke_V_s_rad * out.omega_rad_s[k], 1e-9)
        << "row " << k;
  }
  // A torque-driven run is the same drive through T = Kt i.
  Inputs torque = in;
  torque.i_cmd_A.clear();
  torque.T_cmd_Nm.assign(in.t_s.size(), mm.Kt_Nm_A * i_cmd);
  EXPECT_NEAR(simulate(m, torque).omega_rad_s[500], out.omega_rad_s[500], 1e-9 * w_inf);
}

}  // namespace
}  // namespace mcg::model
