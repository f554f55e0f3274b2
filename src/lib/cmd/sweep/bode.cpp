// mcg-sweep bode: its options and signal::bode on them.
#include "cmd/sweep/bode.hpp"

#include <map>

namespace mcg::cmd {

void SweepBode::define(CLI::App& app) {
  signal::BodeOptions& bode = options;
  app.add_option("file", bode.input, "input table (- = stdin)")->capture_default_str();
  app.add_option("--in", bode.in_column, "input column (default: the excitation line's column, else v)");
  app.add_option("--out", bode.out_column, "output column (default: omega, else rpm)");
  app.add_option("--method", bode.method, "auto (lines when the table is a multisine), welch or lines")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, signal::BodeMethod>{{"auto", signal::BodeMethod::automatic},
                                                    {"welch", signal::BodeMethod::welch},
                                                    {"lines", signal::BodeMethod::lines}}));
  app.add_option("--segment", bode.segment, "Welch segment, samples (default: a power of two near n/8)")
      ->check(CLI::Range(std::size_t{16}, std::size_t{1} << 24));
  app.add_option("--overlap", bode.overlap, "Welch segment overlap, fraction")
      ->check(CLI::Range(0.0, 0.95))
      ->capture_default_str();
  app.add_option("--lines", bode.lines_hz, "multisine lines, Hz, e.g. 1,2,5 (default from metadata)");
  app.add_option("--period", bode.period_s, "multisine period, s (default from metadata)")
      ->check(CLI::Range(1e-6, 1e6));
  app.add_option("--f-min,--fmin", bode.f_min_hz, "lowest frequency written, Hz (default: excitation band)")
      ->check(CLI::Range(0.0, 1e9));
  app.add_option("--f-max,--fmax", bode.f_max_hz, "highest frequency written, Hz (default: excitation band)")
      ->check(CLI::Range(0.0, 1e9));
}

int SweepBode::run(Io& io) {
  options.tool = io.tool;
  signal::bode(options, io.out, io.diag);
  return 0;
}

}  // namespace mcg::cmd
