// mcg-sim --board: the emulated board behind a pseudo-terminal, paced by the wall clock.
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <string_view>
#include <utility>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <ostream>
#include <vector>

#include <fmt/format.h>

#include "board/board.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"   // mcg::fail
#include "common/poll_timeout.hpp"
#include "common/quote.hpp"
#include "config/ini.hpp"     // Ini
#include "link/interrupt.hpp" // InterruptGuard
#include "link/port.hpp"      // EmulatedPortEntry
#include "link/pty.hpp"       // PtyLink
#include "mcg_protocol.h"     // MCG_SYNC, MCG_FRAME_OVERHEAD
#include "model/load.hpp"

namespace mcg::board {

namespace {

/// Ticks run back to back at most this far behind the wall clock; a longer stall of the host
/// (the machine busy) is skipped instead of replayed in a burst.
constexpr double k_max_lag_s = 0.25;

/// Bytes the board sent that the host has not read yet, beyond which whole frames are dropped,
/// as on a line nobody reads (about 4 s of the 9600 baud line).
constexpr std::size_t k_max_unread_bytes = 4096;

/// Length of the prefix of `line` made of complete frames (SYNC LEN CMD PAYLOAD CRC CRC). The
/// emulator hands the pseudo-terminal whole frames only: a stall of this process inside a frame
/// must not look to the host like a silence on the line, which drops the partial frame.
std::size_t complete_frames(const std::vector<std::uint8_t>& line) {
  std::size_t end = 0;
  while (end < line.size()) {
    if (line[end] != MCG_SYNC) {
      ++end;  // not a frame start: passed on as it is, as the line would
      continue;
    }
    if (end + 1 >= line.size()) break;
    const std::size_t frame = line[end + 1] + std::size_t{MCG_FRAME_OVERHEAD};
    if (end + frame > line.size()) break;
    end += frame;
  }
  return end;
}

/// Writes the complete frames of `line` that the pseudo-terminal takes now and keeps the rest;
/// what a pseudo-terminal without a reader refuses is lost, as on a line nobody reads.
void write_frames(int fd, std::vector<std::uint8_t>& line) {
  const std::size_t ready = complete_frames(line);
  if (ready == 0) return;
  const ssize_t n = ::write(fd, line.data(), ready);
  const std::size_t written = n >= 0 ? static_cast<std::size_t>(n) : errno == EAGAIN ? 0 : ready;
  line.erase(line.begin(), line.begin() + static_cast<std::ptrdiff_t>(written));
  if (line.size() > k_max_unread_bytes) {
    // Drops from the first frame start past the excess, so the host resynchronises on a SYNC.
    const auto cut = std::find(line.begin() + static_cast<std::ptrdiff_t>(line.size() - k_max_unread_bytes),
                               line.end(), std::uint8_t{MCG_SYNC});
    line.erase(line.begin(), cut);
  }
}

}  // namespace

void refuse_unused_options(const std::vector<std::string>& options_given) {
  // What each mcg-sim option would mean on the emulated board, and why it does not apply.
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 10> k_refused{{
      {"--encoder", "the board measures speed with its encoder; mcg-serial stream writes the rpm it counts"},
      {"--window", "the rpm window of a capture is mcg-serial stream --window"},
      {"--counts-per-rev", "the board's encoder has 2048 counts/rev (mcg-protocol(7))"},
      {"--open-loop", "the board's mode register chooses open or closed loop (mcg-serial set mode)"},
      {"--clutch", "the clutch is the board's output (mcg-serial set clutch)"},
      {"--noise-i", "the board measures no current, only the encoder"},
      {"--noise-v-gen", "the board measures no generator voltage, only the encoder"},
      {"--adc", "the board measures no current, only the encoder"},
      {"--seed", "nothing on the emulated board is random"},
      {"--loop", "the board runs its own core on the registers mcg-serial load writes"},
  }};
  for (const auto& given : options_given) {
    for (const auto& [name, why] : k_refused) {
      if (given == name) fail("{}: not used with --board: {}", name, why);
    }
  }
}

void serve(const ServeOptions& options, Diagnostics& diag) {
  refuse_unused_options(options.options_given);
  BoardOptions board_options = options.board;
  board_options.model = model::load_model(options.configs, options.effects);
  link::PtyLink pty(options.link_path);
  EmulatedBoard board(board_options);
  const link::InterruptGuard guard;
  const link::EmulatedPortEntry entry(
      pty.link_path(),
      fmt::format("emulated board ({} pid {}, {})", diag.prefix(), ::getpid(), pty.slave_path()));
  diag.report(
      fmt::format("board at {} ({}); Ctrl-C ends", printable_name(pty.link_path()), pty.slave_path()));
  diag.stream().flush();

  using Clock = std::chrono::steady_clock;
  const double tick_s = 1e-3 / options.speed;  // wall-clock seconds per simulated tick
  const auto limit_ticks = static_cast<std::uint64_t>(std::llround(options.seconds * 1e3));
  auto start = Clock::now();
  std::uint64_t ticks = 0;
  std::vector<std::uint8_t> rx_pending;
  std::vector<std::uint8_t> tx_pending;
  std::uint8_t buf[4096];
  while (!link::InterruptGuard::interrupted() && (limit_ticks == 0 || ticks < limit_ticks)) {
    for (;;) {
      const ssize_t n = ::read(pty.fd(), buf, sizeof buf);
      if (n <= 0) break;
      rx_pending.insert(rx_pending.end(), buf, buf + n);
    }
    double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
    auto due = static_cast<std::uint64_t>(wall_s / tick_s);
    if (static_cast<double>(due - std::min(due, ticks)) * tick_s > k_max_lag_s) {
      start += std::chrono::duration_cast<Clock::duration>(
          std::chrono::duration<double>(static_cast<double>(due - ticks) * tick_s - k_max_lag_s));
      due = ticks + static_cast<std::uint64_t>(k_max_lag_s / tick_s);
    }
    if (limit_ticks != 0) due = std::min(due, limit_ticks);
    while (ticks < due) {
      if (!rx_pending.empty()) {
        const std::size_t taken = board.rx(rx_pending);
        rx_pending.erase(rx_pending.begin(), rx_pending.begin() + static_cast<std::ptrdiff_t>(taken));
      }
      board.tick();
      ++ticks;
      const std::size_t n = board.tx(buf);
      tx_pending.insert(tx_pending.end(), buf, buf + n);
    }
    write_frames(pty.fd(), tx_pending);
    wall_s = std::chrono::duration<double>(Clock::now() - start).count();
    const double wait_s = static_cast<double>(ticks + 1) * tick_s - wall_s;
    pollfd p{pty.fd(), POLLIN, 0};
    ::poll(&p, 1, poll_timeout_ms(wait_s));
  }
}

}  // namespace mcg::board
