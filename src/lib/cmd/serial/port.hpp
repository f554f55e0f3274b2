// The port subcommands of mcg-serial: serve (hold the port for the other commands) and relay
// (a faulty line for tests).
#pragma once

#include "cmd/serial/link_command.hpp"
#include "link/relay.hpp"

namespace mcg::cmd {

/// Holds the port and serves the other mcg-serial commands on it until Ctrl-C or --seconds.
class SerialServe final : public SerialCommand {
 public:
  link::ServeOptions options;
  explicit SerialServe(link::LinkOptions& link)
      : SerialCommand(link, "serve", "hold the port and serve the other mcg-serial commands on it") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// Forwards -p PORT to a new pty with faults; its summary line is reported as "<tool> relay: ...".
class SerialRelay final : public SerialCommand {
 public:
  link::RelayOptions options;
  explicit SerialRelay(link::LinkOptions& link)
      : SerialCommand(link, "relay",
                      "test aid: forward -p PORT to a new pty, corrupting, dropping, delaying") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

}  // namespace mcg::cmd
