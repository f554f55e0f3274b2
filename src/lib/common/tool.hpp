// What every tool's main shares: option parsing, --version, the one error path, pipes.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace mcg {

/// Parses argv with `app`, then calls `run`. Adds --version, ignores SIGPIPE (a closed
/// stdout ends the tool quietly, exit 0), catches mcg::Error and prints
/// "<app name>: error: <message>" on one line, exit 1. CLI11 usage errors print the same
/// way and exit 2. Returns the process exit status.
int tool_main(CLI::App& app, int argc, char** argv, const std::function<void()>& run);

/// Same, for tools whose run() decides its own exit status (e.g. "lost samples": 3).
int tool_main_status(CLI::App& app, int argc, char** argv, const std::function<int()>& run);

/// Opens `path` for reading ("-" is stdin). Throws mcg::Error naming the file on failure.
/// The returned stream stays valid until the next call with the same path or program end.
std::istream& open_input(const std::string& path);

/// Display name of an input path for error messages: "<stdin>" for "-".
std::string input_name(const std::string& path);

/// True when stderr is a terminal: progress reports go there only then.
bool stderr_is_terminal();

}  // namespace mcg
