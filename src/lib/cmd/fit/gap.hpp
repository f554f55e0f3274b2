// mcg-fit gap: where the model misses the runs, which effect explains it, how far it shrinks.
#pragma once

#include <string>

#include "cmd/command.hpp"
#include "fit/gap.hpp"

namespace mcg::cmd {

/// fit::run_gap on the options of the command line; its progress lines carry the subcommand's
/// name ("<tool> gap: ..."). Exit status 0, or fit::k_gap_partial_exit when the budget ran out.
class FitGap final : public Command {
 public:
  fit::GapOptions options;
  std::string name() const override { return "gap"; }
  std::string help() const override {
    return "where the model misses the runs, which effect explains it, how far it shrinks";
  }
  void define(CLI::App& app) override;
  int run(Io& io) override;

 private:
  CLI::Option* m_split = nullptr;
};

}  // namespace mcg::cmd
