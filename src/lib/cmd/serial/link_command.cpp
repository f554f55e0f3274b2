// mcg-serial's line options and the port every subcommand but list needs.
#include "cmd/serial/link_command.hpp"

namespace mcg::cmd {

void define_link(CLI::App& app, link::LinkOptions& link) {
  app.add_option("-p,--port", link.port, "serial port, e.g. /dev/ttyUSB0 or ./ttyMCG");
  app.add_option("--baud", link.baud, "line rate")
      ->check(CLI::IsMember({1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200}))
      ->capture_default_str();
  app.add_option("--timeout", link.timeout_s, "wait for each answer, s")
      ->check(CLI::Range(0.01, 10.0))
      ->capture_default_str();
  app.add_option("--tries", link.attempts, "attempts per request")
      ->check(CLI::Range(1, 20))
      ->capture_default_str();
}

const link::LinkOptions& SerialCommand::line(const Io& io) {
  if (m_link.port.empty()) throw CLI::RequiredError("-p,--port");
  m_link.tool = io.tool;
  return m_link;
}

}  // namespace mcg::cmd
