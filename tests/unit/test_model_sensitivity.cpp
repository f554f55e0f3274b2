// The sensitivities the plant carries on dual numbers (model/sensitivity.hpp) are the
// derivatives of the simulation: they equal central finite differences of whole simulations
// for every nominal parameter and every parameter of every effect of the catalog, on a run
// that passes through each mode the plant has (motor alone, engaging the clutch on a load,
// reversing through zero with stick-slip, holding stuck, the clutch released).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "model/model.hpp"
#include "model/sensitivity.hpp"

namespace mcg::model {
namespace {

/// 3 s at 1 kHz: 6 V alone; engaged on 5.6 ohm at 8 V; -4 V (through zero); 0.3 V (stuck);
/// released (clutch 1) at 10 V on an open circuit.
Inputs through_every_mode() {
  Inputs in;
  for (int n = 0; n <= 3000; ++n) {
    const double t = n * 1e-3;
    in.t_s.push_back(t);
    double v = 6.0, clutch = 0.0, load = k_open_circuit;
    if (t >= 0.5) clutch = 2.0, load = 5.6, v = 8.0;
    if (t >= 1.2) v = -4.0;
    if (t >= 1.8) v = 0.3;
    if (t >= 2.4) clutch = 1.0, load = k_open_circuit, v = 10.0;
    in.v_V.push_back(v);
    in.clutch.push_back(clutch);
    in.r_load_ohm.push_back(load);
  }
  return in;
}

/// |a - b| / max(|b|, floor) over a whole series.
double relative_error(const std::vector<double>& a, const std::vector<double>& b, double floor) {
  double diff = 0.0, norm = 0.0;
  for (std::size_t n = 0; n < a.size(); ++n) {
    diff += (a[n] - b[n]) * (a[n] - b[n]);
    norm += b[n] * b[n];
  }
  return std::sqrt(diff) / std::max(std::sqrt(norm), floor);
}

/// A parameter's size: its value, or at 0 a thousandth of its range.
double size_of(const Model& m, const std::string& name) {
  for (const ParamInfo& p : parameters(m)) {
    if (p.name == name)
      return p.value != 0.0 ? std::abs(p.value) : 1e-3 * std::max(std::abs(p.lower), std::abs(p.upper));
  }
  return 0.0;
}

/// Central finite differences of whole simulations, a relative step `rel` of the parameter's size.
Outputs finite_difference(const Model& m, const std::string& name, double rel, const Inputs& in,
                          const SimOptions& options) {
  const double v = get_parameter(m, name);
  const double h = rel * size_of(m, name);
  Model plus = m, minus = m;
  set_parameter(plus, name, v + h);
  set_parameter(minus, name, v - h);
  const Outputs a = simulate(plus, in, options), b = simulate(minus, in, options);
  Outputs d;
  d.resize(in.t_s.size());
  for (std::size_t n = 0; n < in.t_s.size(); ++n) {
    d.omega_rad_s[n] = (a.omega_rad_s[n] - b.omega_rad_s[n]) / (2 * h);
    d.theta_rad[n] = (a.theta_rad[n] - b.theta_rad[n]) / (2 * h);
    d.i_A[n] = (a.i_A[n] - b.i_A[n]) / (2 * h);
    d.i_gen_A[n] = (a.i_gen_A[n] - b.i_gen_A[n]) / (2 * h);
  }
  return d;
}

/// The sensitivities of `names` against finite differences: within 1e-4 of the finite
/// difference's size in speed, angle and both currents, where a parameter moves an output by
/// more than 1e-7 of the output's size per relative change (below, the finite difference is
/// its own rounding: compared absolutely against that floor), and the values exactly the plain
/// simulation's. The finite differences take the best of three steps, 1e-4, 1e-5 and 1e-6 of
/// the parameter's size: a large step meets the parameter's curvature (a cogging order N
/// moves the phase N theta by 1e-4 N theta, radians after a few hundred turns), a small one
/// the rounding of the events' location (1e-4 of the derivative at 1e-5 of a static level).
void expect_matches(const Model& m, const std::vector<std::string>& names, const SimOptions& options = {}) {
  const Inputs in = through_every_mode();
  const auto sens = simulate_sensitivities(m, parameter_directions(m, names), in, options);
  ASSERT_TRUE(sens.has_value());
  const Outputs plain = simulate(m, in, options);
  EXPECT_EQ(sens->value.omega_rad_s, plain.omega_rad_s);
  EXPECT_EQ(sens->value.i_A, plain.i_A);
  const auto floor = [&](const std::vector<double>& y, double size) {
    double sq = 0.0;
    for (double x : y) sq += x * x;
    return 1e-7 * std::sqrt(sq) / size;
  };
  for (std::size_t j = 0; j < names.size(); ++j) {
    SCOPED_TRACE(names[j]);
    const double size = size_of(m, names[j]);
    const Outputs& ad = sens->d[j];
    double worst = std::numeric_limits<double>::infinity();
    for (double rel : {1e-4, 1e-5, 1e-6}) {
      const Outputs fd = finite_difference(m, names[j], rel, in, options);
      worst = std::min(
          worst, std::max({relative_error(ad.omega_rad_s, fd.omega_rad_s, floor(plain.omega_rad_s, size)),
                           relative_error(ad.theta_rad, fd.theta_rad, floor(plain.theta_rad, size)),
                           relative_error(ad.i_A, fd.i_A, floor(plain.i_A, size)),
                           relative_error(ad.i_gen_A, fd.i_gen_A, floor(plain.i_gen_A, size))}));
    }
    EXPECT_LT(worst, 1e-4);
  }
}

TEST(ModelSensitivity, EqualFiniteDifferencesForEveryNominalParameter) {
  Model m;
  m.params.dead_time_s = 0.0023;  // between rows: see ADeadTimeOnTheRowsIsDifferentiatedFromBelow
  std::vector<std::string> names;
  for (const ParamInfo& p : parameters(m)) names.push_back(p.name);
  expect_matches(m, names);
}

/// Values inside every parameter's range where the catalog's default sits on a bound or
/// leaves the effect idle (a dead band of 0 has no derivative from below).
const std::map<std::string, double> k_interior = {
    {"thermal.dT0_K", 5.0},
    {"friction_levels.Ts_excess_Nm", 0.002},
    {"friction_levels.c1_Nm_s_rad", 1e-5},
    {"pwm_coast.coast", 0.6},
    {"cogging.phase_rad", 0.4},
    {"cogging.T_c_Nm", 0.004},
    {"dead_time.tau_d_s", 0.0023},
};

TEST(ModelSensitivity, EqualFiniteDifferencesForEveryParameterOfEveryEffect) {
  for (const EffectSpec& spec : effect_catalog()) {
    SCOPED_TRACE(spec.name);
    Model m;
    m.effects.push_back(default_effect(spec.name));
    std::vector<std::string> names;
    for (const EffectParamSpec& p : spec.params) {
      const std::string name = spec.name + "." + p.name;
      if (const auto it = k_interior.find(name); it != k_interior.end()) set_parameter(m, name, it->second);
      names.push_back(name);
    }
    expect_matches(m, names);
  }
}

TEST(ModelSensitivity, EqualFiniteDifferencesOnTheRegularisedStick) {
  Model m;
  m.effects.push_back(parse_effect("friction_levels:Tc_Nm=0.002,Ts_excess_Nm=0.003,c1_Nm_s_rad=1e-5"));
  SimOptions options;
  options.smooth_stick = true;
  expect_matches(m, {"friction_levels.Tc_Nm", "friction_levels.Ts_excess_Nm", "motor.J_kg_m2", "motor.R_ohm"},
                 options);
}

TEST(ModelSensitivity, ATorqueDriveDifferentiatesItsCommandedCurrent) {
  Inputs in = through_every_mode();
  for (double& v : in.v_V) in.T_cmd_Nm.push_back(0.01 * v);
  Model m;
  const std::vector<std::string> names = {"motor.Kt_Nm_A", "motor.J_kg_m2"};
  const auto sens = simulate_sensitivities(m, parameter_directions(m, names), in);
  ASSERT_TRUE(sens.has_value());
  // The torque is commanded, so the speed does not depend on Kt (the current does: T / Kt).
  for (double d : sens->d[0].omega_rad_s) EXPECT_NEAR(d, 0.0, 1e-6);
  const Outputs fd = [&] {
    Model a = m, b = m;
    set_parameter(a, "motor.J_kg_m2", 7.06e-6 * (1 + 1e-5));
    set_parameter(b, "motor.J_kg_m2", 7.06e-6 * (1 - 1e-5));
    Outputs pa = simulate(a, in), pb = simulate(b, in), d;
    d.resize(in.t_s.size());
    for (std::size_t n = 0; n < in.t_s.size(); ++n)
      d.omega_rad_s[n] = (pa.omega_rad_s[n] - pb.omega_rad_s[n]) / (2e-5 * 7.06e-6);
    return d;
  }();
  EXPECT_LT(relative_error(sens->d[1].omega_rad_s, fd.omega_rad_s, 1e-9), 1e-4);
}

TEST(ModelSensitivity, ADeadTimeOnTheRowsIsDifferentiatedFromBelow) {
  // A delay of two rows switches the bridge on a row: the row's sample has the new command
  // for a delay just below, the old one just above, so the sampled run has a kink there. The
  // sensitivity is the derivative from below (the switch inside the row before), its jump
  // (f_before - f_after) d(t_switch) the continuous-time one: the finite difference
  // differentiates the integrator's short step before the switch, which agrees with it to the
  // scheme's accuracy, 1e-3 on the step into a start from rest.
  Model m;
  m.params.dead_time_s = 0.002;
  const Inputs in = through_every_mode();
  const auto sens = simulate_sensitivities(m, parameter_directions(m, {"drive.dead_time_s"}), in);
  ASSERT_TRUE(sens.has_value());
  const double h = 1e-8;
  Model below = m;
  below.params.dead_time_s -= h;
  const Outputs a = simulate(m, in), b = simulate(below, in);
  std::vector<double> fd_w, fd_i;
  for (std::size_t n = 0; n < in.t_s.size(); ++n) {
    fd_w.push_back((a.omega_rad_s[n] - b.omega_rad_s[n]) / h);
    fd_i.push_back((a.i_A[n] - b.i_A[n]) / h);
  }
  EXPECT_LT(relative_error(sens->d[0].omega_rad_s, fd_w, 1e-9), 1e-3);
  EXPECT_LT(relative_error(sens->d[0].i_A, fd_i, 1e-9), 1e-3);
}

TEST(ModelSensitivity, ADiscrepancyTermWithoutDualFunctionsHasNone) {
  Model m;
  m.shaft_terms.push_back(
      {"test", [](const std::array<double, 4>& k, double, double w) { return k[3] * w; }, {0, 0, 0, 1e-6}});
  EXPECT_FALSE(
      simulate_sensitivities(m, parameter_directions(m, {"motor.R_ohm"}), through_every_mode()).has_value());
}

}  // namespace
}  // namespace mcg::model
