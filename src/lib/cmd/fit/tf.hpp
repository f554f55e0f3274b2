// mcg-fit tf: a rational transfer function fitted to a frequency response or a time-domain run.
#pragma once

#include <string>

#include "cmd/command.hpp"
#include "fit/tf.hpp"

namespace mcg::cmd {

/// Options of `mcg-fit tf`.
struct FitTfOptions {
  std::string file = "-";
  /// What the response maps (`v -> rpm`, `rpm/V`, ...) when its metadata does not say; given
  /// with metadata, the two must agree.
  std::string units;
  fit::TfFitOptions fit;
  /// A time-domain run (a table with t and no f_hz): its input and output columns (empty: v,
  /// and rpm or else omega) and a held-out run scored with the fit (empty: none).
  std::string in_column;
  std::string out_column;
  std::string validate;
  bool band_given = false;  ///< --f-min, --f-max or --no-coherence was given (frequency data only)
};

/// Writes [plant] (tf in the syntax mcg-design reads, num/den in descending powers of s,
/// domain = s, maps = the response's units, delay_s when a delay was fitted) and [fit.tf] (gain,
/// corners and dampings with standard errors, RMS errors). Without --delay, a fit that leaves
/// more than 5 degrees of phase RMS is refitted with a delay and with one more pole; if either
/// halves the phase residual, a warning names the command that fits better (sampled data lag: a
/// zero-order hold alone by half a sample period, a speed from counts over one period by another
/// half). A time-domain run (t, no f_hz) is fitted by fit_tf_time instead: [plant] as above,
/// maps = "IN -> OUT" of the columns, and in [fit.tf] the operating point, fit %, RMS and the
/// held-out run's fit %; the leading rows skipped are noted.
class FitTf final : public Command {
 public:
  FitTfOptions options;
  std::string name() const override { return "tf"; }
  std::string help() const override {
    return "rational transfer function fitted to a frequency response or to a time-domain run (output error)";
  }
  void define(CLI::App& app) override;
  int run(Io& io) override;

 private:
  CLI::App* m_app = nullptr;
};

}  // namespace mcg::cmd
