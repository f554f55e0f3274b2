// tool_main: the shared entry of every mcg executable.
#include "common/tool.hpp"
#include "common/edit_distance.hpp"

#include "common/error.hpp"
#include "common/quote.hpp"
#include "mcg/version.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace mcg {

namespace {

void print_error(const std::string& tool, const std::string& message) {
  std::fflush(stdout);
  std::cout.flush();
  std::fputs(fmt::format("{}: error: {}\n", tool, message).c_str(), stderr);
}

/// The first argument that `app` or a subcommand it ran could not place, with that (sub)command.
std::optional<std::pair<const CLI::App*, std::string>> first_extra(const CLI::App& app) {
  if (const auto left = app.remaining(false); !left.empty()) return std::pair{&app, left.front()};
  for (const CLI::App* sub : app.get_subcommands()) {
    if (auto found = first_extra(*sub)) return found;
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> nearest_name(std::string_view word, const std::vector<std::string>& names) {
  std::optional<std::string> best;
  std::size_t best_distance = 3;
  for (const auto& name : names) {
    const std::size_t d = edit_distance(word, name);
    if (d < best_distance && d < name.size()) {
      best = name;
      best_distance = d;
    }
  }
  return best;
}

std::string usage_message(const CLI::App& app, const CLI::ParseError& e) {
  const auto extra = first_extra(app);
  if (!extra) return e.what();
  const auto& [where, arg] = *extra;
  if (arg.size() > 1 && arg.front() == '-' && !std::isdigit(static_cast<unsigned char>(arg[1])) &&
      arg[1] != '.') {
    const std::string option = arg.substr(0, arg.find('='));
    std::vector<std::string> names;
    for (const CLI::Option* o : where->get_options()) {
      for (const auto& n : o->get_lnames()) names.push_back("--" + n);
    }
    const auto near = nearest_name(option, names);
    return fmt::format("unknown option {}{}", quote(option),
                       near ? fmt::format(": did you mean {}?", quote(*near)) : "");
  }
  const auto subs = where->get_subcommands([](const CLI::App*) { return true; });
  if (!subs.empty() && where->get_subcommands().empty()) {
    std::vector<std::string> names;
    for (const CLI::App* sub : subs) names.push_back(sub->get_name());
    const auto near = nearest_name(arg, names);
    if (near) return fmt::format("unknown subcommand {}: did you mean {}?", quote(arg), quote(*near));
    std::string all;
    for (const auto& n : names) all += (all.empty() ? "" : ", ") + n;
    return fmt::format("unknown subcommand {}: not one of {}", quote(arg), all);
  }
  return fmt::format("unexpected argument {}", quote(arg));
}

int tool_main_status(CLI::App& app, int argc, char** argv, const std::function<int()>& run) {
  std::signal(SIGPIPE, SIG_IGN);
  std::ios::sync_with_stdio(false);
  const std::string tool = app.get_name();
  app.set_version_flag("--version", fmt::format("{} {}", tool, k_version));
  // --help and --version are ParseErrors of status 0: CLI11 prints them. Every other one is
  // a usage error, named here.
  const auto usage_error = [&app, &tool](const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    const std::string message = usage_message(app, e);
    print_error(tool, fmt::format("{} (see {} --help)", printable(message, message.size()), tool));
    return k_usage_status;
  };
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return usage_error(e);
  }
  try {
    const int status = run();
    std::cout.flush();
    if (!std::cout) {
      if (errno == EPIPE) return 0;
      print_error(tool, fmt::format("writing <stdout>: {}", std::strerror(errno)));
      return 1;
    }
    return status;
  } catch (const BrokenPipe&) {
    return 0;
  } catch (const Error& e) {
    print_error(tool, e.what());
    return 1;
  } catch (const CLI::ParseError& e) {
    return usage_error(e);
  }
}

int tool_main(CLI::App& app, int argc, char** argv, const std::function<void()>& run) {
  return tool_main_status(app, argc, argv, [&run] {
    run();
    return 0;
  });
}

std::string input_name(const std::string& path) { return path == "-" ? "<stdin>" : printable_name(path); }

std::istream& open_input(const std::string& path) {
  if (path == "-") return std::cin;
  static std::map<std::string, std::unique_ptr<std::ifstream>> open_files;
  auto file = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!*file) fail("{}: cannot open: {}", path, std::strerror(errno));
  auto& slot = open_files[path];
  slot = std::move(file);
  return *slot;
}

bool stderr_is_terminal() { return ::isatty(STDERR_FILENO) == 1; }

}  // namespace mcg
