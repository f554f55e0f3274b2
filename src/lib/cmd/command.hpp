// The command layer: one module per (sub)command of a tool, each with its own options, defined
// on the command line by define() and run over the shared services by run().
#pragma once

#include <CLI/CLI.hpp>
#include <iosfwd>
#include <string>
#include <vector>

#include "common/diagnostics.hpp"

namespace mcg::cmd {

/// Where a command reads and writes: its input, its result, the tool's diagnostics, and the
/// tool's name (for the provenance its results record).
struct Io {
  std::istream& in;
  std::ostream& out;
  Diagnostics& diag;
  std::string tool;
};

/// One (sub)command: its options (members of the module), their definition and its body.
class Command {
 public:
  virtual ~Command() = default;
  /// The subcommand's name and one line of help (unused for a tool without subcommands).
  virtual std::string name() const = 0;
  virtual std::string help() const = 0;
  /// Adds the command's options to `app` (the subcommand's own, or the tool's).
  virtual void define(CLI::App& app) = 0;
  /// Runs the command on the parsed options; returns the exit status (the worst one wins
  /// with those reported on io.diag). Bad input throws mcg::Error.
  virtual int run(Io& io) = 0;
};

/// The main of a tool without subcommands: defines `command` on `app`, parses argv and runs
/// it (tool_main_status: the one error path), reporting on `diag`.
int main_of(CLI::App& app, int argc, char** argv, Diagnostics& diag, Command& command);

/// The main of a tool of subcommands: one subcommand of `app` per command, in order; exactly
/// one must be given.
int main_of(CLI::App& app, int argc, char** argv, Diagnostics& diag, const std::vector<Command*>& commands);

}  // namespace mcg::cmd
