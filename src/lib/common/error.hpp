// The one error path: bad input (data, options, files, devices) throws mcg::Error.
#pragma once

#include "common/quote.hpp"

#include <fmt/format.h>

#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace mcg {

/// Bad input of any kind: malformed CSV, a missing column, an out-of-range option, a port
/// that vanished. The message is one line that names where ("<stdin>:12: column 'rpm': ...").
/// Tools catch it once in tool_main(), print "mcg-TOOL: error: <what>" and exit 1.
/// Broken invariants are MCG_DEMAND (common/demand.hpp), never this type.
class Error : public std::runtime_error {
 public:
  /// The message passes through printable() uncut: whatever a site forgot to quote through
  /// quote(), a hostile byte still cannot split the line or reach the terminal raw.
  explicit Error(std::string_view what) : std::runtime_error(printable(what, what.size())) {}
};

/// Thrown by output writers when the reader of stdout went away (EPIPE). Not an error:
/// tool_main() ends the tool quietly with exit status 0, as Unix filters do.
class BrokenPipe : public std::exception {
 public:
  const char* what() const noexcept override { return "broken pipe"; }
};

/// Throws mcg::Error with a fmt-formatted message.
template <typename... Args>
[[noreturn]] void fail(fmt::format_string<Args...> format, Args&&... args) {
  throw Error(fmt::format(format, std::forward<Args>(args)...));
}

}  // namespace mcg
