// mcg-serial stream: live stream blocks to CSV, with loss accounting.
#include <chrono>
#include <cmath>
#include <ostream>

#include <fmt/format.h>

#include "common/error.hpp"     // mcg::fail
#include "config/ini.hpp"       // format_number
#include "link/connection.hpp"  // connect
#include "link/interrupt.hpp"   // InterruptGuard
#include "link/serial.hpp"
#include "link/stream_block.hpp"  // StreamAssembler
#include "mcg/version.hpp"      // k_version
#include "sim/encoder.hpp"      // format_rpm_estimator
#include "table/table.hpp"      // Writer

namespace mcg::link {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

int run_stream(const LinkOptions& link, const StreamOptions& options, std::ostream& out, std::ostream& err) {
  std::int64_t want = options.samples;
  if (options.seconds > 0.0) {
    want = static_cast<std::int64_t>(std::llround(options.seconds / (MCG_STREAM_PERIOD_MS * 1e-3)));
  }
  auto c = connect(link);
  Session& s = *c->session;
  const InterruptGuard guard;
  const std::string mode = format_value(require_register("mode"), s.read(require_register("mode")), 0);
  const std::int16_t clutch = s.read(require_register("clutch"));
  const std::int16_t load = s.read(require_register("load"));
  s.write(require_register("stream"), 1);

  table::Writer w(out);
  w.meta("source", fmt::format("mcg-serial {} stream", k_version));
  w.meta("board", c->board_text());
  w.meta("port", link.port);
  w.meta("sample_period", config::format_number(MCG_STREAM_PERIOD_MS * 1e-3));
  sim::CountEstimator est;
  est.window_s = options.window_ms * 1e-3;
  est.counts_per_rev = MCG_COUNTS_PER_REV;
  w.meta("rpm_estimator", sim::format_rpm_estimator(est));
  w.meta("encoder", "512 lines, x4 quadrature decoding = 2048 counts/rev");
  w.meta("timing",
         "counts over (t - 0.002, t]; rpm over the estimator window ending at t; duty and rpm_cmd as reported "
         "at each 32 ms block's last sample, held until the next");
  w.meta("mode", mode);
  w.meta("clutch", clutch != 0 ? "2" : "1");
  w.meta("load_relay", load != 0 ? "closed" : "open");
  w.header({"t", "rpm", "counts", "duty", "rpm_cmd"});
  w.finish();

  StreamAssembler assembler(options.window_ms / static_cast<int>(MCG_STREAM_PERIOD_MS));
  std::int64_t written = 0;
  auto last_block = Clock::now();
  std::string ended_by;
  try {
    while (want == 0 || written < want) {
      if (InterruptGuard::interrupted()) break;
      const auto f = s.receive(0.1);
      if (!f) {
        if (seconds_since(last_block) > options.idle_timeout_s) {
          ended_by = fmt::format("{}: no stream data for {} s", link.port, config::format_number(options.idle_timeout_s));
          break;
        }
        continue;
      }
      if (f->cmd != MCG_MSG_STREAM) continue;
      const double arrival_gap_s = seconds_since(last_block);
      last_block = Clock::now();
      if (!assembler.push(f->payload, arrival_gap_s)) continue;
      for (const StreamRow& r : assembler.rows()) {
        if (want != 0 && written >= want) break;
        w.row({r.t_s, r.rpm, r.counts, r.duty, r.rpm_cmd});
        ++written;
      }
      w.finish();
    }
  } catch (const PortVanished&) {
    w.finish();
    fail("{}: the port vanished after {} samples (they are on stdout)", link.port, written);
  }
  w.finish();
  if (ended_by.empty()) {
    try {
      s.write(require_register("stream"), 0);
    } catch (const Error&) {
      // The capture is complete; a board that does not confirm the stop changes nothing.
    }
  }
  if (!ended_by.empty()) fail("{} ({} samples captured are on stdout)", ended_by, written);
  const auto& st = s.stats();
  const std::uint64_t lost = assembler.lost_samples();
  if (lost > 0) {
    err << fmt::format(
        "mcg-serial: lost {} of {} samples ({} stream blocks; {} damaged frames, {} bytes of noise)\n", lost,
        static_cast<std::uint64_t>(written) + lost, lost / MCG_STREAM_SAMPLES, st.bad_crc + st.too_long + st.timeouts,
        st.skipped_bytes);
    if (!options.allow_loss) return k_exit_lost_samples;
  }
  return 0;
}

}  // namespace mcg::link
