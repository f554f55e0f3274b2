// The register subcommands of mcg-serial: list (the ports), get, set, load and send (a command
// sequence into the board's RAM).
#pragma once

#include <string>
#include <vector>

#include "cmd/serial/link_command.hpp"

namespace mcg::cmd {

/// Every serial port with its description, then the emulated boards (link::run_list).
class SerialList final : public SerialCommand {
 public:
  explicit SerialList(link::LinkOptions& link)
      : SerialCommand(link, "list", "list the serial ports with their descriptions") {}
  void define(CLI::App&) override {}
  int run(Io& io) override;
};

/// Registers in engineering units; all of them as an INI [board] section without names.
class SerialGet final : public SerialCommand {
 public:
  std::vector<std::string> names;
  explicit SerialGet(link::LinkOptions& link)
      : SerialCommand(link, "get",
                      "print registers in engineering units, duty in % (all, as an INI [board] section, "
                      "without NAME)") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// One register written in engineering units and read back; a rounded value is a note.
class SerialSet final : public SerialCommand {
 public:
  std::string register_name;
  std::string value;
  explicit SerialSet(link::LinkOptions& link)
      : SerialCommand(link, "set", "write a register in engineering units and verify it") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// Every register of a [board] or [controller] INI written and verified; the board's [board].
class SerialLoad final : public SerialCommand {
 public:
  std::string path;
  explicit SerialLoad(link::LinkOptions& link)
      : SerialCommand(link, "load", "write every register of a [board] or [controller] INI and verify each") {
  }
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

/// A table of register values over time loaded as the board's command sequence.
class SerialSend final : public SerialCommand {
 public:
  link::SendOptions options;
  explicit SerialSend(link::LinkOptions& link)
      : SerialCommand(link, "send", "load a command sequence (CSV: t and register columns) into the board") {}
  void define(CLI::App& app) override;
  int run(Io& io) override;
};

}  // namespace mcg::cmd
