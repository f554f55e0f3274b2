// The diagnostics of one run of a tool: the sink its main owns (prefix, warnings, notes, the
// exit status). Library code reports through it and never names a tool or prints itself.
#pragma once

#include <iosfwd>
#include <string>
#include <string_view>

namespace mcg {

/// The exit status of a run that wrote its result but whose numbers are not to be relied on
/// (a fit that did not converge, or converged to untrustworthy numbers).
inline constexpr int k_untrustworthy_status = 3;

/// Writes "<prefix>: warning: ...", "<prefix>: note: ...", "<prefix>: error: ..." and plain
/// "<prefix>: ..." report lines to one stream, and keeps the run's exit status. The main of a
/// tool makes one with its own name as the prefix; a test makes one over a string stream.
class Diagnostics {
 public:
  Diagnostics(std::ostream& out, std::string prefix) : m_out(&out), m_prefix(std::move(prefix)) {}

  void warning(std::string_view message);
  void note(std::string_view message);
  /// An error found after (part of) the result was written: reported, and the run ends with
  /// `status` (an input error, 1, outranks any other status; otherwise the first one stays).
  void error(std::string_view message, int status = 1);
  /// A report line: "<prefix>: <message>".
  void report(std::string_view message);
  /// A progress line that overwrites the previous one on a terminal: "\r<prefix>: <message>".
  void progress(std::string_view message);
  /// Ends a run of progress lines.
  void end_progress();

  /// The exit status so far: 0, or that of the errors reported.
  int status() const { return m_status; }
  const std::string& prefix() const { return m_prefix; }
  /// The stream itself, for multi-line reports (a summary table) that carry no prefix.
  std::ostream& stream() { return *m_out; }

 private:
  std::ostream* m_out;
  std::string m_prefix;
  int m_status = 0;
};

}  // namespace mcg
