// A faulty line for tests: forwards bytes between a port and a new pseudo-terminal, and
// corrupts, drops and delays them, or cuts the line.
#pragma once

#include <cstdint>
#include <string>

#include "common/diagnostics.hpp"

namespace mcg::link {

struct RelayOptions {
  std::string port;            ///< the board side, opened like a serial port
  int baud = 9600;
  std::string link_path;       ///< the pseudo-terminal to create for the tool
  double corrupt = 0.0;        ///< probability per byte of one flipped bit
  double drop = 0.0;           ///< probability per byte of losing it
  double stall = 0.0;          ///< probability per byte of a pause before it
  double stall_ms = 50.0;      ///< the longest pause (uniform in 0..stall_ms)
  double cut_after_s = 0.0;    ///< close the line this long after the first byte from the
                               ///< board (0: never)
  double seconds = 0.0;        ///< end after this long (0: until a signal or the board goes)
  bool to_board = true;        ///< apply the faults to bytes towards the board, too
  std::uint64_t seed = 1;
};

/// Runs the relay until a signal, `seconds`, the cut, or the board side vanishing. Each
/// direction keeps its byte order: a pause holds back the bytes behind it. Reports one
/// summary line on `diag` at the end (bytes forwarded, corrupted, dropped, paused).
void run_relay(const RelayOptions& options, Diagnostics& diag);

}  // namespace mcg::link
