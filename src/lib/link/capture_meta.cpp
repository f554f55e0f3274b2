// Capture metadata: the rig and the board's configuration.
#include "link/capture_meta.hpp"

#include <fmt/format.h>

#include <array>
#include <sstream>

#include "common/error.hpp"
#include "common/quote.hpp"
#include "config/ini.hpp"       // Ini, format_number
#include "link/connection.hpp"  // Connection
#include "link/registers.hpp"
#include "mcg_protocol.h"       // MCG_REG_*
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

namespace {

/// The registers a capture's board_config states: the mode, those a capture's rows also carry,
/// and those that shape the controller's output.
constexpr std::array<const char*, 12> k_config_registers{"mode",      "rpm_cmd",   "clutch",   "load",
                                                         "coef_frac", "kp",        "b0",       "b1",
                                                         "b2",        "duty_bias", "duty_min", "duty_max"};

/// The registers whose value each row of a capture carries (its rpm_cmd, clutch, r_load).
bool carried_by_rows(std::string_view name) { return name == "rpm_cmd" || name == "clutch" || name == "load"; }

}  // namespace

std::vector<std::pair<std::string, std::string>> board_config(Connection& c) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const char* name : k_config_registers) {
    const RegisterInfo& reg = require_register(name);
    const int frac = reg.unit == Unit::Gain ? c.frac_bits() : 0;
    out.emplace_back(name, format_value(reg, c.session->read(reg), frac));
  }
  return out;
}

std::optional<CapturedBoard> captured_board(const table::Metadata& meta, std::string_view where) {
  const std::optional<std::string> text = meta.get("board_config");
  if (!text) return std::nullopt;
  CapturedBoard board;
  board.text = *text;
  std::vector<std::pair<const RegisterInfo*, std::string>> pairs;
  std::istringstream words(*text);
  for (std::string word; words >> word;) {
    const auto eq = word.find('=');
    const RegisterInfo* reg = eq == std::string::npos ? nullptr : find_register(std::string_view(word).substr(0, eq));
    if (reg == nullptr) fail("{}: board_config: {} is not NAME=value of a register", where, quote(word));
    pairs.emplace_back(reg, word.substr(eq + 1));
  }
  const std::string at = fmt::format("{}: board_config", where);
  const auto value_of = [&](const RegisterInfo& reg, const std::string& value, int frac) {
    const double v = parse_value(reg, value, at);
    try {
      return to_raw(reg, v, frac);
    } catch (const Error& e) {
      fail("{}: {}", at, e.what());
    }
  };
  // The gains are in units of 2^-coef_frac: coef_frac first.
  int frac = require_register("coef_frac").raw_default;
  bool has_mode = false;
  for (const auto& [reg, value] : pairs) {
    if (reg->name == "coef_frac") frac = value_of(*reg, value, 0);
  }
  for (const auto& [reg, value] : pairs) {
    const std::int16_t raw = value_of(*reg, value, reg->unit == Unit::Gain ? frac : 0);
    if (reg->id == MCG_REG_MODE) {
      board.mode = raw;
      board.mode_name = value;
      has_mode = true;
    } else if (!carried_by_rows(reg->name)) {
      board.registers.emplace_back(reg->id, raw);
    }
  }
  if (!has_mode) fail("{}: board_config: no mode (the capture does not say what the board ran)", where);
  return board;
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
