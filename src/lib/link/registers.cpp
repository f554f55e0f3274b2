// Register table and unit conversions.
#include "link/registers.hpp"

#include <fmt/format.h>

#include <array>
#include <charconv>
#include <cmath>
#include <string>

#include "boardunits/fixed_point.hpp"  // k_board_modes
#include "common/checked.hpp"
#include "common/error.hpp"  // mcg::fail
#include "config/ini.hpp"    // format_number
#include "mcg_protocol.h"    // MCG_REG_*, MCG_ST_*

namespace mcg::link {

namespace {

#define MCG_HOST_REGISTER(NAME, name, access, lo, hi, def, unit, capture, keypad, doc)                  \
  RegisterInfo{name, MCG_REG_##NAME,     static_cast<Unit>(unit), (access) != MCG_RO,      lo, hi, def, \
               doc,  (access) == MCG_RS, (capture) != MCG_CAP_NO, (capture) == MCG_CAP_ROW},
constexpr std::array<RegisterInfo, MCG_REG_COUNT - 1> k_registers{{MCG_REGISTERS(MCG_HOST_REGISTER)}};
#undef MCG_HOST_REGISTER

constexpr bool ids_in_table_order() {
  for (std::size_t k = 0; k < k_registers.size(); ++k) {
    if (k_registers[k].id != k + 1 || k_registers[k].name.empty()) return false;
  }
  return true;
}
static_assert(ids_in_table_order(), "MCG_REGISTERS: one row per id 0x01..MCG_REG_COUNT-1, in id order");

constexpr const auto& k_modes = boardunits::k_board_modes;
constexpr std::array<std::string_view, 3> k_seq_states{"stop", "play", "loop"};
constexpr std::array<std::string_view, 4> k_excitations{"none", "prbs", "staircase", "chirp"};
constexpr std::array<std::string_view, 5> k_flags{"saturated", "logging", "log_full", "seq", "seq_set"};

std::string normalise(std::string_view name) {
  std::string out(name);
  for (char& c : out) {
    if (c == '-') c = '_';
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

/// Raw steps per engineering unit: the engineering value is raw / steps, a division, so that
/// duty 157 reads as the double nearest 15.7 (157 * 0.1 is 15.700000000000001).
double steps_per_unit(const RegisterInfo& reg, int frac_bits) {
  switch (reg.unit) {
    case Unit::Percent:
      return 10.0;
    case Unit::Hz:
      return 100.0;
    case Unit::Gain:
      return std::ldexp(1.0, frac_bits);
    default:
      return 1.0;
  }
}

}  // namespace

std::span<const RegisterInfo> registers() { return k_registers; }

const RegisterInfo* find_register(std::string_view name) {
  const std::string key = normalise(name);
  for (const auto& reg : k_registers) {
    if (reg.name == key) return &reg;
  }
  return nullptr;
}

const RegisterInfo* find_register(std::uint8_t id) {
  for (const auto& reg : k_registers) {
    if (reg.id == id) return &reg;
  }
  return nullptr;
}

const RegisterInfo& require_register(std::string_view name) {
  if (const auto* reg = find_register(name)) return *reg;
  std::string names;
  for (const auto& reg : k_registers) names += fmt::format("{}{}", names.empty() ? "" : ", ", reg.name);
  fail("unknown register {} (registers: {})", quote(name), names);
}

std::string_view unit_suffix(Unit unit) {
  switch (unit) {
    case Unit::Rpm:
      return "rpm";
    case Unit::Percent:
      return "%";
    case Unit::Gain:
      return "/1000 per pulse/ms";
    case Unit::Bits:
      return "bits";
    case Unit::Ms:
      return "ms";
    case Unit::Hz:
      return "Hz";
    case Unit::Seconds:
      return "s";
    default:
      return "";
  }
}

double to_engineering(const RegisterInfo& reg, std::int16_t raw, int frac_bits) {
  if (reg.unit == Unit::Count || reg.unit == Unit::Flags) return static_cast<std::uint16_t>(raw);
  return raw / steps_per_unit(reg, frac_bits);
}

std::int16_t to_raw(const RegisterInfo& reg, double value, int frac_bits) {
  const std::optional<std::int32_t> raw =
      to_integer(std::round(value * steps_per_unit(reg, frac_bits)), reg.raw_min, reg.raw_max);
  if (!raw) {
    const double lo = reg.raw_min / steps_per_unit(reg, frac_bits);
    const double hi = reg.raw_max / steps_per_unit(reg, frac_bits);
    const std::string_view unit = unit_suffix(reg.unit);
    fail("{}: {}{}{} is outside {}..{}{}{}", reg.name, config::format_number(value), unit.empty() ? "" : " ",
         unit, config::format_number(lo), config::format_number(hi), unit.empty() ? "" : " ", unit);
  }
  return static_cast<std::int16_t>(*raw);
}

double parse_value(const RegisterInfo& reg, std::string_view text, std::string_view where) {
  const std::string key = normalise(text);
  const auto named = [&](std::span<const std::string_view> names) -> std::optional<double> {
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (names[i] == key) return static_cast<double>(i);
    }
    return std::nullopt;
  };
  std::optional<double> value;
  if (reg.unit == Unit::Mode) value = named(k_modes);
  if (reg.unit == Unit::SeqState) value = named(k_seq_states);
  if (reg.unit == Unit::Excitation) value = named(k_excitations);
  if (reg.unit == Unit::Switch) {
    if (key == "on") value = 1.0;
    if (key == "off") value = 0.0;
  }
  if (reg.unit == Unit::Clutch) {
    if (key == "disengaged") value = MCG_CLUTCH_ATTACHED;
    if (key == "engaged") value = MCG_CLUTCH_ENGAGED;
  }
  if (value) return *value;
  double number = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, number);
  if (text.empty() || ec != std::errc() || ptr != end || !std::isfinite(number)) {
    std::string hint;
    if (reg.unit == Unit::Mode) hint = " (open, p, pi, pid)";
    if (reg.unit == Unit::SeqState) hint = " (stop, play, loop)";
    if (reg.unit == Unit::Excitation) hint = " (none, prbs, staircase, chirp)";
    if (reg.unit == Unit::Switch) hint = " (0, 1, off, on)";
    if (reg.unit == Unit::Clutch) hint = " (1 or disengaged, 2 or engaged)";
    fail("{}: {}: invalid value {}{}", where, reg.name, quote(text), hint);
  }
  if (reg.unit == Unit::Clutch && number == 0.0) {
    fail("{}: clutch 0 (motor alone) is not a state of the board: its clutch is mounted (1 attached and "
         "disengaged, 2 engaged)", where);
  }
  return number;
}

std::string format_value(const RegisterInfo& reg, std::int16_t raw, int frac_bits) {
  const auto index = static_cast<std::size_t>(raw);
  switch (reg.unit) {
    case Unit::Mode:
      return raw >= 0 && index < k_modes.size() ? std::string(k_modes[index]) : std::to_string(raw);
    case Unit::SeqState:
      return raw >= 0 && index < k_seq_states.size() ? std::string(k_seq_states[index]) : std::to_string(raw);
    case Unit::Excitation:
      return raw >= 0 && index < k_excitations.size() ? std::string(k_excitations[index])
                                                      : std::to_string(raw);
    case Unit::Flags: {
      std::string out;
      for (std::size_t bit = 0; bit < k_flags.size(); ++bit) {
        if ((static_cast<unsigned>(raw) >> bit) & 1u)
          out += fmt::format("{}{}", out.empty() ? "" : ",", k_flags[bit]);
      }
      return out.empty() ? "none" : out;
    }
    default:
      return config::format_number(to_engineering(reg, raw, frac_bits));
  }
}

std::string_view status_text(std::uint8_t status) {
  switch (status) {
    case MCG_ST_OK:
      return "ok";
    case MCG_ST_BAD_CRC:
      return "frame damaged (CRC mismatch)";
    case MCG_ST_TOO_LONG:
      return "frame too long";
    case MCG_ST_TIMEOUT:
      return "frame truncated";
    case MCG_ST_OVERRUN:
      return "receive buffer overrun";
    case MCG_ST_BAD_CMD:
      return "unknown command";
    case MCG_ST_BAD_LENGTH:
      return "wrong payload length";
    case MCG_ST_BAD_REG:
      return "unknown register";
    case MCG_ST_READ_ONLY:
      return "register is read-only";
    case MCG_ST_RANGE:
      return "value outside the register's range";
    case MCG_ST_BUSY:
      return "board busy (log recording, dump, sequence playing, or a set another writer staged)";
    case MCG_ST_OWNED:
      return "the controller owns duty in a closed-loop mode; set mode open first";
    case MCG_ST_NO_GAINS:
      return "a closed-loop mode with every gain zero (write its gains first); nothing changed";
    case MCG_ST_LIMITS:
      return "duty_min above duty_max; nothing changed";
    default:
      return "unknown status";
  }
}

std::string_view status_name(std::uint8_t status) {
  static constexpr std::array<std::string_view, MCG_ST_COUNT> k_names{
      "OK",      "BAD_CRC",   "TOO_LONG", "TIMEOUT", "OVERRUN", "BAD_CMD",  "BAD_LENGTH",
      "BAD_REG", "READ_ONLY", "RANGE",    "BUSY",    "OWNED",   "NO_GAINS", "LIMITS"};
  return status < k_names.size() ? k_names[status] : "UNKNOWN";
}

}  // namespace mcg::link
