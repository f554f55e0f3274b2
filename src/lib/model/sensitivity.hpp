// Sensitivities of a simulation to the model's parameters by forward-mode automatic
// differentiation along it: the plant runs once on dual numbers (model/dual.hpp) carrying up
// to k_dual_dirs directions, instead of once more per parameter as finite differences do.
//
// Every number the effects compile from the parameters (model/effects/compiled.hpp) is lifted
// to a dual whose derivatives are the compile's own central differences: compiling is a few
// multiplications, so those are exact to rounding, while everything downstream (the circuits'
// exponential steps, friction, stick-slip events whose times move with the parameters, a dead
// time's delayed commands) is differentiated exactly along the simulation.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "model/model.hpp"

namespace mcg::model {

/// One direction to differentiate along: the model moved by +step and -step along it (a
/// parameter and whatever is tied to it), step > 0.
struct Direction {
  Model plus;
  Model minus;
  double step = 0.0;
};

/// The directions of the named parameters (get_parameter/set_parameter names) about `model`,
/// each moved by a relative 1e-6 (1e-9 in its own units at 0).
std::vector<Direction> parameter_directions(const Model& model, const std::vector<std::string>& names);

/// A simulation's outputs and their derivatives: d[j] holds d(output)/d(direction j) for every
/// output and row (rpm per unit of the direction for rpm, and so on).
struct Sensitivities {
  Outputs value;
  std::vector<Outputs> d;
};

/// Simulates as simulate() does, with the derivatives along `directions`; nullopt when the model
/// cannot be differentiated this way: a term without dual functions (a discrepancy term's), or
/// a direction that changes the model's structure (a term appears, a hook changes).
std::optional<Sensitivities> simulate_sensitivities(const Model& model,
                                                    const std::vector<Direction>& directions,
                                                    const Inputs& inputs, const SimOptions& options = {});

}  // namespace mcg::model
