// The generator subcommands of mcg-sweep: step, staircase, chirp, multisine, prbs, aprbs. Each
// writes its excitation table (signal::generate) for mcg-sim or the board.
#pragma once

#include <string>

#include "cmd/command.hpp"
#include "signal/sweep.hpp"

namespace mcg::cmd {

/// One generator: its options (those every generator shares, then its own) and its table on
/// io.out. Inconsistent options (a band above Nyquist, a schedule out of order) throw mcg::Error.
class SweepGenerate final : public Command {
 public:
  signal::GeneratorOptions options;
  explicit SweepGenerate(signal::Generator generator) : m_generator(generator) {}
  std::string name() const override;
  std::string help() const override;
  void define(CLI::App& app) override;
  int run(Io& io) override;

 private:
  signal::Generator m_generator;
};

}  // namespace mcg::cmd
