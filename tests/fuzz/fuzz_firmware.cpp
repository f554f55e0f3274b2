// The firmware's frame receiver and command dispatcher, on the host board layer: the bytes
// arrive on the serial line a chunk per 1 ms tick; the board must keep running and answering.
#include "fuzz.hpp"
#include "host_board.h"
#include "link/frame.hpp"

#include <algorithm>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  host_board_reset();
  std::uint8_t out[256];
  std::size_t at = 0;
  // Every byte is offered, a chunk per tick; then the line stays quiet for longer than the frame
  // timeout, as a host does before it asks again (a request that follows garbage at once
  // completes the garbage's partial frame and is lost with it; the host retries).
  constexpr int k_quiet_ticks = 2 * static_cast<int>(MCG_FRAME_TIMEOUT_MS);
  while (at < size && host_board_time_ms() < 60000u) {
    at += host_board_rx(data + at, std::min<std::size_t>(size - at, 8));
    host_board_tick(static_cast<std::uint16_t>(at < size ? data[at] & 0x0fu : 0u));
    host_board_tx(out, sizeof out);
  }
  for (int t = 0; t < k_quiet_ticks; ++t) {
    host_board_tick(0);
    host_board_tx(out, sizeof out);
  }
  // Still alive: a version request gets its answer.
  const std::vector<std::uint8_t> ask = mcg::link::encode(MCG_CMD_VERSION, {});
  host_board_rx(ask.data(), ask.size());
  mcg::link::Decoder decoder(1e9);
  std::vector<mcg::link::Frame> frames;
  bool answered = false;
  for (int t = 0; t < 200 && !answered; ++t) {
    host_board_tick(0);
    const std::size_t n = host_board_tx(out, sizeof out);
    decoder.feed({out, n}, 0.0, frames);
    for (const auto& f : frames) answered = answered || f.cmd == (MCG_CMD_VERSION | MCG_REPLY_BIT);
  }
  if (!answered) mcg::fuzz::finding("the board stopped answering after the input");
  return 0;
}
