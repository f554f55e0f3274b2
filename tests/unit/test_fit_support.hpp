// Test data for the fit tests: runs simulated in-process and measured like the rig measures
// them (encoder counts over a 5 ms window at 2048 counts/rev; the current through a 1 ohm
// shunt into a 10-bit ADC over -2.5..2.495 A with 3 mA Gaussian noise; seeded).
#pragma once

#include "model/model.hpp"
#include "sim/encoder.hpp"
#include "table/table.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace mcg::fit::testing {

inline constexpr double k_window_s = 0.005;
inline constexpr double k_counts_per_rev = 2048.0;
inline constexpr double k_adc_lsb_A = 5.0 / 1024.0;

/// Piecewise-constant inputs at 1 kHz built segment by segment.
struct Program {
  model::Inputs inputs;
  double dt_s = 1e-3;

  /// Holds v for `duration_s`.
  Program& hold(double v_V, double duration_s, int clutch, double r_load_ohm = model::k_open_circuit) {
    return ramp(v_V, v_V, duration_s, clutch, r_load_ohm);
  }
  /// Ramps v linearly from v0 to v1 over `duration_s`.
  Program& ramp(double v0_V, double v1_V, double duration_s, int clutch, double r_load_ohm = model::k_open_circuit) {
    const auto rows = static_cast<std::size_t>(std::lround(duration_s / dt_s));
    for (std::size_t k = 0; k < rows; ++k) {
      inputs.t_s.push_back(static_cast<double>(inputs.t_s.size()) * dt_s);
      inputs.v_V.push_back(v0_V + (v1_V - v0_V) * static_cast<double>(k) / static_cast<double>(rows));
      inputs.clutch.push_back(clutch);
      inputs.r_load_ohm.push_back(r_load_ohm);
    }
    return *this;
  }
};

/// Simulates `inputs` under `model` and returns the table a logging run would write:
/// t, v, clutch, r_load, rpm (counts over the trailing 5 ms), i (noisy, ADC-quantised),
/// with the rpm_estimator metadata.
inline table::Table measure(const model::Model& model, const model::Inputs& inputs, std::uint64_t seed,
                            bool with_current = true) {
  const model::Outputs out = model::simulate(model, inputs);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.003);
  table::Table t;
  t.source = "sim.csv";
  t.meta.set("sample_period", "0.001");
  t.meta.set("rpm_estimator", "counts over 0.005 s window, 2048 counts/rev");
  t.meta.set("i_measurement", "1 ohm shunt, 10-bit ADC (range -2.5..2.495 A, saturates), noise sigma 0.003 A");
  const std::size_t n = inputs.t_s.size();
  std::vector<double> rpm(n), current(n);
  const auto lag = static_cast<std::size_t>(std::lround(k_window_s / 1e-3));
  for (std::size_t k = 0; k < n; ++k) {
    const double before = k >= lag ? out.theta_rad[k - lag] : out.theta_rad[0];
    rpm[k] = (sim::encoder_count(out.theta_rad[k], k_counts_per_rev) - sim::encoder_count(before, k_counts_per_rev)) / k_counts_per_rev / k_window_s * 60.0;
    const double code = std::round((out.i_A[k] + noise(rng)) / k_adc_lsb_A);
    current[k] = std::clamp(code, -512.0, 511.0) * k_adc_lsb_A;
  }
  t.set("t", inputs.t_s);
  t.set("v", inputs.v_V);
  t.set("clutch", inputs.clutch);
  t.set("r_load", inputs.r_load_ohm);
  t.set("rpm", rpm);
  if (with_current) t.set("i", current);
  return t;
}

}  // namespace mcg::fit::testing
