// The analysis subcommands of mcg-design: margins (INI), bode, nyquist, rlocus and step (CSV,
// or step's metrics as INI), each of the loop of the plant and the controller to analyse.
#pragma once

#include <cmath>
#include <string>

#include "cmd/design/plant_command.hpp"

namespace mcg::cmd {

/// Options of `mcg-design margins`.
struct MarginsOptions {
  design::PlantOptions plant;
  std::string controller;  ///< text in s or z; empty: [controller] of --config, or 1
};

class Margins final : public PlantCommand {
 public:
  MarginsOptions options;
  Margins()
      : PlantCommand("margins",
                     "all crossovers, gain/phase/delay margins, Ms, closed-loop poles, stable gains (INI)") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// Options of `mcg-design bode` and `nyquist`.
struct BodeOptions {
  design::PlantOptions plant;
  std::string controller;
  double f_min_hz = NAN;
  double f_max_hz = NAN;
  int points = 0;  ///< 0: 500
};

/// bode (f_hz, mag_db, phase_deg) or, `nyquist`, the Nyquist plot (f_hz, re, im).
class Bode final : public PlantCommand {
 public:
  BodeOptions options;
  explicit Bode(bool nyquist)
      : PlantCommand(nyquist ? "nyquist" : "bode", nyquist
                                                       ? "Nyquist plot: f_hz, re, im (CSV)"
                                                       : "frequency response: f_hz, mag_db, phase_deg (CSV)"),
        m_nyquist(nyquist) {}
  void define(CLI::App& app) override;
  int run(Io& io) override;

 private:
  bool m_nyquist;
};

/// Options of `mcg-design rlocus`.
struct RlocusOptions {
  design::PlantOptions plant;
  std::string controller;
  double k_max = NAN;  ///< NaN: 3 times the largest boundary gain, or 100
  int points = 0;      ///< 0: 400
};

class Rlocus final : public PlantCommand {
 public:
  RlocusOptions options;
  Rlocus() : PlantCommand("rlocus", "root locus of 1 + K L: k, branch, re, im (CSV)") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// Options of `mcg-design step`.
struct StepOptions {
  design::PlantOptions plant;
  std::string controller;
  bool open_loop = false;     ///< the series C·G as typed, no feedback
  std::string rise_pct;       ///< "LOW,HIGH" rise-time limits, % of the final value
  double settling_pct = NAN;  ///< settling band, % (2)
  double t_end_s = NAN;       ///< NaN: 10 time constants of the slowest pole
  int points = 0;             ///< samples of a continuous loop; 0: 2000
  bool metrics = false;       ///< the metrics as INI instead of the series
};

class Step final : public PlantCommand {
 public:
  StepOptions options;
  Step()
      : PlantCommand(
            "step",
            "unit step, closed loop (t, r, y, e, u) or open (t, r, y, u): CSV with stepinfo metrics") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

}  // namespace mcg::cmd
