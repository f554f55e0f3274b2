// Simulation speed: 60 s of the coupled rig under the report's PI at 1 ms (the fit engineer's
// inner loop), and 60 s open loop; prints the real-time factor and the step-halving accuracy.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>

#include "boardunits/fixed_point.hpp"
#include "model/model.hpp"
#include "sim/controller.hpp"

namespace {

constexpr double k_duration_s = 60.0;
constexpr double k_dt_s = 1e-3;

mcg::sim::ClosedLoopInputs pi_program() {
  mcg::sim::ClosedLoopInputs in;
  const auto n = static_cast<std::size_t>(k_duration_s / k_dt_s);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * k_dt_s;
    in.t_s.push_back(t);
    // Command steps every 0.5 s between 100 and 1500 rpm, a load toggling every 0.7 s.
    in.rpm_cmd.push_back(100.0 + 1400.0 * std::fabs(std::sin(0.37 * std::floor(t / 0.5))));
    in.clutch.push_back(2);
    in.r_load_ohm.push_back(std::fmod(t, 1.4) < 0.7 ? 5.6 : mcg::model::k_open_circuit);
  }
  return in;
}

mcg::model::Inputs open_program() {
  mcg::model::Inputs in;
  const auto n = static_cast<std::size_t>(k_duration_s / k_dt_s);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * k_dt_s;
    in.t_s.push_back(t);
    in.v_V.push_back(6.0 + 5.0 * std::sin(2.0 * 3.141592653589793 * 2.0 * t));
    in.clutch.push_back(2);
    in.r_load_ohm.push_back(std::fmod(t, 1.4) < 0.7 ? 5.6 : mcg::model::k_open_circuit);
  }
  return in;
}

void BM_ClosedLoopPi60s(benchmark::State& state) {
  const auto in = pi_program();
  const mcg::model::Model model;
  for (auto _ : state) {
    auto out = mcg::sim::simulate_closed_loop(model, mcg::sim::equation_loop_controller(mcg::sim::report_pi()), in, {});
    benchmark::DoNotOptimize(out.plant.omega_rad_s.back());
  }
  state.counters["realtime_x"] = benchmark::Counter(k_duration_s * static_cast<double>(state.iterations()),
                                                    benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ClosedLoopPi60s)->Unit(benchmark::kMillisecond);

/// The same program on the board's firmware core (mcg-sim's default), commands as whole rpm in
/// the board's 120..720.
void BM_ClosedLoopPiBoard60s(benchmark::State& state) {
  auto in = pi_program();
  for (double& r : in.rpm_cmd) r = std::round(120.0 + (r - 100.0) * 600.0 / 1400.0);
  const mcg::model::Model model;
  const mcg::sim::Controller pi = mcg::sim::report_pi();
  const auto registers = *mcg::boardunits::board_fixed_point(pi.b, pi.a, pi.units());
  for (auto _ : state) {
    auto out = mcg::sim::simulate_closed_loop(model, mcg::sim::board_loop_controller(registers), in, {});
    benchmark::DoNotOptimize(out.plant.omega_rad_s.back());
  }
  state.counters["realtime_x"] = benchmark::Counter(k_duration_s * static_cast<double>(state.iterations()),
                                                    benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ClosedLoopPiBoard60s)->Unit(benchmark::kMillisecond);

void BM_OpenLoop60s(benchmark::State& state) {
  const auto in = open_program();
  const mcg::model::Model model;
  for (auto _ : state) {
    auto out = mcg::model::simulate(model, in, {});
    benchmark::DoNotOptimize(out.omega_rad_s.back());
  }
  state.counters["realtime_x"] = benchmark::Counter(k_duration_s * static_cast<double>(state.iterations()),
                                                    benchmark::Counter::kIsRate);
}
BENCHMARK(BM_OpenLoop60s)->Unit(benchmark::kMillisecond);

/// The plant as a fit runs it (the circuits' step bound kept) behind a dead time of 3.3 ms, not
/// a whole number of rows: every row is integrated as steps of two lengths in turn.
void BM_OpenLoopDeadTime60s(benchmark::State& state) {
  const auto in = open_program();
  mcg::model::Model model;
  model.params.dead_time_s = 3.3e-3;
  for (auto _ : state) {
    auto out = mcg::model::simulate(model, in, {});
    benchmark::DoNotOptimize(out.omega_rad_s.back());
  }
  state.counters["realtime_x"] =
      benchmark::Counter(k_duration_s * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_OpenLoopDeadTime60s)->Unit(benchmark::kMillisecond);

/// The accuracy the speed is bought at: rpm RMS change when the step is halved, open loop
/// (in a closed loop the encoder's quantisation turns any tiny difference into a different
/// count sequence, so the comparison there measures the loop's sensitivity, not the integrator).
void print_accuracy() {
  const auto in = open_program();
  const mcg::model::SimOptions coarse;
  mcg::model::SimOptions fine;
  fine.max_step_s = 0.25 * 4.1e-3 / 3.91;
  const auto a = mcg::model::simulate(mcg::model::Model{}, in, coarse);
  const auto b = mcg::model::simulate(mcg::model::Model{}, in, fine);
  double s = 0.0;
  for (std::size_t k = 0; k < a.rpm.size(); ++k) s += (a.rpm[k] - b.rpm[k]) * (a.rpm[k] - b.rpm[k]);
  std::printf("open loop 60 s, default step vs half of it: rpm RMS difference %.2e rpm\n",
              std::sqrt(s / static_cast<double>(a.rpm.size())));
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  print_accuracy();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
