// fw_harness.hpp: drives the firmware core through its host board layer, the way the PC would.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "core.h"
#include "fw_frames.hpp"
#include "host_board.h"
#include "mcg_protocol.h"

namespace fwtest {

// The board after a power-on reset, with an unlimited serial line unless set_baud is called.
class Board {
 public:
  Board() { host_board_reset(); }

  void set_baud(std::uint32_t baud) { host_board_set_baud(baud); }
  void send(const Bytes& bytes) { host_board_rx(bytes.data(), bytes.size()); }

  // Runs ms ticks with the given encoder pulses per tick; returns the frames the board sent.
  std::vector<Frame> run(int ms, std::uint16_t pulses_per_ms = 0) {
    std::vector<Frame> frames;
    for (int i = 0; i < ms; ++i) {
      host_board_tick(pulses_per_ms);
      collect(frames);
    }
    return frames;
  }

  // Sends one request and waits (up to 200 ms of board time) for its answer.
  std::optional<Frame> request(std::uint8_t cmd, const Bytes& payload = {}) {
    send(encode(cmd, payload));
    for (int i = 0; i < 200; ++i) {
      std::vector<Frame> frames;
      host_board_tick(m_pulses);
      collect(frames);
      for (const Frame& f : frames) {
        if (f.cmd == (cmd | MCG_REPLY_BIT)) {
          return f;
        }
        m_other.push_back(f);
      }
    }
    return std::nullopt;
  }

  // Status of a register write (MCG_ST_*).
  std::uint8_t write(std::uint8_t reg, int value) {
    Bytes p{reg};
    const Bytes v = le16(value);
    p.insert(p.end(), v.begin(), v.end());
    const auto f = request(MCG_CMD_WRITE, p);
    return f ? f->payload.at(0) : 0xFF;
  }

  // A write as mcg-serial set makes it: a register of the controller's set (MCG_RS) is staged and
  // then committed. The status of the write, or else of the commit.
  std::uint8_t set(std::uint8_t reg, int value) {
    const std::uint8_t st = write(reg, value);
    if (st != MCG_ST_OK || !staged(reg)) {
      return st;
    }
    return write(MCG_REG_COMMIT, 1);
  }

  static bool staged(std::uint8_t reg) {
#define FW_ACCESS(NAME, name, access, lo, hi, def, unit, capture, keypad, doc) access,
    static const unsigned access[] = {MCG_REGISTERS(FW_ACCESS)};
#undef FW_ACCESS
    return reg >= MCG_REG_MODE && reg < MCG_REG_COUNT && access[reg - 1u] == MCG_RS;
  }

  int read(std::uint8_t reg) {
    const auto f = request(MCG_CMD_READ, {reg});
    if (!f || f->payload.at(0) != MCG_ST_OK) {
      return -100000;
    }
    return i16_at(f->payload, 2);
  }

  void key(std::uint8_t k) { host_board_key(k); }

  // Holds a key for one service period, then releases it for one.
  void press(std::uint8_t k, int service_ms = 40) {
    key(k);
    run(service_ms);
    key(MCG_KEY_NONE);
    run(service_ms);
  }

  void set_pulses(std::uint16_t p) { m_pulses = p; }
  // Frames that arrived while request() waited for its answer; taking them empties the list.
  std::vector<Frame> take_other() {
    std::vector<Frame> o;
    o.swap(m_other);
    return o;
  }
  std::size_t garbage() const { return m_decoder.garbage(); }

 private:
  void collect(std::vector<Frame>& frames) {
    std::uint8_t buf[512];
    const std::size_t n = host_board_tx(buf, sizeof buf);
    const auto got = m_decoder.feed(Bytes(buf, buf + n));
    frames.insert(frames.end(), got.begin(), got.end());
  }

  Decoder m_decoder;
  std::uint16_t m_pulses = 0;
  std::vector<Frame> m_other;
};

}  // namespace fwtest
