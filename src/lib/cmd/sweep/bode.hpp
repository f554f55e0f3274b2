// mcg-sweep bode: the frequency response between two columns of a measured table.
#pragma once

#include <string>

#include "cmd/command.hpp"
#include "signal/sweep.hpp"

namespace mcg::cmd {

/// Writes f_hz, mag_db, phase_deg, coherence (signal::bode); the leading rows skipped are a note
/// and uneven sampling, resampled, a warning on io.diag.
class SweepBode final : public Command {
 public:
  signal::BodeOptions options;
  std::string name() const override { return "bode"; }
  std::string help() const override { return "frequency response f_hz,mag_db,phase_deg,coherence"; }
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

}  // namespace mcg::cmd
