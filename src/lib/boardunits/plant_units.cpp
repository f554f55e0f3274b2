// Plant units: parsing the spellings, the canonical text, the conversion to rad/s per V.
#include "boardunits/plant_units.hpp"

#include <algorithm>
#include <cctype>

#include "common/demand.hpp"
#include "common/units.hpp"

namespace mcg::boardunits {

namespace {

std::string lower_without_blanks(std::string_view text) {
  std::string out;
  for (char c : text) {
    if (std::isspace(static_cast<unsigned char>(c)) == 0) {
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
  }
  return out;
}

std::optional<PlantInput> input_named(std::string_view name) {
  if (name == "v") return PlantInput::v;
  if (name == "duty") return PlantInput::duty;
  return std::nullopt;
}

std::optional<PlantOutput> output_named(std::string_view name) {
  if (name == "omega" || name == "rad/s") return PlantOutput::omega;
  if (name == "rpm" || name == "rpm_true" || name == "rpm_measured") return PlantOutput::rpm;
  return std::nullopt;
}

}  // namespace

std::optional<PlantUnits> parse_plant_units(std::string_view text) {
  std::string t = lower_without_blanks(text);
  if (t == "loop") return PlantUnits{true, PlantInput::v, PlantOutput::omega};
  std::string in;
  std::string out;
  if (const auto arrow = t.find("->"); arrow != std::string::npos) {
    in = t.substr(0, arrow);
    out = t.substr(arrow + 2);
  } else if (const auto per = t.rfind("per"); per != std::string::npos && per > 0) {
    out = t.substr(0, per);
    in = t.substr(per + 3);
  } else if (const auto slash = t.rfind('/'); slash != std::string::npos && slash > 0) {
    out = t.substr(0, slash);
    in = t.substr(slash + 1);
  } else {
    return std::nullopt;
  }
  const auto i = input_named(in);
  const auto o = output_named(out);
  if (!i || !o) return std::nullopt;
  return PlantUnits{false, *i, *o};
}

std::string units_text(const PlantUnits& units) {
  if (units.loop) return "loop";
  return std::string(units.in == PlantInput::v ? "v" : "duty") + " -> " +
         (units.out == PlantOutput::omega ? "omega" : "rpm");
}

std::string units_words(const PlantUnits& units) {
  if (units.loop) return "encoder counts per sample per duty count";
  return std::string(units.out == PlantOutput::omega ? "rad/s" : "rpm") + " per " +
         (units.in == PlantInput::v ? "V" : "duty (1 = full scale)");
}

double omega_per_v_factor(const PlantUnits& units, const LoopChain& chain) {
  MCG_DEMAND(!units.loop);
  double f = units.out == PlantOutput::rpm ? k_rad_s_per_rpm : 1.0;
  if (units.in == PlantInput::duty) f /= chain.pwm_logic_v * chain.hbridge_gain;
  return f;
}

}  // namespace mcg::boardunits
