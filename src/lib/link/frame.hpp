// Framing of the board protocol (mcg-protocol(7)): encoder, CRC and a resynchronising decoder.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "mcg_protocol.h"  // MCG_SYNC, MCG_MAX_PAYLOAD, MCG_FRAME_OVERHEAD

namespace mcg::link {

/// One checked frame: the command byte and its payload (at most MCG_MAX_PAYLOAD bytes).
struct Frame {
  std::uint8_t cmd = 0;
  std::vector<std::uint8_t> payload;
};

/// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF) over `bytes`, as the board computes it.
std::uint16_t crc16(std::span<const std::uint8_t> bytes, std::uint16_t crc = MCG_CRC_INIT);

/// The wire bytes of a frame: SYNC LEN CMD PAYLOAD CRC_LO CRC_HI. The payload must not exceed
/// MCG_MAX_PAYLOAD (MCG_DEMAND).
std::vector<std::uint8_t> encode(std::uint8_t cmd, std::span<const std::uint8_t> payload);

/// What the decoder threw away, and why.
struct DecoderStats {
  std::uint64_t frames = 0;         ///< frames delivered
  std::uint64_t bad_crc = 0;        ///< candidate frames whose CRC did not match
  std::uint64_t too_long = 0;       ///< SYNC followed by LEN > MCG_MAX_PAYLOAD
  std::uint64_t timeouts = 0;       ///< partial frames dropped after a silence inside the frame
  std::uint64_t skipped_bytes = 0;  ///< bytes that belonged to no frame (noise, resync)
};

/// Turns a byte stream into frames, resynchronising on noise, lost bytes and truncation.
///
/// A candidate frame starts at a SYNC byte. When its LEN is impossible or its CRC fails, only
/// that SYNC byte is discarded and the search restarts at the next byte, so a good frame that
/// begins inside the bytes of a damaged one is still found. A candidate that stays incomplete
/// for longer than the inter-byte timeout is dropped the same way (its bytes are rescanned).
class Decoder {
 public:
  /// `frame_timeout_s`: the longest silence allowed inside a frame (the protocol's
  /// MCG_FRAME_TIMEOUT_MS by default; the host may allow more for scheduling jitter).
  explicit Decoder(double frame_timeout_s = MCG_FRAME_TIMEOUT_MS * 1e-3) : m_timeout_s(frame_timeout_s) {}

  /// Feeds bytes that arrived at `now_s` (any monotonic clock, seconds); appends every
  /// complete, CRC-checked frame to `out`. Never drops a partial frame for lateness: bytes
  /// that waited in the port's buffer while the host was busy are not a silence on the line.
  void feed(std::span<const std::uint8_t> bytes, double now_s, std::vector<Frame>& out);
  /// Call after a wait on the line that brought nothing: applies the inter-byte timeout at
  /// `now_s`; appends frames found by rescanning a dropped partial frame to `out`.
  void poll(double now_s, std::vector<Frame>& out);
  /// True while a partial frame is buffered.
  bool pending() const { return !m_buf.empty(); }
  /// Forgets any partial frame (e.g. after flushing the port's input).
  void reset();

  const DecoderStats& stats() const { return m_stats; }

 private:
  void scan(std::vector<Frame>& out);
  void drop_front(std::size_t count);

  double m_timeout_s;
  double m_last_byte_s = 0.0;
  std::vector<std::uint8_t> m_buf;
  DecoderStats m_stats;
};

/// Little-endian field access for payloads.
inline std::int16_t get_i16(std::span<const std::uint8_t> p, std::size_t at) {
  return static_cast<std::int16_t>(static_cast<std::uint16_t>(p[at] | (p[at + 1] << 8)));
}
inline std::uint16_t get_u16(std::span<const std::uint8_t> p, std::size_t at) {
  return static_cast<std::uint16_t>(p[at] | (p[at + 1] << 8));
}
inline void put_i16(std::vector<std::uint8_t>& p, std::int16_t value) {
  const auto u = static_cast<std::uint16_t>(value);
  p.push_back(static_cast<std::uint8_t>(u & 0xFFu));
  p.push_back(static_cast<std::uint8_t>(u >> 8));
}
inline void put_u16(std::vector<std::uint8_t>& p, std::uint16_t value) {
  p.push_back(static_cast<std::uint8_t>(value & 0xFFu));
  p.push_back(static_cast<std::uint8_t>(value >> 8));
}

}  // namespace mcg::link
