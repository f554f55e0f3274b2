// The plant subcommands of mcg-design: c2d (the plant discretised, INI) and loop (the report's
// Figure 17-1 chain: every gain, the ZOH loop and its margins, INI).
#pragma once

#include "cmd/design/plant_command.hpp"

namespace mcg::cmd {

/// Options of `mcg-design c2d`: the plant's alone (--method is the discretisation, zoh).
struct C2dOptions {
  design::PlantOptions plant;
};

class C2d final : public PlantCommand {
 public:
  C2dOptions options;
  C2d() : PlantCommand("c2d", "discretise the plant: [plant] in z (INI)") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// Options of `mcg-design loop`: the plant's alone, always inside the chain.
struct LoopOptions {
  design::PlantOptions plant;
};

class Loop final : public PlantCommand {
 public:
  LoopOptions options;
  Loop()
      : PlantCommand("loop", "the report's Figure 17-1 chain: every gain, the ZOH loop, its margins (INI)") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

}  // namespace mcg::cmd
