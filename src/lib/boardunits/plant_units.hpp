// What a plant's transfer function maps, input -> output, defined once: a frequency response's
// `# response:` metadata, `[plant] maps` in a fit or a design, and mcg-design's --plant-units.
#pragma once

#include "boardunits/chain.hpp"

#include <optional>
#include <string>
#include <string_view>

namespace mcg::boardunits {

/// The input of a physical plant: the motor voltage v (V) or the PWM duty (a fraction, -1..1,
/// as every table holds it).
enum class PlantInput { v, duty };
/// The output: the shaft speed omega (rad/s) or rpm (rev/min).
enum class PlantOutput { omega, rpm };

/// A plant's units: physical (`v -> rpm`: rpm per V) or the board's loop itself (`loop`:
/// encoder counts per sample per duty count, designed on as it is).
struct PlantUnits {
  bool loop = false;
  PlantInput in = PlantInput::v;
  PlantOutput out = PlantOutput::omega;

  bool operator==(const PlantUnits&) const = default;
};

/// Reads the spellings a user or a file gives: the arrow form of a response's metadata
/// (`v -> rpm`, `duty -> omega`; measured columns `rpm_true`, `rpm_measured` are rpm), the
/// ratio forms (`rpm/V`, `rad/s/V`, `rad/s per V`, `rpm/duty`, `omega/v`) and `loop`. Any other
/// text is not known: nullopt.
std::optional<PlantUnits> parse_plant_units(std::string_view text);

/// The canonical spelling, the arrow form: `v -> omega`, `duty -> rpm`, or `loop`.
std::string units_text(const PlantUnits& units);

/// In words, for comments and messages: `rad/s per V`, `rpm per duty (1 = full scale)`, ...
std::string units_words(const PlantUnits& units);

/// The factor that turns a physical plant in `units` into rad/s per V, the input of the loop
/// chain: rpm -> rad/s is 2 pi/60; duty -> V divides by the chain's full-scale voltage
/// (pwm_logic_v * hbridge_gain = 20 V, the same number the chain's gain uses):
///   G_omega/v(s) = G(s) * (2 pi/60 if rpm) / (V_logic K_hb if duty)
double omega_per_v_factor(const PlantUnits& units, const LoopChain& chain);

}  // namespace mcg::boardunits
