// fw_frames.hpp: the host side of mcg-protocol(7) framing, for tests: encode, CRC, decode.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "mcg_protocol.h"

namespace fwtest {

using Bytes = std::vector<std::uint8_t>;

struct Frame {
  std::uint8_t cmd = 0;
  Bytes payload;
};

inline std::uint16_t crc16(const Bytes& bytes, std::size_t from, std::size_t to) {
  unsigned crc = MCG_CRC_INIT;
  for (std::size_t i = from; i < to; ++i) {
    crc = mcg_crc16_update(crc, bytes[i]);
  }
  return static_cast<std::uint16_t>(crc);
}

// SYNC LEN CMD PAYLOAD CRC_LO CRC_HI
inline Bytes encode(std::uint8_t cmd, const Bytes& payload = {}) {
  Bytes f{static_cast<std::uint8_t>(MCG_SYNC), static_cast<std::uint8_t>(payload.size()), cmd};
  f.insert(f.end(), payload.begin(), payload.end());
  const std::uint16_t crc = crc16(f, 1, f.size());
  f.push_back(static_cast<std::uint8_t>(crc & 0xFFu));
  f.push_back(static_cast<std::uint8_t>(crc >> 8));
  return f;
}

inline Bytes le16(int v) {
  const auto u = static_cast<std::uint16_t>(v);
  return {static_cast<std::uint8_t>(u & 0xFFu), static_cast<std::uint8_t>(u >> 8)};
}

inline int i16_at(const Bytes& b, std::size_t at) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(b[at] | (b[at + 1] << 8)));
}

// Splits what the board sent into frames; the board's output must be clean framing (checked).
class Decoder {
 public:
  std::vector<Frame> feed(const Bytes& bytes) {
    m_buf.insert(m_buf.end(), bytes.begin(), bytes.end());
    std::vector<Frame> out;
    for (;;) {
      if (m_buf.size() < 2) {
        break;
      }
      if (m_buf[0] != MCG_SYNC) {
        ++m_garbage;
        m_buf.erase(m_buf.begin());
        continue;
      }
      const std::size_t total = m_buf[1] + std::size_t{MCG_FRAME_OVERHEAD};
      if (m_buf.size() < total) {
        break;
      }
      const std::uint16_t crc = crc16(m_buf, 1, total - 2);
      if (m_buf[total - 2] != (crc & 0xFFu) || m_buf[total - 1] != (crc >> 8)) {
        ++m_garbage;
        m_buf.erase(m_buf.begin());
        continue;
      }
      out.push_back(Frame{m_buf[2], Bytes(m_buf.begin() + 3, m_buf.begin() + static_cast<long>(total) - 2)});
      m_buf.erase(m_buf.begin(), m_buf.begin() + static_cast<long>(total));
    }
    return out;
  }
  std::size_t garbage() const { return m_garbage; }

 private:
  Bytes m_buf;
  std::size_t m_garbage = 0;
};

}  // namespace fwtest
