// Capture metadata: the rig and the board's configuration.
#include "link/capture_meta.hpp"

#include <fmt/format.h>

#include "config/ini.hpp"       // Ini, format_number
#include "link/connection.hpp"  // Connection
#include "model/model.hpp"      // model_from_ini
#include "table/table.hpp"      // Writer

namespace mcg::link {

Rig load_rig(const RigOptions& options) {
  Rig rig;
  rig.supply_V = model::model_from_ini(config::Ini::load_all(options.configs)).params.supply_V;
  rig.r_load_ohm = options.r_load_ohm;
  rig.supply_source = "model default";
  if (!options.configs.empty()) rig.supply_source = fmt::format("{}", fmt::join(options.configs, ", "));
  return rig;
}

std::vector<std::pair<std::string, std::string>> board_config(Connection& c) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const char* name : {"mode", "rpm_cmd", "clutch", "load", "coef_frac", "kp", "b0", "b1", "b2", "duty_bias",
                           "duty_min", "duty_max"}) {
    const RegisterInfo& reg = require_register(name);
    const int frac = reg.unit == Unit::Gain ? c.frac_bits() : 0;
    out.emplace_back(name, format_value(reg, c.session->read(reg), frac));
  }
  return out;
}

void write_rig_meta(table::Writer& w, const Rig& rig, const std::vector<std::pair<std::string, std::string>>& config) {
  w.meta("supply_V", fmt::format("{} (v = duty * supply_V; from {})", config::format_number(rig.supply_V),
                                 rig.supply_source));
  w.meta("r_load_relay_ohm", fmt::format("{} (r_load when the load relay is closed; inf when open)",
                                         config::format_number(rig.r_load_ohm)));
  std::string text;
  for (const auto& [name, value] : config) text += fmt::format("{}{}={}", text.empty() ? "" : " ", name, value);
  w.meta("board_config", text);
}

}  // namespace mcg::link
