// The board's `# excitation:` line: what the board played from the capture's t = 0 (mcg-serial
// stream --then excite writes it, mcg-sweep bode and mcg-fit tf read it), per mcg-csv(5):
//   <kind> column=<duty|rpm_cmd> <key>=<value> ... amp=<a> bias=<b> periods=<n>
// kind prbs (order, clock s), staircase (steps, hold s) or chirp (f0 Hz, f1 Hz, sweep s, update s);
// levels in the column's unit (duty as a fraction of full scale, rpm_cmd in rpm). The generator
// lines mcg-sweep writes (no `column=`) are not this form.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace mcg::measurement {

struct BoardExcitation {
  std::string kind;                                    ///< prbs, staircase, chirp
  std::string column;                                  ///< the column the board drove: duty or rpm_cmd
  std::vector<std::pair<std::string, double>> values;  ///< the other key=value pairs, in order

  /// The value of `key`, if the line has it.
  std::optional<double> value(std::string_view key) const;
};

/// The metadata text of `excitation`, in the form parse_board_excitation() reads.
std::string format_board_excitation(const BoardExcitation& excitation);
/// The board's excitation in `text`, or nullopt when the text is not of its form (no `column=`,
/// as mcg-sweep's own generator lines). Throws mcg::Error "<where>: ..." for a line of the form
/// with a value that is not a number.
std::optional<BoardExcitation> parse_board_excitation(std::string_view text, std::string_view where);

}  // namespace mcg::measurement
