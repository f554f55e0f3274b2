// Frame encoder and resynchronising decoder.
#include "link/frame.hpp"

#include <algorithm>
#include "common/demand.hpp"

namespace mcg::link {

std::uint16_t crc16(std::span<const std::uint8_t> bytes, std::uint16_t crc) {
  unsigned c = crc;
  for (const std::uint8_t b : bytes) c = mcg_crc16_update(c, b);
  return static_cast<std::uint16_t>(c);
}

std::vector<std::uint8_t> encode(std::uint8_t cmd, std::span<const std::uint8_t> payload) {
  MCG_DEMAND(payload.size() <= MCG_MAX_PAYLOAD);
  std::vector<std::uint8_t> out;
  out.reserve(payload.size() + MCG_FRAME_OVERHEAD);
  out.push_back(static_cast<std::uint8_t>(MCG_SYNC));
  out.push_back(static_cast<std::uint8_t>(payload.size()));
  out.push_back(cmd);
  out.insert(out.end(), payload.begin(), payload.end());
  const std::uint16_t crc = crc16(std::span<const std::uint8_t>(out).subspan(1));
  put_u16(out, crc);
  return out;
}

void Decoder::reset() { m_buf.clear(); }

void Decoder::drop_front(std::size_t count) {
  m_buf.erase(m_buf.begin(), m_buf.begin() + static_cast<std::ptrdiff_t>(count));
}

void Decoder::feed(std::span<const std::uint8_t> bytes, double now_s, std::vector<Frame>& out) {
  if (bytes.empty()) return;
  m_buf.insert(m_buf.end(), bytes.begin(), bytes.end());
  m_last_byte_s = now_s;
  scan(out);
}

void Decoder::poll(double now_s, std::vector<Frame>& out) {
  // A silence inside a frame: the frame lost bytes. Drop its SYNC and look again at the rest.
  while (!m_buf.empty() && now_s - m_last_byte_s > m_timeout_s) {
    ++m_stats.timeouts;
    drop_front(1);
    scan(out);
  }
}

void Decoder::scan(std::vector<Frame>& out) {
  for (;;) {
    const auto sync = std::find(m_buf.begin(), m_buf.end(), static_cast<std::uint8_t>(MCG_SYNC));
    const auto skipped = static_cast<std::size_t>(sync - m_buf.begin());
    m_stats.skipped_bytes += skipped;
    drop_front(skipped);
    if (m_buf.size() < 2) return;
    const std::size_t len = m_buf[1];
    if (len > MCG_MAX_PAYLOAD) {
      ++m_stats.too_long;
      drop_front(1);
      continue;
    }
    const std::size_t total = len + MCG_FRAME_OVERHEAD;
    if (m_buf.size() < total) return;
    const std::span<const std::uint8_t> body(m_buf.data() + 1, len + 2);
    if (crc16(body) != get_u16(m_buf, len + 3)) {
      ++m_stats.bad_crc;
      drop_front(1);
      continue;
    }
    Frame frame;
    frame.cmd = m_buf[2];
    frame.payload.assign(m_buf.begin() + 3, m_buf.begin() + 3 + static_cast<std::ptrdiff_t>(len));
    out.push_back(std::move(frame));
    ++m_stats.frames;
    drop_front(total);
  }
}

}  // namespace mcg::link
