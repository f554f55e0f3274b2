// mcg-serial serve and relay: their options and the link's functions on them.
#include "cmd/serial/port.hpp"

namespace mcg::cmd {

void SerialServe::define(CLI::App& app) {
  app.add_option("--seconds", options.seconds, "stop after this long, s (default: Ctrl-C)")
      ->check(CLI::Range(0.01, 1e6));
}

int SerialServe::run(Io& io) {
  link::run_serve(line(io), options);
  return 0;
}

void SerialRelay::define(CLI::App& app) {
  link::RelayOptions& o = options;
  app.add_option("--link", o.link_path, "pseudo-terminal link to create for the tool")->required();
  app.add_option("--corrupt", o.corrupt, "probability per byte of a flipped bit")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--drop", o.drop, "probability per byte of losing it")->check(CLI::Range(0.0, 1.0));
  app.add_option("--stall", o.stall, "probability per byte of a pause before it")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--stall-ms", o.stall_ms, "longest pause, ms")
      ->check(CLI::Range(0.0, 10000.0))
      ->capture_default_str();
  app.add_option("--cut-after", o.cut_after_s, "close the line this long after the board's first byte, s")
      ->check(CLI::Range(0.001, 1e6));
  app.add_option("--seconds", o.seconds, "end after this long, s")->check(CLI::Range(0.001, 1e6));
  app.add_flag("!--clean-to-board", o.to_board, "faults only on bytes towards the tool");
  app.add_option("--seed", o.seed, "seed of the faults")->capture_default_str();
}

int SerialRelay::run(Io& io) {
  const link::LinkOptions& l = line(io);
  options.port = l.port;
  options.baud = l.baud;
  // The summary line keeps the subcommand in its prefix: "<tool> relay: ...".
  Diagnostics relay(io.diag.stream(), io.diag.prefix() + " relay");
  link::run_relay(options, relay);
  return relay.status();
}

}  // namespace mcg::cmd
