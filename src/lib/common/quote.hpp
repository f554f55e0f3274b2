// Input quoted in a message: one line, nothing a terminal would act on, a bounded length.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace mcg {

/// The longest stretch of input a message quotes, in bytes; more is cut with "..." and the
/// full size, so that a 4 KiB garbage field still gives a one-line error.
inline constexpr std::size_t k_quote_max_bytes = 64;

/// `text` safe to print: control characters (C0, DEL, C1) and bytes that are not valid UTF-8
/// become \xNN (a backslash stays as is); valid UTF-8 such as "ω" is kept. Longer than
/// `max_bytes`: cut at a character boundary and followed by "... (N bytes)".
/// Every message that quotes input (a CSV cell or name, an INI key or value, an option value,
/// text from the serial line) quotes it through this; mcg::Error applies it, uncut, to the
/// whole message as a last guard.
std::string printable(std::string_view text, std::size_t max_bytes = k_quote_max_bytes);

/// A file or port name as messages, metadata and written INI comments show it: printable(),
/// never cut (a newline in a name would start a line of its own in what a tool writes).
inline std::string printable_name(std::string_view name) { return printable(name, std::string_view::npos); }

/// printable(text) between single quotes: 'text'.
std::string quote(std::string_view text, std::size_t max_bytes = k_quote_max_bytes);
/// One byte of input between single quotes ('\x07' for a control character).
inline std::string quote(char c) { return quote(std::string_view(&c, 1)); }

}  // namespace mcg
