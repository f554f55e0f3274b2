// The design subcommands of mcg-design: p, pi, pid, lead, lag, rlocus-design, tune. Each writes
// its design with design::write_design: [design], [margins], and with a sample period the
// [controller], [fixed_point] and [margins_quantised] the board runs.
#pragma once

#include <cmath>
#include <string>

#include "cmd/design/plant_command.hpp"
#include "design/design.hpp"

namespace mcg::cmd {

/// Options of `mcg-design p`: a P controller for a phase margin.
struct DesignPOptions {
  design::PlantOptions plant;
  double pm_deg = NAN;
};

class DesignP final : public PlantCommand {
 public:
  DesignPOptions options;
  DesignP() : PlantCommand("p", "P controller for a phase margin") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// Options of `mcg-design pi`: a phase margin with a zero or a crossover (one of the two).
struct DesignPiOptions {
  design::PlantOptions plant;
  double pm_deg = NAN;
  double zero_rad_s = NAN;
  double wc_rad_s = NAN;
};

class DesignPi final : public PlantCommand {
 public:
  DesignPiOptions options;
  DesignPi() : PlantCommand("pi", "PI controller for a phase margin with a chosen zero or crossover") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// Options of `mcg-design pid`.
struct DesignPidOptions {
  design::PlantOptions plant;
  double pm_deg = NAN;
  double wc_rad_s = NAN;
  double ti_over_td = 4.0;
  double n = 10.0;                ///< derivative filter: pole at N/Td (form filtered)
  std::string form = "filtered";  ///< "filtered" (C(s) with N, discretised) or "board" (the board's form)
};

class DesignPid final : public PlantCommand {
 public:
  DesignPidOptions options;
  DesignPid() : PlantCommand("pid", "PID with a filtered derivative for a phase margin at a crossover") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// Options of `mcg-design lead`.
struct DesignLeadOptions {
  design::PlantOptions plant;
  double pm_deg = NAN;
  double wc_rad_s = NAN;
};

class DesignLead final : public PlantCommand {
 public:
  DesignLeadOptions options;
  DesignLead() : PlantCommand("lead", "lead compensator for a phase margin at a crossover") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// Options of `mcg-design lag`.
struct DesignLagOptions {
  design::PlantOptions plant;
  double pm_deg = NAN;
  double k_dc = NAN;
  double ratio = 10.0;  ///< zero at wc/ratio
};

class DesignLag final : public PlantCommand {
 public:
  DesignLagOptions options;
  DesignLag() : PlantCommand("lag", "lag compensator for a phase margin with a DC gain") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// Options of `mcg-design rlocus-design`.
struct DesignRlocusOptions {
  design::PlantOptions plant;
  double zeta = NAN;
};

class DesignRlocus final : public PlantCommand {
 public:
  DesignRlocusOptions options;
  DesignRlocus() : PlantCommand("rlocus-design", "gain that puts closed-loop poles on a damping line") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// Options of `mcg-design tune`.
struct DesignTuneOptions {
  design::PlantOptions plant;
  std::string structure = "pi";
  design::TuneLimits limits;
};

class DesignTune final : public PlantCommand {
 public:
  DesignTuneOptions options;
  DesignTune() : PlantCommand("tune", "robust tuning: highest crossover within PM, GM and Ms limits") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

}  // namespace mcg::cmd
