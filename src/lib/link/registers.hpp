// The board's registers by name, with their engineering units and the protocol's scales.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "mcg_protocol.h"  // MCG_UNIT_*, MCG_REGISTERS

namespace mcg::link {

/// How a register's raw i16 maps to the value a user types and reads (the unit column of
/// MCG_REGISTERS in mcg_protocol.h).
enum class Unit : std::uint8_t {
  Mode = MCG_UNIT_MODE,         ///< MCG_MODE_*: open, p, pi, pid (or 0..3)
  SeqState = MCG_UNIT_SEQ,      ///< MCG_SEQ_*: stop, play, loop (or 0..2)
  Rpm = MCG_UNIT_RPM,           ///< rev/min, raw = value
  Percent = MCG_UNIT_PERMILLE,  ///< duty in %, raw = 10 x value (the board counts 1/1000 of full scale)
  Gain = MCG_UNIT_GAIN,       ///< coefficient, raw = value x 2^F (F = coef_frac): 1/1000 duty per (pulse/ms)
  Bits = MCG_UNIT_BITS,       ///< fractional bits, raw = value
  Ms = MCG_UNIT_MS,           ///< milliseconds, raw = value
  Count = MCG_UNIT_COUNT,     ///< a count, raw = value (counters read as unsigned 16 bit)
  Switch = MCG_UNIT_SWITCH,   ///< 0/1 (also off/on)
  Flags = MCG_UNIT_FLAGS,     ///< MCG_FLAG_* bits, read only
  Clutch = MCG_UNIT_CLUTCH,   ///< mcg-csv clutch state: 1 attached and disengaged, 2 engaged (also names)
  Excitation = MCG_UNIT_EXC,  ///< MCG_EXC_*: none, prbs, staircase, chirp (or 0..3)
  Level = MCG_UNIT_LEVEL,     ///< the excitation's target, raw = value: 1/1000 duty (open loop) or rpm

  Hz = MCG_UNIT_CHZ,     ///< frequency in Hz, raw = 100 x value
  Seconds = MCG_UNIT_S,  ///< seconds, raw = value
};

struct RegisterInfo {
  std::string_view name;
  std::uint8_t id;
  Unit unit;
  bool writable;
  std::int32_t raw_min;  ///< the range the board accepts (static part; the board checks the rest)
  std::int32_t raw_max;
  std::int16_t raw_default;  ///< the board's power-on value
  std::string_view doc;  ///< unit and meaning, one line
  /// One of the controller's set (MCG_RS): a write goes to the board's shadow set and acts only
  /// when the commit register is written; a read shows the active set.
  bool staged = false;
  /// Stated in a capture's board_config metadata (MCG_CAP_STATE or MCG_CAP_ROW).
  bool captured = false;
  /// Each row of a capture carries its value too (MCG_CAP_ROW: rpm_cmd, clutch, load).
  bool carried_by_rows = false;
};

/// Every register of the protocol, in id order (MCG_REGISTERS expanded).
std::span<const RegisterInfo> registers();
/// The register called `name` (case-insensitive; '-' may stand for '_'), or nullptr.
const RegisterInfo* find_register(std::string_view name);
/// The register with protocol id `id`, or nullptr.
const RegisterInfo* find_register(std::uint8_t id);
/// find_register(name) that throws "unknown register 'x' (registers: mode, rpm_cmd, ...)".
const RegisterInfo& require_register(std::string_view name);

/// Unit text for messages and listings: "rpm", "%", "ms", ...
std::string_view unit_suffix(Unit unit);
/// Engineering value of a raw register value: rpm and ms as is, duty % = raw / 10,
/// gain = raw / 2^frac_bits, counters as unsigned 16 bit.
double to_engineering(const RegisterInfo& reg, std::int16_t raw, int frac_bits);
/// The raw value nearest to `value` (rounded half away from zero). Throws mcg::Error
/// "<reg>: <value> <unit> is outside <min>..<max>" when it falls outside the register's range.
std::int16_t to_raw(const RegisterInfo& reg, double value, int frac_bits);
/// Parses the text a user typed for `reg` (a number, or a name for mode, seq_state and
/// switches) into its engineering value. Throws mcg::Error naming `where`.
double parse_value(const RegisterInfo& reg, std::string_view text, std::string_view where);
/// Shortest exact text of a raw value in engineering units ("420", "35.5", "0.75", "pi",
/// "saturated,logging").
std::string format_value(const RegisterInfo& reg, std::int16_t raw, int frac_bits);

/// Text of a protocol status code ("value outside the register's range", ...).
std::string_view status_text(std::uint8_t status);
/// The protocol's name of a status code ("RANGE", "NO_GAINS", ...), as mcg-protocol(7) lists it.
std::string_view status_name(std::uint8_t status);

}  // namespace mcg::link
