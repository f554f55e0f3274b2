// What every tool's main shares: option parsing, --version, the one error path, pipes.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mcg {

/// The exit status of a usage error (an unknown option or subcommand, a missing or malformed
/// argument, an option out of its range), whatever CLI11's own code for it.
inline constexpr int k_usage_status = 2;

/// Parses argv with `app`, then calls `run`. Adds --version, ignores SIGPIPE (a closed
/// stdout ends the tool quietly, exit 0), catches mcg::Error and prints
/// "<app name>: error: <message>" on one line, exit 1. Usage errors print the same way,
/// naming the option or argument at fault (an unknown subcommand with the nearest one's name),
/// and exit k_usage_status. Returns the process exit status.
int tool_main(CLI::App& app, int argc, char** argv, const std::function<void()>& run);

/// Same, for tools whose run() decides its own exit status (e.g. "lost samples": 3).
int tool_main_status(CLI::App& app, int argc, char** argv, const std::function<int()>& run);

/// The name in `names` nearest to `word` (edit distance, a swap of two neighbours counting
/// as one edit), when it is near enough to be a typo of it: at most 2 edits, and fewer than
/// the name has characters. Ties go to the first.
std::optional<std::string> nearest_name(std::string_view word, const std::vector<std::string>& names);

/// The message of a usage error `e` that `app` raised parsing argv: an argument it could not
/// place is named ("unknown option '--bogus'", "unknown subcommand 'strem': did you mean
/// 'stream'?"), even when CLI11 reports another failure first; otherwise CLI11's message.
std::string usage_message(const CLI::App& app, const CLI::ParseError& e);

/// Opens `path` for reading ("-" is stdin). Throws mcg::Error naming the file on failure.
/// The returned stream stays valid until the next call with the same path or program end.
std::istream& open_input(const std::string& path);

/// Display name of an input path for messages and written metadata: "<stdin>" for "-", else
/// printable_name(path).
std::string input_name(const std::string& path);

/// True when stderr is a terminal: progress reports go there only then.
bool stderr_is_terminal();

}  // namespace mcg
