// Register table and unit conversions.
#include "link/registers.hpp"

#include <fmt/format.h>

#include <array>
#include <charconv>
#include <cmath>
#include <string>

#include "common/error.hpp"  // mcg::fail
#include "mcg_protocol.h"    // MCG_REG_*, MCG_ST_*

namespace mcg::link {

namespace {

constexpr std::int32_t k_i16_min = -32768;
constexpr std::int32_t k_i16_max = 32767;

constexpr std::array<RegisterInfo, MCG_REG_COUNT - 1> k_registers{{
    {"mode", MCG_REG_MODE, Unit::Mode, true, 0, MCG_MODE_COUNT - 1, "controller: open, p, pi, pid"},
    {"rpm_cmd", MCG_REG_RPM_CMD, Unit::Rpm, true, 120, 720, "speed command, rpm"},
    {"duty", MCG_REG_DUTY, Unit::Percent, true, -1000, 1000,
     "motor duty, % (read: the output; write: open loop only, within duty_min..duty_max)"},
    {"duty_step", MCG_REG_DUTY_STEP, Unit::Percent, true, 1, 1000, "keypad up/down duty step, %"},
    {"duty_bias", MCG_REG_DUTY_BIAS, Unit::Percent, true, -1000, 1000, "P mode: u = bias + kp e, %"},
    {"kp", MCG_REG_KP, Unit::Gain, true, k_i16_min, k_i16_max, "P gain, 1/1000 duty per pulse/ms"},
    {"b0", MCG_REG_B0, Unit::Gain, true, k_i16_min, k_i16_max,
     "PI/PID: u[n] = u[n-1] + b0 e[n] + b1 e[n-1] + b2 e[n-2], 1/1000 duty per pulse/ms"},
    {"b1", MCG_REG_B1, Unit::Gain, true, k_i16_min, k_i16_max, "PI/PID coefficient of e[n-1]"},
    {"b2", MCG_REG_B2, Unit::Gain, true, k_i16_min, k_i16_max, "PID coefficient of e[n-2]"},
    {"coef_frac", MCG_REG_COEF_FRAC, Unit::Bits, true, 0, MCG_COEF_FRAC_BITS_MAX,
     "fractional bits F of kp, b0, b1, b2"},
    {"duty_min", MCG_REG_DUTY_MIN, Unit::Percent, true, -1000, 1000, "controller output floor, %"},
    {"duty_max", MCG_REG_DUTY_MAX, Unit::Percent, true, -1000, 1000, "controller output ceiling, %"},
    {"service_ms", MCG_REG_SERVICE_MS, Unit::Ms, true, 5, 250, "keypad and duty service period, ms"},
    {"log_interval", MCG_REG_LOG_INTERVAL, Unit::Ms, true, 1, 255, "RAM log point spacing, ms"},
    {"log_count", MCG_REG_LOG_COUNT, Unit::Count, false, 0, MCG_LOG_POINTS, "RAM log points recorded"},
    {"stream", MCG_REG_STREAM, Unit::Switch, true, 0, 1, "stream blocks on"},
    {"clutch", MCG_REG_CLUTCH, Unit::Switch, true, 0, 1, "clutch engaged"},
    {"load", MCG_REG_LOAD, Unit::Switch, true, 0, 1, "generator load relay closed"},
    {"rpm", MCG_REG_RPM, Unit::Rpm, false, k_i16_min, k_i16_max, "measured speed over 16 ms, rpm"},
    {"counts_16ms", MCG_REG_COUNTS_16MS, Unit::Count, false, 0, 65535, "encoder pulses in the last 16 ms"},
    {"seq_len", MCG_REG_SEQ_LEN, Unit::Count, false, 0, MCG_SEQ_MAX, "command sequence entries stored"},
    {"seq_state", MCG_REG_SEQ_STATE, Unit::SeqState, true, 0, 2, "sequence playback: stop, play, loop"},
    {"flags", MCG_REG_FLAGS, Unit::Flags, false, 0, 255, "saturated, logging, log_full, seq"},
    {"rx_errors", MCG_REG_RX_ERRORS, Unit::Count, true, 0, 0, "frames the board dropped; write 0 clears"},
    {"tx_drops", MCG_REG_TX_DROPS, Unit::Count, true, 0, 0, "frames the board could not send; write 0 clears"},
    {"stream_seq", MCG_REG_STREAM_SEQ, Unit::Count, false, 0, 255, "sequence number of the next stream block"},
}};

constexpr std::array<std::string_view, MCG_MODE_COUNT> k_modes{"open", "p", "pi", "pid"};
constexpr std::array<std::string_view, 3> k_seq_states{"stop", "play", "loop"};
constexpr std::array<std::string_view, 4> k_flags{"saturated", "logging", "log_full", "seq"};

std::string normalise(std::string_view name) {
  std::string out(name);
  for (char& c : out) {
    if (c == '-') c = '_';
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

double scale_of(const RegisterInfo& reg, int frac_bits) {
  switch (reg.unit) {
    case Unit::Percent:
      return 0.1;
    case Unit::Gain:
      return std::ldexp(1.0, -frac_bits);
    default:
      return 1.0;
  }
}

std::string shortest(double value) { return fmt::format("{}", value); }

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
  fail("unknown register '{}' (registers: {})", name, names);
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
    default:
      return "";
  }
}

double to_engineering(const RegisterInfo& reg, std::int16_t raw, int frac_bits) {
  if (reg.unit == Unit::Count || reg.unit == Unit::Flags) return static_cast<std::uint16_t>(raw);
  return raw * scale_of(reg, frac_bits);
}

std::int16_t to_raw(const RegisterInfo& reg, double value, int frac_bits) {
  const double scaled = std::round(value / scale_of(reg, frac_bits));
  if (!std::isfinite(value) || scaled < reg.raw_min || scaled > reg.raw_max) {
    const double lo = reg.raw_min * scale_of(reg, frac_bits);
    const double hi = reg.raw_max * scale_of(reg, frac_bits);
    const std::string_view unit = unit_suffix(reg.unit);
    fail("{}: {}{}{} is outside {}..{}{}{}", reg.name, shortest(value), unit.empty() ? "" : " ", unit,
         shortest(lo), shortest(hi), unit.empty() ? "" : " ", unit);
  }
  return static_cast<std::int16_t>(scaled);
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
  if (reg.unit == Unit::Switch) {
    if (key == "on") value = 1.0;
    if (key == "off") value = 0.0;
  }
  if (value) return *value;
  double number = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, number);
  if (text.empty() || ec != std::errc() || ptr != end || !std::isfinite(number)) {
    std::string hint;
    if (reg.unit == Unit::Mode) hint = " (open, p, pi, pid)";
    if (reg.unit == Unit::SeqState) hint = " (stop, play, loop)";
    if (reg.unit == Unit::Switch) hint = " (0, 1, off, on)";
    fail("{}: {}: invalid value '{}'{}", where, reg.name, text, hint);
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
    case Unit::Flags: {
      std::string out;
      for (std::size_t bit = 0; bit < k_flags.size(); ++bit) {
        if ((static_cast<unsigned>(raw) >> bit) & 1u) out += fmt::format("{}{}", out.empty() ? "" : ",", k_flags[bit]);
      }
      return out.empty() ? "none" : out;
    }
    default:
      return shortest(to_engineering(reg, raw, frac_bits));
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
      return "board busy (log recording, dump or sequence playing)";
    default:
      return "unknown status";
  }
}

}  // namespace mcg::link
