// main_of: a tool's commands defined, parsed and run through tool_main_status.
#include "cmd/command.hpp"

#include <iostream>

#include "common/demand.hpp"
#include "common/tool.hpp"

namespace mcg::cmd {

namespace {

int run_with(Command& command, Diagnostics& diag, const CLI::App& app) {
  Io io{std::cin, std::cout, diag, app.get_name()};
  const int status = command.run(io);
  return status != 0 ? status : diag.status();
}

}  // namespace

int main_of(CLI::App& app, int argc, char** argv, Diagnostics& diag, Command& command) {
  command.define(app);
  return tool_main_status(app, argc, argv, [&] { return run_with(command, diag, app); });
}

int main_of(CLI::App& app, int argc, char** argv, Diagnostics& diag, const std::vector<Command*>& commands) {
  app.require_subcommand(1);
  std::vector<CLI::App*> subs;
  for (Command* c : commands) {
    subs.push_back(app.add_subcommand(c->name(), c->help()));
    c->define(*subs.back());
  }
  return tool_main_status(app, argc, argv, [&] {
    for (std::size_t k = 0; k < subs.size(); ++k) {
      if (subs[k]->parsed()) return run_with(*commands[k], diag, app);
    }
    MCG_DEMAND(!"a subcommand was parsed");
    return 1;
  });
}

}  // namespace mcg::cmd
