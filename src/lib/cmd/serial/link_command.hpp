// What every mcg-serial subcommand shares: the port and its line, options of the tool itself.
#pragma once

#include <string>

#include "cmd/command.hpp"
#include "link/serial.hpp"

namespace mcg::cmd {

/// Adds the line's options (-p/--port, --baud, --timeout, --tries) to the tool's `app`.
void define_link(CLI::App& app, link::LinkOptions& link);

/// A subcommand of mcg-serial: the line of the tool's options, and its own.
class SerialCommand : public Command {
 public:
  SerialCommand(link::LinkOptions& link, std::string name, std::string help)
      : m_link(link), m_name(std::move(name)), m_help(std::move(help)) {}
  std::string name() const override { return m_name; }
  std::string help() const override { return m_help; }

 protected:
  /// The line, with the tool's name for provenance; a usage error (exit 2) without --port.
  const link::LinkOptions& line(const Io& io);

 private:
  link::LinkOptions& m_link;
  std::string m_name;
  std::string m_help;
};

}  // namespace mcg::cmd
