// mcg-serial stream: live stream blocks to CSV, with loss accounting.
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <ostream>

#include "common/error.hpp"  // mcg::fail
#include "common/quote.hpp"
#include "config/ini.hpp"         // format_number
#include "link/capture_meta.hpp"  // load_rig, board_config
#include "link/connection.hpp"    // connect
#include "link/interrupt.hpp"     // InterruptGuard
#include "link/serial.hpp"
#include "link/stream_block.hpp"             // StreamAssembler
#include "mcg/version.hpp"                   // k_version
#include "measurement/board_excitation.hpp"  // format_board_excitation
#include "measurement/measurement.hpp"       // CountEstimator, format_rpm_estimator
#include "model/model.hpp"                   // model_from_ini, k_open_circuit
#include "table/table.hpp"                   // Writer

namespace mcg::link {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Starts the excitation the exc_* registers hold, with the stream off so that the board turns it on
/// with the first level (t = 0 is the excitation's start); returns its description in the column's
/// units: "prbs column=duty order=9 clock=0.003 amp=0.2 bias=0.4 periods=2" (duty as a fraction, as
/// mcg-csv's duty column; rpm_cmd in rpm; the clock, the hold or a chirp's update in s, its
/// frequencies in Hz and its sweep in s: "chirp column=duty f0=0.1 f1=10 sweep=10 update=0.001 ...").
std::string start_excitation(Connection& c) {
  const auto raw = [&](std::string_view name) { return c.session->read(require_register(name)); };
  const std::int16_t kind = raw("exc_kind");
  if (kind == MCG_EXC_NONE) fail("--then excite: exc_kind is none on the board (set exc_kind first)");
  if (raw("stream") != 0) fail("--then excite: the stream is already on (another capture?)");
  const bool rpm = raw("mode") != MCG_MODE_OPEN;
  const double scale = rpm ? 1.0 : 1e-3;
  const double clock_s = raw("exc_div") * 1e-3;
  measurement::BoardExcitation e;
  e.column = rpm ? "rpm_cmd" : "duty";
  if (kind == MCG_EXC_PRBS) {
    e.kind = "prbs";
    e.values = {{"order", raw("exc_order")}, {"clock", clock_s}};
  } else if (kind == MCG_EXC_CHIRP) {
    e.kind = "chirp";
    e.values = {{"f0", raw("exc_f0") / 100.0},
                {"f1", raw("exc_f1") / 100.0},
                {"sweep", raw("exc_sweep")},
                {"update", clock_s}};
  } else {
    e.kind = "staircase";
    e.values = {{"steps", raw("exc_steps")}, {"hold", clock_s}};
  }
  e.values.emplace_back("amp", raw("exc_amp") * scale);
  e.values.emplace_back("bias", raw("exc_offset") * scale);
  e.values.emplace_back("periods", raw("exc_periods"));
  const std::string text = measurement::format_board_excitation(e);
  c.session->write(require_register("exc_run"), 1);
  return text;
}

}  // namespace

void write_stream_header(table::Writer& w, const Connection& c, const LinkOptions& link, int window_samples,
                         const Rig& rig, const std::vector<std::pair<std::string, std::string>>& config) {
  constexpr double k_sample_s = MCG_STREAM_PERIOD_MS * 1e-3;
  w.meta("source", fmt::format("{} {} stream", link.tool, k_version));
  w.meta("board", c.board_text());
  w.meta("port", printable_name(link.port));
  w.meta("sample_period", config::format_number(k_sample_s));
  measurement::CountEstimator est;
  est.window_s = window_samples * k_sample_s;
  est.counts_per_rev = MCG_COUNTS_PER_REV;
  w.meta("rpm_estimator", measurement::format_rpm_estimator(est));
  w.meta("encoder", k_encoder_text);
  w.meta(
      "timing",
      "duty, v, clutch, r_load, rpm_cmd of row n act over [t(n), t(n+1)) (duty: the mean over the "
      "sample's 1 ms ticks); counts over (t - sample_period, t], rpm over the estimator window ending at t; "
      "speed signed with the direction of the last non-zero drive");
  write_rig_meta(w, rig, config);
  w.header({"t", "rpm", "counts", "duty", "v", "rpm_cmd", "clutch", "r_load"});
  w.finish();
}

void write_stream_row(table::Writer& w, const StreamRow& r, const Rig& rig) {
  const double r_load = std::isnan(r.load) ? r.load : r.load != 0.0 ? rig.r_load_ohm : model::k_open_circuit;
  w.row({r.t_s, r.rpm, r.counts, r.duty, r.duty * rig.supply_V, r.rpm_cmd, r.clutch, r_load});
}

int run_stream(const LinkOptions& link, const StreamOptions& options, std::ostream& out, Diagnostics& diag) {
  constexpr double k_sample_s = MCG_STREAM_PERIOD_MS * 1e-3;
  const auto window_samples = static_cast<int>(std::llround(options.window_s / k_sample_s));
  if (window_samples < 1 || std::abs(window_samples * k_sample_s - options.window_s) > 1e-9) {
    fail("--window: {} s is not a multiple of the {} s sample period",
         config::format_number(options.window_s), config::format_number(k_sample_s));
  }
  std::int64_t want = options.samples;
  if (options.seconds > 0.0) want = static_cast<std::int64_t>(std::llround(options.seconds / k_sample_s));
  const Rig rig = load_rig(options.rig);
  auto c = connect(link, Hold::Serve);
  const InterruptGuard guard;
  const std::vector<std::pair<std::string, std::string>> config = board_config(*c);
  const RegisterInfo& stream = require_register("stream");
  std::string excitation;
  if (options.then.empty()) {
    c->session->write(stream, 1);
  } else if (options.then == "excite") {
    excitation = start_excitation(*c);
    c->session->write(stream, 1);
  } else {
    // A sequence that turns the stream on in its first entry starts the capture on its own first
    // tick (t = 0 there). Writing 1 after it changes nothing on the board (on stays on), turns on
    // a sequence's stream that does not, and tells a port owner this client reads the stream.
    const RegisterInfo& state = require_register("seq_state");
    c->session->write(state, static_cast<std::int16_t>(parse_value(state, options.then, "--then")));
    c->session->write(stream, 1);
  }

  table::Writer w(out);
  if (!excitation.empty()) {
    w.meta("excitation", excitation);
    w.meta("t0", "the excitation's first tick (the board turned the stream on with its first level)");
  }
  write_stream_header(w, *c, link, window_samples, rig, config);

  StreamAssembler assembler(window_samples);
  std::int64_t written = 0;
  auto last_block = Clock::now();
  auto idle_from = last_block;  // the last block, or the moment the stream came back
  std::string ended_by;
  DecoderStats before_reconnect;  // the line's damage over the connections already closed
  // --reconnect: the port back (or the board answering again), the stream on again; false
  // when the wait ran out or a signal came first.
  const auto come_back = [&](std::string_view why, bool vanished) {
    const auto lost_at = Clock::now();
    bool back = false;
    while (!back && seconds_since(lost_at) < options.reconnect_wait_s && !InterruptGuard::interrupted()) {
      try {
        if (vanished) {
          if (c) {
            const auto& st = c->session->stats();
            before_reconnect.bad_crc += st.bad_crc;
            before_reconnect.too_long += st.too_long;
            before_reconnect.timeouts += st.timeouts;
            before_reconnect.skipped_bytes += st.skipped_bytes;
            c.reset();
          }
          c = connect(link, Hold::Serve);
        }
        c->session->write(stream, 1);
        back = true;
      } catch (const PortVanished&) {
        vanished = true;
        ::usleep(200000);
      } catch (const Error&) {
        if (vanished) c.reset();
        ::usleep(200000);  // not back yet
      }
    }
    if (!back) return false;
    const double silence_s = seconds_since(last_block);
    assembler.restart();
    diag.note(fmt::format("{}: {}; back after {} s, the gap is a row of nan in the capture", link.port, why,
                          config::format_number(std::round(silence_s * 10.0) / 10.0)));
    idle_from = Clock::now();
    return true;
  };
  for (;;) {
    try {
      while (want == 0 || written < want) {
        if (InterruptGuard::interrupted()) break;
        const auto f = c->session->receive(0.1);
        if (!f) {
          if (seconds_since(idle_from) > options.idle_timeout_s) {
            ended_by = fmt::format("{}: no stream data for {} s", link.port,
                                   config::format_number(options.idle_timeout_s));
            break;
          }
          continue;
        }
        if (f->cmd != MCG_MSG_STREAM) continue;
        const double arrival_gap_s = seconds_since(last_block);
        last_block = Clock::now();
        idle_from = last_block;
        if (!assembler.push(f->payload, arrival_gap_s)) continue;
        for (const StreamRow& r : assembler.rows()) {
          if (want != 0 && written >= want) break;
          write_stream_row(w, r, rig);
          ++written;
        }
        w.finish();
      }
    } catch (const PortVanished&) {
      w.finish();
      if (options.reconnect_wait_s > 0.0 && come_back("the port vanished", true)) continue;
      if (!c)
        fail("{}: the port vanished and did not come back within {} s ({} samples captured are on stdout)",
             link.port, config::format_number(options.reconnect_wait_s), written);
      fail("{}: the port vanished after {} samples (they are on stdout)", link.port, written);
    }
    if (!ended_by.empty() && options.reconnect_wait_s > 0.0 && !InterruptGuard::interrupted()) {
      // A board that reset turns its stream off; the port stays: ask it again.
      ended_by.clear();
      if (come_back("the stream stopped", false)) continue;
      ended_by = fmt::format("{}: no stream data, and the board did not come back within {} s", link.port,
                             config::format_number(options.reconnect_wait_s));
      break;
    }
    break;
  }
  w.finish();
  if (ended_by.empty() && c) {
    try {
      c->session->write(require_register("stream"), 0);
    } catch (const Error&) {
      // The capture is complete; a board that does not confirm the stop changes nothing.
    }
  }
  if (!ended_by.empty()) fail("{} ({} samples captured are on stdout)", ended_by, written);
  if (assembler.breaks() > 0) {
    diag.note(fmt::format("{} break{} in the stream (a row of nan each)", assembler.breaks(),
                          assembler.breaks() == 1 ? "" : "s"));
  }
  DecoderStats st = before_reconnect;
  if (c) {
    st.bad_crc += c->session->stats().bad_crc;
    st.too_long += c->session->stats().too_long;
    st.timeouts += c->session->stats().timeouts;
    st.skipped_bytes += c->session->stats().skipped_bytes;
  }
  const std::uint64_t lost = assembler.lost_samples();
  if (lost > 0) {
    diag.report(fmt::format("lost {} of {} samples ({} stream blocks; {} damaged frames, {} bytes of noise)",
                            lost, static_cast<std::uint64_t>(written), lost / MCG_STREAM_SAMPLES,
                            st.bad_crc + st.too_long + st.timeouts, st.skipped_bytes));
    if (!options.allow_loss) return k_exit_lost_samples;
  }
  return 0;
}

}  // namespace mcg::link
