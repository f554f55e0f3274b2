// The capture subcommands of mcg-serial: stream (live samples as CSV), dump (the RAM log),
// monitor (one redrawn line) and console (the board on a terminal screen).
#pragma once

#include "cmd/serial/link_command.hpp"
#include "link/console.hpp"

namespace mcg::cmd {

/// Live samples as CSV until done; lost samples are reported and, without --allow-loss, end
/// with link::k_exit_lost_samples.
class SerialStream final : public SerialCommand {
 public:
  link::StreamOptions options;
  bool reconnect = false;
  double reconnect_wait_s = 60.0;  ///< with --reconnect: the longest wait for the port
  explicit SerialStream(link::LinkOptions& link)
      : SerialCommand(link, "stream",
                      "write live samples as CSV (t, rpm, counts, duty, v, rpm_cmd, clutch, r_load) until "
                      "done") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// The RAM log as CSV, after a recording with --record.
class SerialDump final : public SerialCommand {
 public:
  link::DumpOptions options;
  explicit SerialDump(link::LinkOptions& link)
      : SerialCommand(link, "dump", "read the RAM log as CSV (t, rpm, counts)") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// Live values on one redrawn terminal line.
class SerialMonitor final : public SerialCommand {
 public:
  link::MonitorOptions options;
  explicit SerialMonitor(link::LinkOptions& link)
      : SerialCommand(link, "monitor", "show live values on one redrawn terminal line") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// The board on a terminal screen, serving the other subcommands while it runs.
class SerialConsole final : public SerialCommand {
 public:
  link::ConsoleOptions options;
  explicit SerialConsole(link::LinkOptions& link)
      : SerialCommand(link, "console",
                      "the board on a terminal screen: live speed, model and duty, registers, keys to drive "
                      "it") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

}  // namespace mcg::cmd
