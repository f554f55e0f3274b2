// Capture metadata: the rig and the board's configuration.
#include "link/capture_meta.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <sstream>
#include <vector>

#include "common/error.hpp"
#include "common/quote.hpp"
#include "common/tool.hpp"
#include "config/ini.hpp"       // Ini, format_number
#include "link/connection.hpp"  // Connection
#include "link/registers.hpp"
#include "mcg_protocol.h"   // MCG_REG_*
#include "model/load.hpp"   // load_model
#include "table/table.hpp"  // Writer

namespace mcg::link {

Rig load_rig(const RigOptions& options) {
  Rig rig;
  rig.supply_V = model::load_model(options.configs, {}).params.supply_V;
  rig.r_load_ohm = options.r_load_ohm;
  rig.supply_source = "model default";
  std::vector<std::string> names;
  for (const auto& path : options.configs) names.push_back(input_name(path));
  if (!names.empty()) rig.supply_source = fmt::format("{}", fmt::join(names, ", "));
  return rig;
}

namespace {

/// The registers a capture's board_config states, in id order: the protocol table's capture
/// column (the controller's set and mode, and those a capture's rows also carry).
const std::vector<std::string_view>& config_registers() {
  static const std::vector<std::string_view> names = [] {
    std::vector<std::string_view> out;
    for (const RegisterInfo& reg : registers()) {
      if (reg.captured) out.push_back(reg.name);
    }
    return out;
  }();
  return names;
}

}  // namespace

std::span<const std::string_view> config_register_names() { return config_registers(); }

std::vector<std::pair<std::string, std::string>> board_config(Connection& c) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const std::string_view name : config_registers()) {
    const RegisterInfo& reg = require_register(name);
    const int frac = reg.unit == Unit::Gain ? c.frac_bits() : 0;
    out.emplace_back(name, format_value(reg, c.session->read(reg), frac));
  }
  return out;
}

std::optional<CapturedBoard> captured_board(const table::Metadata& meta, std::string_view source) {
  const std::optional<std::string> text = meta.get("board_config");
  if (!text) return std::nullopt;
  const std::string at = fmt::format("{}: board_config", meta.where(source, "board_config"));
  CapturedBoard board;
  board.text = *text;
  // The registers board_config writes and nothing else: another one (stream_seq, a read-only
  // counter; duty, busy outside mode open) is nothing the firmware core could be set to.
  const std::vector<std::string_view>& names = config_registers();
  std::vector<std::optional<std::string>> values(names.size());
  std::istringstream words(*text);
  for (std::string word; words >> word;) {
    const auto eq = word.find('=');
    const RegisterInfo* reg = eq == std::string::npos ? nullptr : find_register(std::string_view(word).substr(0, eq));
    if (reg == nullptr) fail("{}: {} is not NAME=value of a register", at, quote(word));
    const auto it = std::find(names.begin(), names.end(), reg->name);
    if (it == names.end()) {
      fail("{}: {} is not one of the registers a capture states ({})", at, quote(reg->name),
           fmt::join(names, ", "));
    }
    auto& slot = values[static_cast<std::size_t>(it - names.begin())];
    if (slot) fail("{}: {} is given twice", at, quote(reg->name));
    slot = word.substr(eq + 1);
  }
  const auto index_of = [&](std::string_view name) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  const auto value_of = [&](std::string_view name, int frac) -> std::int16_t {
    const RegisterInfo& reg = require_register(name);
    const std::optional<std::string>& given = values[index_of(name)];
    if (!given) return reg.raw_default;
    const double v = parse_value(reg, *given, at);
    try {
      return to_raw(reg, v, frac);
    } catch (const Error& e) {
      fail("{}: {}", at, e.what());
    }
  };
  if (!values[index_of("mode")]) fail("{}: no mode (the capture does not say what the board ran)", at);
  // The gains are in units of 2^-coef_frac: coef_frac first.
  const int frac = value_of("coef_frac", 0);
  board.mode = value_of("mode", 0);
  board.mode_name = format_value(require_register("mode"), board.mode, 0);
  // The firmware checks duty_min <= duty_max at each write: a pair it would refuse is refused
  // here, and the core takes them in id order (the floor first), which from
  // the power-on limits every ordered pair passes.
  const std::int16_t duty_min = value_of("duty_min", 0);
  const std::int16_t duty_max = value_of("duty_max", 0);
  if (duty_min > duty_max) {
    const RegisterInfo& reg = require_register("duty_min");
    fail("{}: duty_min {} % is above duty_max {} %", at, format_value(reg, duty_min, 0),
         format_value(reg, duty_max, 0));
  }
  // The core takes coef_frac before the gains it scales, then the rest in id order.
  if (values[index_of("coef_frac")])
    board.registers.emplace_back(MCG_REG_COEF_FRAC, value_of("coef_frac", 0));
  for (std::size_t i = 0; i < names.size(); ++i) {
    const RegisterInfo& reg = require_register(names[i]);
    if (!values[i] || reg.name == "mode" || reg.name == "coef_frac" || reg.carried_by_rows) continue;
    board.registers.emplace_back(reg.id, value_of(reg.name, reg.unit == Unit::Gain ? frac : 0));
  }
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
