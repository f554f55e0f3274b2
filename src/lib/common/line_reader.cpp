// LineReader: lines as they arrive, each byte scanned once, no line past k_max_line_bytes.
#include "common/line_reader.hpp"

#include <algorithm>
#include <cstring>
#include <ios>
#include <istream>

#include "common/error.hpp"

namespace mcg {

namespace {

constexpr std::size_t k_first_block = 4096;
constexpr std::size_t k_read_block = 1 << 20;

[[noreturn]] void too_long(const std::string& source, std::size_t line) {
  fail("{}:{}: {}", source, line, line_too_long());
}

}  // namespace

std::string line_too_long() { return fmt::format("line longer than {} bytes", k_max_line_bytes); }

std::size_t read_available(std::streambuf& in, char* dest, std::size_t room, const std::string& source) {
  using traits = std::streambuf::traits_type;
  try {
    // in_avail(): what the buffer holds, else what the pipe or file holds (FIONREAD). Only
    // when that is nothing does sgetc() wait, for one read(2) of whatever comes.
    std::streamsize n = in.in_avail();
    if (n <= 0) {
      if (traits::eq_int_type(in.sgetc(), traits::eof())) return 0;
      n = std::max<std::streamsize>(in.in_avail(), 1);
    }
    const auto want = std::min(static_cast<std::size_t>(n), room);
    return static_cast<std::size_t>(
        std::max<std::streamsize>(in.sgetn(dest, static_cast<std::streamsize>(want)), 0));
  } catch (const std::ios_base::failure& e) {
    fail("{}: read error: {}", source, e.code().message());
  }
}

LineReader::LineReader(std::istream& in, std::string source) : m_in(in), m_source(std::move(source)) {}

void LineReader::fill() {
  // Keep the unfinished line at the front, then read into the free space. The buffer starts
  // small and grows when it is half full or a read filled it (a long line, or a large input
  // arriving fast), by up to k_read_block a step: a three-line file costs 4 KiB.
  if (m_pos > 0) {
    std::memmove(m_buffer.data(), m_buffer.data() + m_pos, m_end - m_pos);
    m_end -= m_pos;
    m_scanned -= m_pos;
    m_pos = 0;
  }
  const bool cramped = m_buffer.size() - m_end < m_buffer.size() / 2;
  if (m_buffer.empty() || cramped || (m_filled && m_buffer.size() < k_read_block)) {
    m_buffer.resize(m_buffer.empty() ? k_first_block
                                     : m_buffer.size() + std::min(m_buffer.size(), k_read_block));
  }
  const std::size_t room = m_buffer.size() - m_end;
  const std::size_t got = read_available(*m_in.rdbuf(), m_buffer.data() + m_end, room, m_source);
  if (got == 0) m_eof = true;
  m_end += got;
  m_filled = got == room;
}

bool LineReader::next(std::string_view& line) {
  while (true) {
    const char* begin = m_buffer.data() + m_pos;
    if (const void* nl = std::memchr(m_buffer.data() + m_scanned, '\n', m_end - m_scanned)) {
      const auto len = static_cast<std::size_t>(static_cast<const char*>(nl) - begin);
      ++m_line;
      if (len > k_max_line_bytes) too_long(m_source, m_line);
      line = std::string_view(begin, len);
      m_pos = m_scanned = m_pos + len + 1;
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      return true;
    }
    m_scanned = m_end;
    if (m_end - m_pos > k_max_line_bytes) too_long(m_source, m_line + 1);
    if (m_eof) {
      if (m_pos == m_end) return false;
      line = std::string_view(begin, m_end - m_pos);
      m_pos = m_scanned = m_end;
      ++m_line;
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      return true;
    }
    fill();
  }
}

bool LineReader::take(std::string& out, std::size_t bytes) {
  out.assign(m_buffer, m_pos, m_end - m_pos);
  m_pos = m_scanned = m_end = 0;
  std::size_t checked = 0;     // out[0, checked) is scanned
  std::size_t line_start = 0;  // where the unfinished line of out[0, checked) starts
  bool cut = false;            // the line at line_start is too long: hand out only what precedes it
  while (true) {
    if (const void* nl = ::memrchr(out.data() + checked, '\n', out.size() - checked)) {
      line_start = static_cast<std::size_t>(static_cast<const char*>(nl) - out.data()) + 1;
    }
    checked = out.size();
    if (checked - line_start > k_max_line_bytes) {
      if (line_start == 0) {
        m_overlong = true;
        out.clear();
        return false;
      }
      cut = true;
      break;
    }
    if (m_eof || (line_start > 0 && out.size() >= bytes)) break;
    // Read in steps that grow with what has come (4 KiB up to k_read_block): a small input
    // costs a small buffer, a large one large reads.
    const std::size_t used = out.size();
    const std::size_t want = std::clamp(used, k_first_block, k_read_block);
    out.resize(used + want);
    const std::size_t got = read_available(*m_in.rdbuf(), out.data() + used, want, m_source);
    out.resize(used + got);
    if (got == 0) m_eof = true;
  }
  if (!m_eof || cut) {
    // The unfinished last line waits in the buffer for the next call.
    m_buffer.assign(out, line_start);
    m_end = m_buffer.size();
    out.resize(line_start);
  }
  return !out.empty();
}

}  // namespace mcg
