// Grey-box fit speed: 30 s of 1 kHz data (steps in all clutch states, rpm from encoder counts,
// noisy current), five free parameters started 10-20 % off, one core. Goal: at most 5 s.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include "fit/greybox.hpp"
#include "model/model.hpp"
#include "model/sensitivity.hpp"
#include "sim/encoder.hpp"

namespace {

using namespace mcg;

table::Table measured_run(const model::Model& truth) {
  model::Inputs in;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> level(-12.0, 12.0);
  const double dt = 1e-3;
  for (int seg = 0; seg < 60; ++seg) {
    const double v = seg % 6 == 0 ? 0.0 : level(rng);
    const double clutch = seg < 20 ? 0.0 : (seg < 40 ? 1.0 : 2.0);
    const double r_load = seg % 3 == 0 ? 5.6 : model::k_open_circuit;
    for (int k = 0; k < 500; ++k) {
      in.t_s.push_back(static_cast<double>(in.t_s.size()) * dt);
      in.v_V.push_back(v);
      in.clutch.push_back(clutch);
      in.r_load_ohm.push_back(r_load);
    }
  }
  const model::Outputs out = model::simulate(truth, in);
  std::normal_distribution<double> noise(0.0, 0.003);
  std::vector<double> rpm(in.t_s.size());
  std::vector<double> i(in.t_s.size());
  for (std::size_t k = 0; k < rpm.size(); ++k) {
    const double before = k >= 5 ? out.theta_rad[k - 5] : out.theta_rad[0];
    rpm[k] = (sim::encoder_count(out.theta_rad[k], 2048.0) - sim::encoder_count(before, 2048.0)) / 2048.0 / 0.005 * 60.0;
    i[k] = std::clamp(std::round((out.i_A[k] + noise(rng)) / (5.0 / 1024.0)), -512.0, 511.0) * (5.0 / 1024.0);
  }
  table::Table t;
  t.source = "bench";
  t.meta.set("rpm_estimator", "counts over 0.005 s window, 2048 counts/rev");
  t.meta.set("i_measurement", "1 ohm shunt, 10-bit ADC (range -2.5..2.495 A, saturates)");
  t.set("t", in.t_s);
  t.set("v", in.v_V);
  t.set("clutch", in.clutch);
  t.set("r_load", in.r_load_ohm);
  t.set("rpm", rpm);
  t.set("i", i);
  return t;
}

}  // namespace

int main() {
  const model::Model truth;
  const table::Table data = measured_run(truth);
  fit::FitProblem problem;
  problem.runs.push_back(fit::make_run(data, {}, problem.model.params));
  problem.free = {"motor.J_kg_m2", "motor.R_ohm", "motor.Kt_Nm_A", "motor.Ke_V_s_rad", "motor.Tc_Nm"};
  problem.model.params.motor.J_kg_m2 *= 1.2;
  problem.model.params.motor.R_ohm *= 0.9;
  problem.model.params.motor.Kt_Nm_A *= 1.1;
  problem.model.params.motor.Ke_V_s_rad *= 1.1;
  problem.model.params.motor.friction.Tc_Nm *= 0.85;
  problem.sim.max_step_s = 2.5e-4;
  problem.nls.threads = 1;

  const auto t0 = std::chrono::steady_clock::now();
  model::simulate(problem.model, problem.runs[0].inputs, problem.sim);
  const auto t1 = std::chrono::steady_clock::now();
  const fit::FitResult result = fit::fit_model(problem);
  const auto t2 = std::chrono::steady_clock::now();
  const double sim_s = std::chrono::duration<double>(t1 - t0).count();
  const double fit_s = std::chrono::duration<double>(t2 - t1).count();
  fmt::print("grey-box fit, {} samples ({:.0f} s at 1 kHz), {} free parameters, one core\n", data.rows(),
             static_cast<double>(data.rows()) * 1e-3, problem.free.size());
  fmt::print("  one simulation   {:8.3f} s\n", sim_s);
  fmt::print("  whole fit        {:8.3f} s   (goal <= 5 s)  {} iterations, {} simulations, converged: {}\n", fit_s,
             result.nls.iterations, result.nls.evaluations, result.nls.converged ? "yes" : "no");
  for (std::size_t k = 0; k < problem.free.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    fmt::print("  {:20s} {:12.6g} +- {:.2g}  (truth {:.6g})\n", problem.free[k], result.nls.values[i],
               result.nls.std_errors[i], model::get_parameter(truth, problem.free[k]));
  }
  fmt::print("  fit rpm {:.2f} %, i {:.2f} %\n", result.runs[0].fit_percent[0], result.runs[0].fit_percent[1]);

  // The same fit with its Jacobians by sensitivities (one simulation on dual numbers carrying
  // the five directions) instead of five more simulations each.
  const auto t3 = std::chrono::steady_clock::now();
  const auto sens =
      model::simulate_sensitivities(problem.model, model::parameter_directions(problem.model, problem.free),
                                    problem.runs[0].inputs, problem.sim);
  const auto t4 = std::chrono::steady_clock::now();
  problem.sensitivities = true;
  const fit::FitResult by_sens = fit::fit_model(problem);
  const auto t5 = std::chrono::steady_clock::now();
  const double dual_s = std::chrono::duration<double>(t4 - t3).count();
  fmt::print(
      "  one simulation with the sensitivities to the {} parameters {:8.3f} s ({:.1f} simulations' time; "
      "finite differences take {})\n",
      problem.free.size(), dual_s, dual_s / sim_s, problem.free.size() + 1);
  fmt::print(
      "  whole fit, Jacobians by sensitivities {:8.3f} s  {} iterations, {} Jacobians, converged: {}{}\n",
      std::chrono::duration<double>(t5 - t4).count(), by_sens.nls.iterations,
      by_sens.nls.sensitivity_jacobians, by_sens.nls.converged ? "yes" : "no",
      sens ? "" : " (no sensitivities)");
  for (std::size_t k = 0; k < problem.free.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    fmt::print("  {:20s} {:12.6g} +- {:.2g}  (finite differences {:.6g} +- {:.2g})\n", problem.free[k],
               by_sens.nls.values[i], by_sens.nls.std_errors[i], result.nls.values[i],
               result.nls.std_errors[i]);
  }
  return result.nls.converged && fit_s <= 5.0 ? 0 : 1;
}
