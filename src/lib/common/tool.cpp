// tool_main: the shared entry of every mcg executable.
#include "common/tool.hpp"

#include "common/error.hpp"
#include "mcg/version.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>

namespace mcg {

namespace {

void print_error(const std::string& tool, const std::string& message) {
  std::fflush(stdout);
  std::cout.flush();
  std::fputs(fmt::format("{}: error: {}\n", tool, message).c_str(), stderr);
}

}  // namespace

int tool_main_status(CLI::App& app, int argc, char** argv, const std::function<int()>& run) {
  std::signal(SIGPIPE, SIG_IGN);
  std::ios::sync_with_stdio(false);
  const std::string tool = app.get_name();
  app.set_version_flag("--version", fmt::format("{} {}", tool, k_version));
  app.failure_message([tool](const CLI::App*, const CLI::Error& e) {
    return fmt::format("{}: error: {} (see {} --help)\n", tool, e.what(), tool);
  });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
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
    return app.exit(e);
  }
}

int tool_main(CLI::App& app, int argc, char** argv, const std::function<void()>& run) {
  return tool_main_status(app, argc, argv, [&run] {
    run();
    return 0;
  });
}

std::string input_name(const std::string& path) { return path == "-" ? "<stdin>" : path; }

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
