// mcg-serial stream, dump, monitor and console: their options and the link's functions on them.
#include "cmd/serial/capture.hpp"

#include <cstdint>

namespace mcg::cmd {

void SerialStream::define(CLI::App& app) {
  link::StreamOptions& o = options;
  auto* seconds = app.add_option("--seconds", o.seconds, "capture this much stream time, s")
                      ->check(CLI::Range(0.002, 1e6));
  app.add_option("--samples", o.samples, "capture this many 4 ms samples")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 40))
      ->excludes(seconds);
  app.add_flag("--allow-loss", o.allow_loss, "exit 0 even when samples were lost");
  app.add_option("--window", o.window_s, "rpm estimator window, s (a multiple of the 0.004 s sample)")
      ->check(CLI::Range(0.004, 1.0))
      ->capture_default_str();
  app.add_option("--config", o.rig.configs,
                 "the rig's INI (as mcg-sim's): supply_V turns duty into v (repeatable)")
      ->check(CLI::ExistingFile);
  app.add_option("--r-load", o.rig.r_load_ohm,
                 "resistor the load relay switches in, ohm (r_load when closed)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  app.add_option("--then", o.then,
                 "start the loaded sequence once the stream is on (it starts on a sample), or the "
                 "excitation the exc_* registers hold (t = 0 at its first tick)")
      ->check(CLI::IsMember({"play", "loop", "excite"}));
  app.add_option("--idle-timeout", o.idle_timeout_s, "no stream data for this long is an error, s")
      ->check(CLI::Range(0.05, 60.0))
      ->capture_default_str();
  app.add_flag("--reconnect", reconnect,
               "when the port vanishes or the stream stops, wait for it and go on after a break row");
  app.add_option("--reconnect-wait", reconnect_wait_s, "with --reconnect: wait this long at most, s")
      ->check(CLI::Range(0.1, 1e6))
      ->capture_default_str();
}

int SerialStream::run(Io& io) {
  const link::LinkOptions& l = line(io);
  if (reconnect) options.reconnect_wait_s = reconnect_wait_s;
  return link::run_stream(l, options, io.out, io.diag);
}

void SerialDump::define(CLI::App& app) {
  app.add_flag("--record", options.record, "start a recording first and wait until the log is full");
  app.add_option("--interval", options.interval_ms, "with --record: log point spacing, ms")
      ->check(CLI::Range(1, 255));
}

int SerialDump::run(Io& io) {
  link::run_dump(line(io), options, io.out, io.diag);
  return 0;
}

void SerialMonitor::define(CLI::App& app) {
  app.add_option("--seconds", options.seconds, "stop after this long, s (default: Ctrl-C)")
      ->check(CLI::Range(0.01, 1e6));
}

int SerialMonitor::run(Io& io) {
  link::run_monitor(line(io), options, io.out);
  return 0;
}

void SerialConsole::define(CLI::App& app) {
  link::ConsoleOptions& o = options;
  app.add_option("--config", o.rig.configs, "the rig's INI (as mcg-sim's): the model and supply_V")
      ->allow_extra_args(false);
  app.add_option("--r-load", o.rig.r_load_ohm, "resistor the load relay switches in, ohm")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  app.add_option("--span", o.span_s, "seconds of traces shown")
      ->check(CLI::Range(1.0, 600.0))
      ->capture_default_str();
  app.add_option("--seconds", o.seconds, "stop after this long, s (default: q)")
      ->check(CLI::Range(0.01, 1e6));
  app.add_option("--log", o.log_path,
                 "a timestamped session log to this file, from the start (L starts and stops one too)");
}

int SerialConsole::run(Io& io) { return link::run_console(line(io), options); }

}  // namespace mcg::cmd
