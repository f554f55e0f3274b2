// Requests, retries and the frames in between.
#include "link/session.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>

#include "common/demand.hpp"  // MCG_DEMAND
#include "common/error.hpp"   // mcg::fail
#include "mcg_protocol.h"     // MCG_CMD_*, MCG_MSG_*

namespace mcg::link {

namespace {

using Clock = std::chrono::steady_clock;

double now_s() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

/// Frames the host keeps for receive() while it waits for answers (the stream at full rate
/// delivers 31 blocks per second; this holds minutes of them).
constexpr std::size_t k_max_unsolicited = 1u << 14;

constexpr double k_write_timeout_s = 2.0;

/// Added to the reply timeout of MCG_CMD_READ_MANY: a port owner holds a long answer back until
/// the board's transmit ring has room for it beside the stream (up to about 0.7 s); a resend
/// meanwhile would only queue another long answer behind it.
constexpr double k_read_many_pacing_s = 1.0;

}  // namespace

std::string board_name(unsigned board) {
  switch (board) {
    case MCG_BOARD_C515:
      return "c515";
    case MCG_BOARD_UCSIM:
      return "ucsim";
    case MCG_BOARD_HOST:
      return "host";
    default:
      return std::to_string(board);
  }
}

Session::Session(Port& port, SessionOptions options)
    : m_port(port), m_options(options), m_decoder(options.frame_timeout_s) {
  MCG_DEMAND(m_options.read_many_chunk >= 1 && m_options.read_many_chunk <= MCG_READ_MANY_MAX);
}

void Session::pump(double timeout_s) {
  std::uint8_t buf[512];
  const std::size_t n = m_port.read_some(buf, timeout_s);
  std::vector<Frame> frames;
  if (n == 0) {
    m_decoder.poll(now_s(), frames);  // a real silence: the wait brought nothing
  } else {
    m_decoder.feed(std::span<const std::uint8_t>(buf, n), now_s(), frames);
  }
  for (auto& f : frames) m_frames.push_back(std::move(f));
}

void Session::no_answer(std::string_view what) const {
  const auto& s = m_decoder.stats();
  if (s.frames == 0 && (s.skipped_bytes > 0 || s.bad_crc > 0 || s.too_long > 0)) {
    fail("{}: nothing answers {}: only garbled bytes arrive (wrong --baud? not the mcg firmware?)", m_port.name(),
         what);
  }
  fail("{}: nothing answers {} after {} tries (board off, not connected, or not running the mcg firmware?)",
       m_port.name(), what, m_options.attempts);
}

std::vector<std::uint8_t> Session::request(std::uint8_t cmd, std::span<const std::uint8_t> payload,
                                           std::string_view what) {
  const std::vector<std::uint8_t> bytes = encode(cmd, payload);
  const auto answer_cmd = static_cast<std::uint8_t>(cmd | MCG_REPLY_BIT);
  // READ and WRITE answers echo the register: an answer to an earlier try must not pass.
  const bool echoes_reg =
      (cmd == MCG_CMD_READ || cmd == MCG_CMD_WRITE || cmd == MCG_CMD_READ_MANY) && !payload.empty();
  for (int attempt = 0; attempt < m_options.attempts; ++attempt) {
    m_port.write_all(bytes, k_write_timeout_s);
    const double deadline =
        now_s() + m_options.reply_timeout_s + (cmd == MCG_CMD_READ_MANY ? k_read_many_pacing_s : 0.0);
    bool resend = false;
    while (!resend) {
      while (!m_frames.empty() && !resend) {
        Frame f = std::move(m_frames.front());
        m_frames.pop_front();
        if (f.cmd == answer_cmd && !f.payload.empty()) {
          const std::uint8_t status = f.payload[0];
          if (status == MCG_ST_OK && echoes_reg && (f.payload.size() < 2 || f.payload[1] != payload[0])) continue;
          if (status != MCG_ST_OK) {
            throw Refused(fmt::format("{}: {}: {}", m_port.name(), what, status_text(status)), status);
          }
          return std::vector<std::uint8_t>(f.payload.begin() + 1, f.payload.end());
        }
        if (f.cmd == MCG_MSG_ERROR) {
          resend = true;
        } else if (f.cmd >= MCG_MSG_STREAM && m_unsolicited.size() < k_max_unsolicited) {
          m_unsolicited.push_back(std::move(f));
        }
      }
      if (resend) break;
      const double left = deadline - now_s();
      if (left <= 0.0) break;
      pump(left);
    }
  }
  no_answer(what);
}

Version Session::hello() {
  m_port.discard_input();
  m_decoder.reset();
  m_frames.clear();
  const auto data = request(MCG_CMD_VERSION, {}, "the version request");
  if (data.size() < sizeof(McgVersionAnswer)) fail("{}: wrong firmware: malformed version answer ({} bytes)", m_port.name(), data.size());
  Version v{data[0], data[1], data[2], data[3], data[4]};
  if (v.protocol != MCG_PROTOCOL_VERSION) {
    fail("{}: wrong firmware: it speaks protocol {} (firmware {}.{}.{} on {}), {} speaks protocol {}",
         m_port.name(), v.protocol, v.major, v.minor, v.patch, board_name(v.board),
         m_options.tool.empty() ? std::string("the host") : m_options.tool, MCG_PROTOCOL_VERSION);
  }
  return v;
}

std::int16_t Session::read(const RegisterInfo& reg) {
  const std::uint8_t req[1] = {reg.id};
  const auto data = request(MCG_CMD_READ, req, fmt::format("reading {}", reg.name));
  if (data.size() < sizeof(McgRegisterAnswer)) fail("{}: reading {}: malformed answer", m_port.name(), reg.name);
  return get_i16(data, 1);
}

std::vector<std::int16_t> Session::read_many(std::span<const RegisterInfo* const> regs) {
  std::vector<std::int16_t> values;
  values.reserve(regs.size());
  std::size_t at = 0;
  while (at < regs.size()) {
    std::size_t n = 1;
    while (at + n < regs.size() && n < m_options.read_many_chunk && regs[at + n]->id == regs[at]->id + n) ++n;
    if (n == 1) {
      values.push_back(read(*regs[at]));
      ++at;
      continue;
    }
    const std::uint8_t req[sizeof(McgReadManyRequest)] = {regs[at]->id, static_cast<std::uint8_t>(n)};
    const auto data = request(MCG_CMD_READ_MANY, req, fmt::format("reading {}..{}", regs[at]->name, regs[at + n - 1]->name));
    if (data.size() != sizeof(McgReadManyRequest) + 2 * n || data[1] != n) {
      fail("{}: reading {}..{}: malformed answer", m_port.name(), regs[at]->name, regs[at + n - 1]->name);
    }
    for (std::size_t k = 0; k < n; ++k) values.push_back(get_i16(data, sizeof(McgReadManyRequest) + 2 * k));
    at += n;
  }
  return values;
}

std::int16_t Session::write(const RegisterInfo& reg, std::int16_t raw) {
  std::vector<std::uint8_t> req{reg.id};
  put_i16(req, raw);
  const auto data = request(MCG_CMD_WRITE, req, fmt::format("writing {}", reg.name));
  if (data.size() < sizeof(McgRegisterAnswer)) fail("{}: writing {}: malformed answer", m_port.name(), reg.name);
  return get_i16(data, 1);
}

std::optional<Frame> Session::receive(double timeout_s) {
  const double deadline = now_s() + timeout_s;
  for (;;) {
    while (!m_frames.empty()) {
      Frame f = std::move(m_frames.front());
      m_frames.pop_front();
      if (f.cmd >= MCG_MSG_STREAM && f.cmd != MCG_MSG_ERROR) m_unsolicited.push_back(std::move(f));
    }
    if (!m_unsolicited.empty()) {
      Frame f = std::move(m_unsolicited.front());
      m_unsolicited.pop_front();
      return f;
    }
    const double left = deadline - now_s();
    if (left <= 0.0) return std::nullopt;
    const std::size_t before = m_frames.size();
    pump(left);
    if (m_frames.size() == before && now_s() < deadline - 1e-3) {
      // Woken without a frame: bytes of a partial frame, or a signal. Let the caller look.
      return std::nullopt;
    }
  }
}

LogDump Session::dump_log() {
  for (int attempt = 0; attempt < m_options.attempts; ++attempt) {
    m_unsolicited.erase(std::remove_if(m_unsolicited.begin(), m_unsolicited.end(),
                                       [](const Frame& f) { return f.cmd == MCG_MSG_LOG_DATA; }),
                        m_unsolicited.end());
    const auto data = request(MCG_CMD_LOG_DUMP, {}, "the log dump");
    if (data.size() < sizeof(McgDumpAnswer)) fail("{}: the log dump: malformed answer", m_port.name());
    LogDump dump;
    const std::size_t points = data[0];
    dump.interval_ms = data[1];
    dump.counts.assign(points, 0);
    std::vector<bool> have(points, false);
    std::size_t missing = points;
    // A data frame every ~40 ms at 9600 baud; a second without one means one was lost.
    double deadline = now_s() + 1.0;
    while (missing > 0 && now_s() < deadline) {
      const auto f = receive(deadline - now_s());
      if (!f || f->cmd != MCG_MSG_LOG_DATA || f->payload.size() < MCG_LOGDATA_HEADER) continue;
      const std::size_t first = f->payload[0];
      const std::size_t n = f->payload[1];
      if (f->payload.size() != MCG_LOGDATA_HEADER + 2 * n) continue;
      for (std::size_t k = 0; k < n && first + k < points; ++k) {
        if (!have[first + k]) --missing;
        have[first + k] = true;
        dump.counts[first + k] = get_u16(f->payload, MCG_LOGDATA_HEADER + 2 * k);
      }
      deadline = now_s() + 1.0;
    }
    if (missing == 0) return dump;
  }
  fail("{}: the log dump: data frames lost on every one of {} tries", m_port.name(), m_options.attempts);
}

void Session::write_sequence(std::span<const SeqEntry> entries) {
  if (entries.size() > MCG_SEQ_MAX) fail("sequence: {} entries, the board holds at most {}", entries.size(), MCG_SEQ_MAX);
  request(MCG_CMD_SEQ_CLEAR, {}, "clearing the sequence");
  std::size_t index = 0;
  while (index < entries.size()) {
    const std::size_t n = std::min<std::size_t>(MCG_SEQ_WRITE_MAX, entries.size() - index);
    std::vector<std::uint8_t> req{static_cast<std::uint8_t>(index)};
    for (std::size_t k = 0; k < n; ++k) {
      const SeqEntry& e = entries[index + k];
      put_u16(req, e.delay_ms);
      req.push_back(e.reg);
      put_i16(req, e.raw);
    }
    const auto data = request(MCG_CMD_SEQ_WRITE, req, fmt::format("writing sequence entries {}..{}", index, index + n - 1));
    if (data.size() < sizeof(McgSeqWriteAnswer) || data[0] != index + n) {
      fail("{}: writing sequence entries {}..{}: the board reports next index {}, expected {}", m_port.name(), index,
           index + n - 1, data.empty() ? -1 : int{data[0]}, index + n);
    }
    index += n;
  }
}

}  // namespace mcg::link
