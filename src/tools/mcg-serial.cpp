// mcg-serial: registers, live capture, the RAM log and command sequences of the board.
#include <iostream>

#include "common/tool.hpp"
#include "link/console.hpp"
#include "link/relay.hpp"
#include "link/serial.hpp"

int main(int argc, char** argv) {
  CLI::App app{
      "Talks to the motor-clutch-generator board (or mcg-sim --board) over a serial line: registers in\n"
      "engineering units, live capture as CSV, the RAM log, command sequences. See man mcg-serial.",
      "mcg-serial"};
  app.require_subcommand(1);
  mcg::link::LinkOptions link;
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

  auto* list = app.add_subcommand("list", "list the serial ports with their descriptions");

  std::vector<std::string> get_names;
  auto* get = app.add_subcommand(
      "get",
      "print registers in engineering units, duty in % (all, as an INI [board] section, without NAME)");
  get->add_option("NAME", get_names, "register name");

  std::string set_name;
  std::string set_value;
  auto* set = app.add_subcommand("set", "write a register in engineering units and verify it");
  set->add_option("NAME", set_name, "register name")->required();
  set->add_option(
         "VALUE", set_value,
         "value: rpm, duty in % (CSV 0.25 = 25 %), gain, ms, clutch 1/2, or a name (mode: open p pi pid)")
      ->required();

  std::string load_path;
  auto* load =
      app.add_subcommand("load", "write every register of a [board] or [controller] INI and verify each");
  load->add_option("FILE", load_path, "INI file (mcg-design output, or mcg-serial get)")
      ->required()
      ->check(CLI::ExistingFile);

  mcg::link::StreamOptions stream_opt;
  auto* stream = app.add_subcommand(
      "stream", "write live samples as CSV (t, rpm, counts, duty, v, rpm_cmd, clutch, r_load) until done");
  auto* seconds = stream->add_option("--seconds", stream_opt.seconds, "capture this much stream time, s")
                      ->check(CLI::Range(0.002, 1e6));
  stream->add_option("--samples", stream_opt.samples, "capture this many 4 ms samples")
      ->check(CLI::Range(std::int64_t{1}, std::int64_t{1} << 40))
      ->excludes(seconds);
  stream->add_flag("--allow-loss", stream_opt.allow_loss, "exit 0 even when samples were lost");
  stream
      ->add_option("--window", stream_opt.window_s,
                   "rpm estimator window, s (a multiple of the 0.004 s sample)")
      ->check(CLI::Range(0.004, 1.0))
      ->capture_default_str();
  stream
      ->add_option("--config", stream_opt.rig.configs,
                   "the rig's INI (as mcg-sim's): supply_V turns duty into v (repeatable)")
      ->check(CLI::ExistingFile);
  stream
      ->add_option("--r-load", stream_opt.rig.r_load_ohm,
                   "resistor the load relay switches in, ohm (r_load when closed)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  stream
      ->add_option("--then", stream_opt.then,
                   "start the loaded sequence once the stream is on (it starts on a sample), or the "
                   "excitation the exc_* registers hold (t = 0 at its first tick)")
      ->check(CLI::IsMember({"play", "loop", "excite"}));
  stream
      ->add_option("--idle-timeout", stream_opt.idle_timeout_s, "no stream data for this long is an error, s")
      ->check(CLI::Range(0.05, 60.0))
      ->capture_default_str();
  bool reconnect = false;
  double reconnect_wait_s = 60.0;
  stream->add_flag("--reconnect", reconnect,
                   "when the port vanishes or the stream stops, wait for it and go on after a break row");
  stream->add_option("--reconnect-wait", reconnect_wait_s, "with --reconnect: wait this long at most, s")
      ->check(CLI::Range(0.1, 1e6))
      ->capture_default_str();

  mcg::link::DumpOptions dump_opt;
  auto* dump = app.add_subcommand("dump", "read the RAM log as CSV (t, rpm, counts)");
  dump->add_flag("--record", dump_opt.record, "start a recording first and wait until the log is full");
  dump->add_option("--interval", dump_opt.interval_ms, "with --record: log point spacing, ms")
      ->check(CLI::Range(1, 255));

  mcg::link::SendOptions send_opt;
  auto* send =
      app.add_subcommand("send", "load a command sequence (CSV: t and register columns) into the board");
  send->add_option("FILE", send_opt.path, "CSV file, - for stdin")->required();
  send->add_option("--then", send_opt.then, "start playback after loading")
      ->check(CLI::IsMember({"play", "loop"}));

  mcg::link::MonitorOptions monitor_opt;
  auto* monitor = app.add_subcommand("monitor", "show live values on one redrawn terminal line");
  monitor->add_option("--seconds", monitor_opt.seconds, "stop after this long, s (default: Ctrl-C)")
      ->check(CLI::Range(0.01, 1e6));

  mcg::link::ConsoleOptions console_opt;
  auto* console = app.add_subcommand(
      "console", "the board on a terminal screen: live speed, model and duty, registers, keys to drive it");
  console
      ->add_option("--config", console_opt.rig.configs,
                   "the rig's INI (as mcg-sim's): the model and supply_V")
      ->allow_extra_args(false);
  console->add_option("--r-load", console_opt.rig.r_load_ohm, "resistor the load relay switches in, ohm")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  console->add_option("--span", console_opt.span_s, "seconds of traces shown")
      ->check(CLI::Range(1.0, 600.0))
      ->capture_default_str();
  console->add_option("--seconds", console_opt.seconds, "stop after this long, s (default: q)")
      ->check(CLI::Range(0.01, 1e6));
  console->add_option("--log", console_opt.log_path,
                      "a timestamped session log to this file, from the start (L starts and stops one too)");

  mcg::link::ServeOptions serve_opt;
  auto* serve = app.add_subcommand("serve", "hold the port and serve the other mcg-serial commands on it");
  serve->add_option("--seconds", serve_opt.seconds, "stop after this long, s (default: Ctrl-C)")
      ->check(CLI::Range(0.01, 1e6));

  mcg::link::RelayOptions relay_opt;
  auto* relay =
      app.add_subcommand("relay", "test aid: forward -p PORT to a new pty, corrupting, dropping, delaying");
  relay->add_option("--link", relay_opt.link_path, "pseudo-terminal link to create for the tool")->required();
  relay->add_option("--corrupt", relay_opt.corrupt, "probability per byte of a flipped bit")
      ->check(CLI::Range(0.0, 1.0));
  relay->add_option("--drop", relay_opt.drop, "probability per byte of losing it")
      ->check(CLI::Range(0.0, 1.0));
  relay->add_option("--stall", relay_opt.stall, "probability per byte of a pause before it")
      ->check(CLI::Range(0.0, 1.0));
  relay->add_option("--stall-ms", relay_opt.stall_ms, "longest pause, ms")
      ->check(CLI::Range(0.0, 10000.0))
      ->capture_default_str();
  relay
      ->add_option("--cut-after", relay_opt.cut_after_s,
                   "close the line this long after the board's first byte, s")
      ->check(CLI::Range(0.001, 1e6));
  relay->add_option("--seconds", relay_opt.seconds, "end after this long, s")->check(CLI::Range(0.001, 1e6));
  relay->add_flag("!--clean-to-board", relay_opt.to_board, "faults only on bytes towards the tool");
  relay->add_option("--seed", relay_opt.seed, "seed of the faults")->capture_default_str();

  const auto need_port = [&] {
    if (link.port.empty()) throw CLI::RequiredError("-p,--port");
  };
  return mcg::tool_main_status(app, argc, argv, [&]() -> int {
    if (*list) {
      mcg::link::run_list(std::cout);
      return 0;
    }
    need_port();
    if (*get) mcg::link::run_get(link, get_names, std::cout);
    if (*set) mcg::link::run_set(link, set_name, set_value, std::cerr);
    if (*load) mcg::link::run_load(link, load_path, std::cout, std::cerr);
    if (*stream) {
      if (reconnect) stream_opt.reconnect_wait_s = reconnect_wait_s;
      return mcg::link::run_stream(link, stream_opt, std::cout, std::cerr);
    }
    if (*dump) mcg::link::run_dump(link, dump_opt, std::cout, std::cerr);
    if (*send) mcg::link::run_send(link, send_opt, std::cout);
    if (*monitor) mcg::link::run_monitor(link, monitor_opt, std::cout);
    if (*console) return mcg::link::run_console(link, console_opt);
    if (*serve) mcg::link::run_serve(link, serve_opt);
    if (*relay) {
      relay_opt.port = link.port;
      relay_opt.baud = link.baud;
      mcg::link::run_relay(relay_opt, std::cerr);
    }
    return 0;
  });
}
