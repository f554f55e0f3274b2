// Test fixtures: model inputs the unit tests build again and again.
#pragma once

#include <cmath>
#include <cstddef>

#include "model/model.hpp"

namespace mcg::test {

/// Inputs held constant: rows at t = k dt_s for k = 0 .. round(duration_s / dt_s), each with the
/// voltage v_V, the clutch state and the load resistor.
inline model::Inputs constant_inputs(double v_V, double duration_s, double dt_s = 1e-3, int clutch = 0,
                                     double r_load_ohm = model::k_open_circuit) {
  model::Inputs in;
  const auto n = static_cast<std::size_t>(std::llround(duration_s / dt_s)) + 1;
  for (std::size_t k = 0; k < n; ++k) {
    in.t_s.push_back(static_cast<double>(k) * dt_s);
    in.v_V.push_back(v_V);
    in.clutch.push_back(clutch);
    in.r_load_ohm.push_back(r_load_ohm);
  }
  return in;
}

}  // namespace mcg::test
