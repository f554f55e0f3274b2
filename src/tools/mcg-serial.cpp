// mcg-serial: registers, live capture, the RAM log and command sequences of the board.
#include <iostream>

#include "cmd/serial/capture.hpp"
#include "cmd/serial/port.hpp"
#include "cmd/serial/registers.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "Talks to the motor-clutch-generator board (or mcg-sim --board) over a serial line: registers in\n"
      "engineering units, live capture as CSV, the RAM log, command sequences. See man mcg-serial.",
      "mcg-serial"};
  mcg::Diagnostics diag(std::cerr, app.get_name());
  mcg::link::LinkOptions link;
  mcg::cmd::define_link(app, link);
  mcg::cmd::SerialList list(link);
  mcg::cmd::SerialGet get(link);
  mcg::cmd::SerialSet set(link);
  mcg::cmd::SerialLoad load(link);
  mcg::cmd::SerialStream stream(link);
  mcg::cmd::SerialDump dump(link);
  mcg::cmd::SerialSend send(link);
  mcg::cmd::SerialMonitor monitor(link);
  mcg::cmd::SerialConsole console(link);
  mcg::cmd::SerialServe serve(link);
  mcg::cmd::SerialRelay relay(link);
  return mcg::cmd::main_of(
      app, argc, argv, diag,
      {&list, &get, &set, &load, &stream, &dump, &send, &monitor, &console, &serve, &relay});
}
