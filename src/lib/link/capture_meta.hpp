// What a capture (mcg-serial stream, dump) states besides its rows: the rig it ran on and the
// board's configuration, so that the model reads the file unedited (mcg-csv(5)).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "boardunits/chain.hpp"  // k_board_encoder_text

namespace mcg::table {
class Writer;
class Metadata;
}

namespace mcg::link {

struct Connection;
struct LinkOptions;
struct StreamRow;

/// The encoder behind every count the board reports (mcg-csv(5) `encoder`).
inline constexpr const char* k_encoder_text = boardunits::k_board_encoder_text;

/// Where the board's outputs go: the H-bridge supply (duty -> v) and the load relay's resistor.
struct RigOptions {
  std::vector<std::string> configs;         ///< --config: the rig's INI (as mcg-sim's; supply_V)
  double r_load_ohm = boardunits::k_load_resistor_ohm;  ///< --r-load: the relay's resistor, ohm
};

struct Rig {
  double supply_V;
  double r_load_ohm;
  std::string supply_source;  ///< the INI files it came from, or "model default"
};

/// Reads the rig's INI files (model::model_from_ini; defaults without any).
Rig load_rig(const RigOptions& options);

/// The registers that decide what the board does with its inputs, as NAME=value pairs in
/// engineering units (mode, rpm_cmd, clutch, load, the controller's coefficients and limits).
std::vector<std::pair<std::string, std::string>> board_config(Connection& c);
/// The registers board_config reads, in its order.
std::span<const std::string_view> config_register_names();

/// What a capture's `# board_config` says the board ran: its mode, and the raw values of its
/// other registers but those each row carries (rpm_cmd, clutch, load), as the firmware core
/// takes them: those that shape the controller's output (coef_frac, kp, b0..b2, duty limits).
struct CapturedBoard {
  std::int16_t mode = 0;  ///< MCG_MODE_*
  std::string mode_name;  ///< "open", "p", "pi", "pid"
  std::vector<std::pair<std::uint8_t, std::int16_t>> registers;  ///< register id, raw value
  std::string text;       ///< the board_config line as the capture states it
};

/// Reads `# board_config` (written by write_rig_meta); nullopt when the metadata has none.
/// Throws mcg::Error "<source>:<line>: board_config: ..." for a pair that is not NAME=value of
/// one of the registers write_rig_meta writes, a register given twice, a value outside its
/// register or limits the firmware would refuse (duty_min above duty_max): every board it
/// returns, the firmware core takes.
std::optional<CapturedBoard> captured_board(const table::Metadata& meta, std::string_view source);

/// `# supply_V`, `# r_load_relay_ohm` and `# board_config` metadata lines.
void write_rig_meta(table::Writer& w, const Rig& rig,
                    const std::vector<std::pair<std::string, std::string>>& config);

/// The metadata and header of a stream capture (mcg-serial stream, the console's recording):
/// source, board, port, sample period, the rpm estimator of `window_samples` samples, the
/// encoder, timing, the rig; columns t, rpm, counts, duty, v, rpm_cmd, clutch, r_load.
void write_stream_header(table::Writer& w, const Connection& c, const LinkOptions& link, int window_samples,
                         const Rig& rig, const std::vector<std::pair<std::string, std::string>>& config);
/// One row of a stream capture: v = duty supply_V, r_load the relay's resistor when closed.
void write_stream_row(table::Writer& w, const StreamRow& r, const Rig& rig);

}  // namespace mcg::link
