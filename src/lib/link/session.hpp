// A conversation with the board: requests with timeouts and retries, unsolicited frames queued.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/error.hpp"    // Error
#include "link/frame.hpp"      // Frame, Decoder
#include "link/port.hpp"       // Port
#include "link/registers.hpp"  // RegisterInfo

namespace mcg::link {

struct SessionOptions {
  /// Wait for each answer, s. At 9600 baud a reply takes under 15 ms on the wire, but it may
  /// queue behind a stream block or a log dump frame; 0.3 s leaves room for both.
  double reply_timeout_s = 0.3;
  /// The tool that speaks for the host, as messages name it ("mcg-serial"); empty: "the host".
  std::string tool;
  /// Attempts per request before the board counts as not answering.
  int attempts = 3;
  /// Longest silence inside a frame before the host drops it, s. Larger than the board's
  /// MCG_FRAME_TIMEOUT_MS because the host is not real-time.
  double frame_timeout_s = 0.1;
  /// Registers asked for in one MCG_CMD_READ_MANY. On a line to the board, 20: a 48-byte
  /// answer, which the board's 128-byte transmit ring takes beside a 56-byte stream block with
  /// room to spare (an answer of MCG_READ_MANY_MAX, 68 bytes, finds no room when the line runs
  /// late, and the board drops it). A port owner answers up to MCG_READ_MANY_MAX itself, asking
  /// the board in parts that fit.
  std::size_t read_many_chunk = 20;
};

/// What MCG_CMD_VERSION reports.
struct Version {
  unsigned protocol = 0;
  unsigned major = 0;
  unsigned minor = 0;
  unsigned patch = 0;
  unsigned board = 0;  ///< MCG_BOARD_*
};
/// "c515", "ucsim", "host" or the number.
std::string board_name(unsigned board);

/// The RAM log as the board sent it.
struct LogDump {
  unsigned interval_ms = 0;            ///< spacing of the points
  std::vector<std::uint16_t> counts;   ///< encoder pulses during each interval, oldest first
};

/// One entry of a command sequence: after `delay_ms` (from the previous entry), write `raw`
/// into register `reg`.
struct SeqEntry {
  std::uint16_t delay_ms = 0;
  std::uint8_t reg = 0;
  std::int16_t raw = 0;
};

/// The board refused a request: `status` (MCG_ST_*) says why. The message is as Session::request
/// words it ("<port>: <what>: <status text>").
class Refused : public Error {
 public:
  Refused(std::string_view what, std::uint8_t status) : Error(what), m_status(status) {}
  std::uint8_t status() const { return m_status; }

 private:
  std::uint8_t m_status;
};

class Session {
 public:
  explicit Session(Port& port, SessionOptions options = {});

  /// Flushes stale input, asks for the version and checks the protocol revision. Throws
  /// mcg::Error "<port>: nothing answers ..." or "<port>: wrong firmware: ...".
  Version hello();

  /// Sends a request and returns the answer's data (the bytes after the status). Resends
  /// after `reply_timeout_s` of silence, or at once when the board reports it dropped a
  /// damaged frame, up to `attempts` times. Throws Refused "<port>: <what>: <status text>" for a
  /// refusal, mcg::Error "<port>: nothing answers ..." after the last attempt.
  std::vector<std::uint8_t> request(std::uint8_t cmd, std::span<const std::uint8_t> payload,
                                    std::string_view what);

  /// The raw value of a register.
  std::int16_t read(const RegisterInfo& reg);
  /// The raw values of `regs`, in their order: each run of consecutive ids in one
  /// MCG_CMD_READ_MANY (at most SessionOptions::read_many_chunk registers an answer), a lone id
  /// by MCG_CMD_READ.
  std::vector<std::int16_t> read_many(std::span<const RegisterInfo* const> regs);
  /// Writes a raw value; returns the value the board holds afterwards (from its answer): for a
  /// staged register, the value in the shadow set.
  std::int16_t write(const RegisterInfo& reg, std::int16_t raw);

  /// Starts nothing: reads the RAM log (MCG_CMD_LOG_DUMP and its data frames), retrying the
  /// whole dump when a data frame is lost.
  LogDump dump_log();
  /// Replaces the board's command sequence with `entries` (cleared first, then written in
  /// chunks of MCG_SEQ_WRITE_MAX), checking the next index each chunk reports.
  void write_sequence(std::span<const SeqEntry> entries);

  /// The next frame the board sent on its own (stream blocks, log data): from the queue of
  /// frames that arrived during requests first, else waits up to `timeout_s`. nullopt on
  /// timeout or when a signal interrupted the wait.
  std::optional<Frame> receive(double timeout_s);

  Port& port() { return m_port; }
  const DecoderStats& stats() const { return m_decoder.stats(); }

 private:
  /// Reads what arrives within `timeout_s` into m_frames.
  void pump(double timeout_s);
  [[noreturn]] void no_answer(std::string_view what) const;

  Port& m_port;
  SessionOptions m_options;
  Decoder m_decoder;
  std::deque<Frame> m_frames;    ///< decoded, not yet consumed
  std::deque<Frame> m_unsolicited;
};

}  // namespace mcg::link
