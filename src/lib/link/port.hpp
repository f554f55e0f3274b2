// Byte lines to the board: serial ports (libserialport) and pseudo-terminals, every wait bounded.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "common/error.hpp"  // mcg::Error

namespace mcg::link {

/// The line went away while in use: a USB adapter unplugged, the emulated board ended, the
/// far end of a pseudo-terminal closed. What was received before is not affected.
class PortVanished : public Error {
 public:
  using Error::Error;
};

/// A byte line with bounded waits. No call blocks longer than the timeout it is given.
class Port {
 public:
  virtual ~Port() = default;
  Port() = default;
  Port(const Port&) = delete;
  Port& operator=(const Port&) = delete;

  /// The path as the user gave it (for messages).
  virtual const std::string& name() const = 0;
  /// Waits up to `timeout_s` for input, then reads what is there (at most buf.size() bytes).
  /// Returns 0 after the timeout, or early when a signal arrived (the caller checks its flag).
  /// Throws PortVanished when the line is gone.
  virtual std::size_t read_some(std::span<std::uint8_t> buf, double timeout_s) = 0;
  /// Writes all bytes within `timeout_s`; throws mcg::Error when the line stays blocked, and
  /// PortVanished when it is gone.
  virtual void write_all(std::span<const std::uint8_t> bytes, double timeout_s) = 0;
  /// Throws away bytes received but not read yet.
  virtual void discard_input() = 0;
  /// A descriptor poll() reports readable when input is there, or -1 (then the port's owner
  /// asks read_some() at short intervals).
  virtual int poll_fd() const { return -1; }
};

/// Opens `path` for the board: 8N1 at `baud`, no flow control, raw, exclusive. Serial devices
/// go through libserialport; pseudo-terminals (the emulated board, socat links), which
/// libserialport does not handle, are opened directly with the same settings. Throws
/// mcg::Error with one line for each way it can fail:
///   "<path>: no such port (mcg-serial list shows the serial ports)"
///   "<path>: permission denied (add your user to the 'dialout' group: ...)"
///   "<path>: port busy (another program has it open)"
///   "<path>: not a serial port"
std::unique_ptr<Port> open_port(const std::string& path, int baud);

/// One serial port that libserialport finds on this machine.
struct PortListing {
  std::string name;         ///< device path, e.g. /dev/ttyUSB0
  std::string description;  ///< e.g. "FT232R USB UART (USB 0403:6001, serial A9XYZ)"
};
/// Every serial port libserialport enumerates, sorted by name.
std::vector<PortListing> list_ports();

/// An emulated port (mcg-sim --board) entered, for as long as this object lives, in the list
/// emulated_ports() reads: a file mcg-board.PID in $XDG_RUNTIME_DIR (else /tmp) holding the
/// link's absolute path and the description.
class EmulatedPortEntry {
 public:
  EmulatedPortEntry(const std::string& link_path, const std::string& description);
  ~EmulatedPortEntry();
  EmulatedPortEntry(const EmulatedPortEntry&) = delete;
  EmulatedPortEntry& operator=(const EmulatedPortEntry&) = delete;

 private:
  std::string m_file;
};
/// The emulated ports whose process still runs and whose link still exists, sorted by name.
std::vector<PortListing> emulated_ports();

/// The one-line message for a failed open of `path` with `err` (an errno value).
std::string open_error_message(const std::string& path, int err);

}  // namespace mcg::link
