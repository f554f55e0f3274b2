// Lines of text from a stream as they arrive: what a pipe has is handed on at once (a live
// plot or filter never waits for a buffer to fill), in time linear in the input and in memory
// bounded by the longest line allowed.
#pragma once

#include <cstddef>
#include <iosfwd>
#include <streambuf>
#include <string>
#include <string_view>

namespace mcg {

/// The longest line a text input may have (a CSV or INI line), in bytes without its newline.
/// A longer line is a one-line error, so a line that never ends costs this much memory, not
/// the size of the input. It holds a multisine's 100000 lines in one metadata line.
inline constexpr std::size_t k_max_line_bytes = std::size_t{16} << 20;

/// "line longer than 16777216 bytes": the message for a line past k_max_line_bytes, after
/// "<source>:N: ".
std::string line_too_long();

/// Reads what `in` has available into `dest` (at most `room` bytes, room > 0), as read(2) does:
/// the bytes already buffered or waiting in the pipe, and only when there are none, waits for
/// at least one. 0 at the end of the input. Throws "<source>: read error: ..." on a failed read.
std::size_t read_available(std::streambuf& in, char* dest, std::size_t room, const std::string& source);

class LineReader {
 public:
  LineReader(std::istream& in, std::string source);
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;

  const std::string& source() const { return m_source; }
  /// The next line, without its '\n' and a '\r' before it, valid until the next call; false at
  /// the end of the input (a last line without '\n' is a line). Throws "<source>:N: line longer
  /// than 16777216 bytes" past k_max_line_bytes.
  bool next(std::string_view& line);
  /// 1-based number of the line next() returned last.
  std::size_t line() const { return m_line; }

  /// The input not read yet as whole lines, at least `bytes` of them unless the input ends
  /// first, into `out` (its storage reused); false when nothing is left, or when the next line
  /// is longer than k_max_line_bytes (then overlong() is true; the lines before it were handed
  /// out). The caller counts these lines: line() does not move.
  bool take(std::string& out, std::size_t bytes);
  bool overlong() const { return m_overlong; }

 private:
  /// Reads more into the free space after m_end (the buffer grows as needed); sets m_eof at
  /// the end of the input.
  void fill();

  std::istream& m_in;
  std::string m_source;
  std::string m_buffer;  ///< storage; bytes [m_pos, m_end) are read and not yet consumed
  std::size_t m_pos = 0;
  std::size_t m_scanned = 0;  ///< bytes [m_pos, m_scanned) hold no newline: never scanned twice
  std::size_t m_end = 0;
  std::size_t m_line = 0;
  bool m_filled = false;  ///< the last read filled the free space: the input comes fast, grow
  bool m_eof = false;
  bool m_overlong = false;
};

}  // namespace mcg
