// The services of mcg-design's commands (src/lib/cmd/design): the plant resolved from the
// options every subcommand shares and the INI files, the controller to analyse, and the
// writers of a design and of margins.
#pragma once

#include <cmath>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "boardunits/chain.hpp"
#include "boardunits/plant_units.hpp"
#include "config/ini.hpp"
#include "design/design.hpp"

namespace mcg::design {

/// The plant and chain options of every subcommand; NaN (or empty) means "not given".
struct PlantOptions {
  std::vector<std::string> configs;

  // The plant: text, coefficient lists, or the INI's [plant]; the report's loop by default.
  std::string plant;
  bool plant_given = false;  ///< --plant was on the command line (even if empty)
  std::string num;
  std::string den;
  std::string domain;  ///< for --num/--den: "s" (default) or "z"
  std::string plant_units;  ///< what --plant maps (rpm/V, ..., loop): boardunits/plant_units.hpp
  double delay_s = NAN;
  double dt_s = NAN;
  std::string method;  ///< controller discretisation (tustin), c2d's method (zoh)
  double prewarp_rad_s = NAN;
  bool zoh = false;   ///< sample the continuous plant through a zero-order hold at dt
  bool loop = false;  ///< wrap the plant in the chain of the report's Figure 17-1

  // The rig model (model INI sections of --config) linearised at an operating point.
  bool rig = false;
  int clutch = -1;          ///< 0, 1, 2; -1: [plant] clutch or 2
  double speed_rpm = NAN;
  double r_load_ohm = NAN;  ///< NaN: [plant] r_load_ohm or open (inf)

  // The chain (PWM, H-bridge, encoder, software conversion).
  double pwm_full_counts = NAN;
  double pwm_logic_v = NAN;
  double hbridge_gain = NAN;
  double counts_per_rev = NAN;
};

/// The plant as the commands design on and analyse it.
struct ResolvedPlant {
  config::Ini ini;
  Tf raw;  ///< the plant as given
  std::string raw_where;
  bool chain = false;
  boardunits::PlantUnits units;  ///< what raw maps; physical units get the chain (converted to rad/s per V)
  boardunits::LoopChain chain_values;
  bool hold = false;  ///< the continuous plant is sampled through a ZOH (the PWM)
  double dt_s = 0.0;  ///< controller sample period, 0 = continuous
  Setup setup;
};

/// The numbers of a coefficient list typed as `text` ("1 2" or "1,2"); errors name `where`.
std::vector<double> parse_list(const std::string& text, const std::string& where);

/// The plant of `o` and its INI files (the built-in report's loop when none is given), with its
/// chain, hold, sample period and design setup. `designs`: for a design command, which refuses a
/// hand-typed plant of unstated units when the controller is sampled. Bad input throws
/// mcg::Error naming the option or file and line.
ResolvedPlant resolve(const PlantOptions& o, bool designs);

/// The controller an analysis command analyses, as it runs: `controller` text (--controller),
/// else [controller] b/a of the INI files, else none.
std::optional<Tf> analysis_controller(const std::string& controller, const ResolvedPlant& r);
/// The loop's factors: the controller (when there is one) and the plant.
std::vector<Tf> analysis_factors(const std::string& controller, const ResolvedPlant& r);

/// One Tf for the loop's product; a mixed loop (z controller, s plant) samples the plant
/// through a ZOH, which `note` records.
Tf single_loop(const std::vector<Tf>& factors, std::string* note);

/// The margins of the loop `factors` as INI `section` (stability, PM, GM, DM, Ms, every
/// crossover, closed-loop poles, stable gains).
void write_margins(config::Ini& ini, const std::string& section, const std::vector<Tf>& factors, double dt_s);

/// A design as INI: [design], [margins], and with a sample period [controller], [fixed_point]
/// and [margins_quantised] when the board can hold it, then the plant and chain. `rl`: the
/// closed-loop poles of a root-locus design; `limits`: those of a robust tuning.
void write_design(const ResolvedPlant& r, const Design& d, std::ostream& out,
                  const std::optional<RlocusResult>& rl = std::nullopt, const TuneLimits* limits = nullptr);

}  // namespace mcg::design
