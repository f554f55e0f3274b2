// mcg-serial list, get, set, load and send: their options and the link's functions on them.
#include "cmd/serial/registers.hpp"

namespace mcg::cmd {

int SerialList::run(Io& io) {
  link::run_list(io.out);
  return 0;
}

void SerialGet::define(CLI::App& app) { app.add_option("NAME", names, "register name"); }

int SerialGet::run(Io& io) {
  link::run_get(line(io), names, io.out);
  return 0;
}

void SerialSet::define(CLI::App& app) {
  app.add_option("NAME", register_name, "register name")->required();
  app.add_option(
         "VALUE", value,
         "value: rpm, duty in % (CSV 0.25 = 25 %), gain, ms, clutch 1/2, or a name (mode: open p pi pid)")
      ->required();
}

int SerialSet::run(Io& io) {
  link::run_set(line(io), register_name, value, io.diag);
  return 0;
}

void SerialLoad::define(CLI::App& app) {
  app.add_option("FILE", path, "INI file (mcg-design output, or mcg-serial get)")
      ->required()
      ->check(CLI::ExistingFile);
}

int SerialLoad::run(Io& io) {
  link::run_load(line(io), path, io.out, io.diag);
  return 0;
}

void SerialSend::define(CLI::App& app) {
  app.add_option("FILE", options.path, "CSV file, - for stdin")->required();
  app.add_option("--then", options.then, "start playback after loading")
      ->check(CLI::IsMember({"play", "loop"}));
}

int SerialSend::run(Io& io) {
  link::run_send(line(io), options, io.out);
  return 0;
}

}  // namespace mcg::cmd
