// Soak benchmark: stream at the protocol's full rate from the emulated board for 10 minutes
// (or --seconds) while another client writes a register every second through the port's owner,
// and count every sample received and lost and every write answered. Not run by the test suite.
//
// The board (firmware core + plant, mcg-sim --board's serve()) runs in a child process behind a
// pseudo-terminal at 9600 baud in real time; this process is the host: the same PortOwner,
// Session and StreamAssembler as mcg-serial stream, and a second client on the control socket
// as another mcg-serial set would be.
#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <sstream>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "board/board.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "link/owner.hpp"
#include "link/port.hpp"
#include "link/registers.hpp"
#include "link/session.hpp"
#include "link/stream_block.hpp"
#include "mcg_protocol.h"

int main(int argc, char** argv) {
  CLI::App app{"Streams from the emulated board and reports samples received, lost and the rate.", "bench_serial_soak"};
  double seconds = 600.0;
  double speed = 1.0;
  app.add_option("--seconds", seconds, "stream time, s")->check(CLI::Range(1.0, 1e6))->capture_default_str();
  app.add_option("--speed", speed, "board speed, simulated s per wall s")->check(CLI::Range(0.1, 10.0))->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  char dir_template[] = "/tmp/mcg-soak-XXXXXX";
  const char* dir = ::mkdtemp(dir_template);
  if (dir == nullptr) {
    std::perror("mkdtemp");
    return 1;
  }
  const std::string link_path = std::string(dir) + "/ttyMCG";
  const pid_t board_pid = ::fork();
  if (board_pid == 0) {
    mcg::board::ServeOptions o;
    o.link_path = link_path;
    o.speed = speed;
    o.seconds = seconds * speed + 30.0;
    try {
      std::ostringstream announce;  // the link's path is known here
      mcg::Diagnostics diag(announce, "board");
      mcg::board::serve(o, diag);
    } catch (const mcg::Error& e) {
      std::fprintf(stderr, "board: %s\n", e.what());
      ::_exit(1);
    }
    ::_exit(0);
  }
  int status = 1;
  try {
    for (int i = 0; i < 100 && ::access(link_path.c_str(), F_OK) != 0; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    ::setenv("XDG_RUNTIME_DIR", dir, 1);
    mcg::link::PortOwner owner(mcg::link::open_port(link_path, 9600));
    auto port = owner.local_client();
    mcg::link::Session session(*port);
    session.hello();
    const auto& stream = mcg::link::require_register("stream");
    session.write(mcg::link::require_register("clutch"), 1);
    session.write(mcg::link::require_register("duty"), 350);
    session.write(stream, 1);
    mcg::link::StreamAssembler assembler(4);
    const auto want_blocks = static_cast<std::uint64_t>(seconds / (MCG_STREAM_SAMPLES * MCG_STREAM_PERIOD_MS * 1e-3));
    // The other client: once a second, connects through the owner, writes rpm_cmd, checks the
    // value the board answers it holds.
    std::atomic<bool> done{false};
    std::atomic<std::uint64_t> writes{0};
    std::atomic<std::uint64_t> answered{0};
    std::string write_error;
    std::thread writer([&] {
      const auto& rpm_cmd = mcg::link::require_register("rpm_cmd");
      auto next = std::chrono::steady_clock::now();
      while (!done) {
        next += std::chrono::seconds(1);
        std::this_thread::sleep_until(next);
        const auto value = static_cast<std::int16_t>(300 + 100 * static_cast<int>(writes % 3));
        ++writes;
        try {
          auto client = mcg::link::connect_owner(link_path);
          if (!client) mcg::fail("no owner listens");
          mcg::link::SessionOptions so;
          so.reply_timeout_s = 1.0;
          mcg::link::Session other(*client, so);
          other.hello();
          if (other.write(rpm_cmd, value) == value) ++answered;
        } catch (const mcg::Error& e) {
          write_error = e.what();
        }
      }
    });
    const auto start = std::chrono::steady_clock::now();
    auto last = start;
    double longest_gap_s = 0.0;
    while (assembler.blocks() + assembler.lost_samples() / MCG_STREAM_SAMPLES < want_blocks) {
      const auto f = session.receive(1.0);
      const auto now = std::chrono::steady_clock::now();
      const double gap_s = std::chrono::duration<double>(now - last).count();
      if (!f) {
        if (gap_s > 2.0) mcg::fail("no stream block for {} s", gap_s);
        continue;
      }
      if (f->cmd != MCG_MSG_STREAM) continue;
      assembler.push(f->payload, gap_s);
      if (assembler.blocks() > 1) longest_gap_s = std::max(longest_gap_s, gap_s);
      last = now;
    }
    const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    done = true;
    writer.join();
    session.write(stream, 0);
    const std::uint64_t received = assembler.blocks() * MCG_STREAM_SAMPLES;
    const auto& st = session.stats();
    std::fputs(fmt::format("soak: {} s of stream from the emulated board at 9600 baud, speed {}\n"
                           "samples received: {}\n"
                           "samples lost:     {}\n"
                           "damaged frames:   {} (noise bytes {})\n"
                           "achieved rate:    {:.2f} samples/s ({:.1f} B/s of the line's 960 B/s; nominal 250 samples/s)\n"
                           "longest gap between blocks: {:.1f} ms (nominal 64 ms)\n"
                           "register writes by another client: {}, answered {}{}\n",
                           seconds, speed, received, assembler.lost_samples(), st.bad_crc + st.too_long + st.timeouts,
                           st.skipped_bytes, static_cast<double>(received) / wall_s,
                           static_cast<double>(assembler.blocks()) * (MCG_STREAM_PAYLOAD + MCG_FRAME_OVERHEAD) / wall_s,
                           longest_gap_s * 1e3, writes.load(), answered.load(),
                           write_error.empty() ? "" : " (last error: " + write_error + ")")
                   .c_str(),
               stdout);
    status = assembler.lost_samples() == 0 && answered == writes ? 0 : 3;
  } catch (const mcg::Error& e) {
    std::fprintf(stderr, "bench_serial_soak: error: %s\n", e.what());
  }
  ::kill(board_pid, SIGTERM);
  ::waitpid(board_pid, nullptr, 0);
  ::rmdir(dir);
  return status;
}
