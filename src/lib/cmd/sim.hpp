// mcg-sim: the rig simulated on a table of inputs, the effect catalog, or the emulated board.
#pragma once

#include <string>

#include "board/board.hpp"
#include "cmd/command.hpp"
#include "sim/run.hpp"

namespace mcg::cmd {

/// sim::run on stdin and stdout (live); instead, with --list-effects, the effect catalog, or
/// with --board, board::serve on the model of --config and --effect.
class Sim final : public Command {
 public:
  sim::RunOptions options;
  board::ServeOptions board;
  bool list_effects = false;
  std::string name() const override { return "sim"; }
  std::string help() const override { return "the rig simulated on a table of inputs"; }
  void define(CLI::App& app) override;
  int run(Io& io) override;

 private:
  CLI::App* m_app = nullptr;
};

}  // namespace mcg::cmd
