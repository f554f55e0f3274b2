// mcg-fit friction: static, Coulomb and viscous friction per clutch state, as INI.
#pragma once

#include <string>
#include <vector>

#include "cmd/command.hpp"
#include "fit/friction.hpp"

namespace mcg::cmd {

/// Options of `mcg-fit friction`.
struct FitFrictionOptions {
  std::vector<std::string> config;  ///< --config files: R, Ke, Kt, J, supply and the base frictions
  std::vector<std::string> files;   ///< runs ("-" = stdin)
  fit::FrictionOptions fit;
  /// The axis is linear (a ball screw, a belt): position in m, speed in m/s, drive force in
  /// N. The results are then forces (N, N s/m, kg) in [fit.friction] only: the rig's model
  /// sections hold rotary parameters.
  bool linear = false;
};

/// Writes the stacked frictions as INI ([motor], [generator], [clutch_disengaged],
/// [clutch_engaged]; each value with its standard error as a comment) and the evidence per
/// clutch state in [fit.friction] (with the inertia and offset when estimated; on a linear
/// axis only [fit.friction], in N, N s/m and kg).
class FitFriction final : public Command {
 public:
  FitFrictionOptions options;
  std::string name() const override { return "friction"; }
  std::string help() const override {
    return "static, Coulomb and viscous friction per clutch state, stacked";
  }
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

}  // namespace mcg::cmd
