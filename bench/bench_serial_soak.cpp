// Soak benchmark: stream at the protocol's full rate from the emulated board for 10 minutes
// (or --seconds) and count every sample received and lost. Not run by the test suite.
//
// The board (firmware core + plant, mcg-sim --board's serve()) runs in a child process behind a
// pseudo-terminal at 9600 baud in real time; this process is the host: the same Port, Session
// and StreamAssembler as mcg-serial stream.
#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "board/board.hpp"
#include "common/error.hpp"
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
      mcg::board::serve(o);
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
    auto port = mcg::link::open_port(link_path, 9600);
    mcg::link::Session session(*port);
    session.hello();
    const auto& stream = mcg::link::require_register("stream");
    session.write(mcg::link::require_register("clutch"), 1);
    session.write(mcg::link::require_register("duty"), 350);
    session.write(stream, 1);
    mcg::link::StreamAssembler assembler(4);
    const auto want_blocks = static_cast<std::uint64_t>(seconds / (MCG_STREAM_SAMPLES * MCG_STREAM_PERIOD_MS * 1e-3));
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
    session.write(stream, 0);
    const std::uint64_t received = assembler.blocks() * MCG_STREAM_SAMPLES;
    const auto& st = session.stats();
    std::fputs(fmt::format("soak: {} s of stream from the emulated board at 9600 baud, speed {}\n"
                           "samples received: {}\n"
                           "samples lost:     {}\n"
                           "damaged frames:   {} (noise bytes {})\n"
                           "achieved rate:    {:.2f} samples/s ({:.1f} B/s of the line's 960 B/s; nominal 250 samples/s)\n"
                           "longest gap between blocks: {:.1f} ms (nominal 64 ms)\n",
                           seconds, speed, received, assembler.lost_samples(), st.bad_crc + st.too_long + st.timeouts,
                           st.skipped_bytes, static_cast<double>(received) / wall_s,
                           static_cast<double>(assembler.blocks()) * (MCG_STREAM_PAYLOAD + MCG_FRAME_OVERHEAD) / wall_s,
                           longest_gap_s * 1e3)
                   .c_str(),
               stdout);
    status = assembler.lost_samples() == 0 ? 0 : 3;
  } catch (const mcg::Error& e) {
    std::fprintf(stderr, "bench_serial_soak: error: %s\n", e.what());
  }
  ::kill(board_pid, SIGTERM);
  ::waitpid(board_pid, nullptr, 0);
  ::rmdir(dir);
  return status;
}
