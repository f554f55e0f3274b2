// The faulty line.
#include "link/relay.hpp"

#include <unistd.h>

#include <chrono>
#include <deque>
#include <ostream>
#include <random>
#include <vector>

#include <fmt/format.h>

#include "link/interrupt.hpp"  // InterruptGuard
#include "link/port.hpp"       // open_port, PortVanished
#include "link/pty.hpp"        // PtyLink

namespace mcg::link {

namespace {

using Clock = std::chrono::steady_clock;

struct Counts {
  std::uint64_t forwarded = 0;
  std::uint64_t corrupted = 0;
  std::uint64_t dropped = 0;
  std::uint64_t paused = 0;
};

/// One direction of the line: bytes with the time they may leave, in order.
class Direction {
 public:
  Direction(const RelayOptions& o, bool faulty) : m_o(o), m_faulty(faulty) {}

  void accept(std::span<const std::uint8_t> bytes, double now_s, std::mt19937_64& rng, Counts& counts) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (std::uint8_t b : bytes) {
      double at = std::max(m_tail_s, now_s);
      if (m_faulty) {
        if (u(rng) < m_o.drop) {
          ++counts.dropped;
          continue;
        }
        if (u(rng) < m_o.corrupt) {
          b = static_cast<std::uint8_t>(b ^ (1u << (rng() % 8u)));
          ++counts.corrupted;
        }
        if (u(rng) < m_o.stall) {
          at += u(rng) * m_o.stall_ms * 1e-3;
          ++counts.paused;
        }
      }
      m_tail_s = at;
      m_queue.emplace_back(at, b);
    }
  }

  /// The bytes due at `now_s`, removed from the queue.
  std::vector<std::uint8_t> due(double now_s) {
    std::vector<std::uint8_t> out;
    while (!m_queue.empty() && m_queue.front().first <= now_s) {
      out.push_back(m_queue.front().second);
      m_queue.pop_front();
    }
    return out;
  }

 private:
  const RelayOptions& m_o;
  bool m_faulty;
  double m_tail_s = 0.0;
  std::deque<std::pair<double, std::uint8_t>> m_queue;
};

}  // namespace

void run_relay(const RelayOptions& options, Diagnostics& diag) {
  auto board = open_port(options.port, options.baud);
  PtyLink link(options.link_path);
  const InterruptGuard guard;
  std::mt19937_64 rng(options.seed);
  Counts to_tool_counts;
  Counts to_board_counts;
  Direction to_tool(options, true);
  Direction to_board(options, options.to_board);
  const auto start = Clock::now();
  const auto now_s = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  double first_byte_s = -1.0;
  std::string ended = "interrupted";
  std::uint8_t buf[1024];
  for (;;) {
    if (InterruptGuard::interrupted()) break;
    if (options.seconds > 0.0 && now_s() >= options.seconds) {
      ended = "time is up";
      break;
    }
    if (options.cut_after_s > 0.0 && first_byte_s >= 0.0 && now_s() - first_byte_s >= options.cut_after_s) {
      ended = "line cut";
      break;
    }
    try {
      const std::size_t n = board->read_some(buf, 0.001);
      if (n > 0 && first_byte_s < 0.0) first_byte_s = now_s();
      to_tool.accept(std::span<const std::uint8_t>(buf, n), now_s(), rng, to_tool_counts);
      const ssize_t m = ::read(link.fd(), buf, sizeof buf);
      if (m > 0) to_board.accept(std::span<const std::uint8_t>(buf, static_cast<std::size_t>(m)), now_s(), rng, to_board_counts);
      const auto out_tool = to_tool.due(now_s());
      if (!out_tool.empty() && ::write(link.fd(), out_tool.data(), out_tool.size()) > 0) {
        to_tool_counts.forwarded += out_tool.size();
      }
      const auto out_board = to_board.due(now_s());
      if (!out_board.empty()) {
        board->write_all(out_board, 1.0);
        to_board_counts.forwarded += out_board.size();
      }
    } catch (const PortVanished&) {
      ended = "the board side vanished";
      break;
    }
  }
  link.close();
  diag.report(
      fmt::format("{}; to the tool {} bytes ({} corrupted, {} dropped, {} paused), to the board {} bytes "
                  "({} corrupted, {} dropped, {} paused)",
                  ended, to_tool_counts.forwarded, to_tool_counts.corrupted, to_tool_counts.dropped,
                  to_tool_counts.paused, to_board_counts.forwarded, to_board_counts.corrupted,
                  to_board_counts.dropped, to_board_counts.paused));
}

}  // namespace mcg::link
