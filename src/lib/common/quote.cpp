// Escaping and cutting of quoted input.
#include "common/quote.hpp"

#include <fmt/format.h>

namespace mcg {

namespace {

/// Length of the valid, printable UTF-8 sequence starting at text[i] (1 for printable ASCII),
/// or 0 when the byte there must be escaped.
std::size_t printable_run(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b = byte(i);
  if (b >= 0x20 && b < 0x7f) return 1;
  std::size_t n = 0;
  unsigned cp = 0;
  if (b >= 0xc2 && b <= 0xdf) {
    n = 2;
    cp = b & 0x1fu;
  } else if (b >= 0xe0 && b <= 0xef) {
    n = 3;
    cp = b & 0x0fu;
  } else if (b >= 0xf0 && b <= 0xf4) {
    n = 4;
    cp = b & 0x07u;
  } else {
    return 0;
  }
  if (i + n > text.size()) return 0;
  for (std::size_t k = 1; k < n; ++k) {
    if ((byte(i + k) & 0xc0u) != 0x80u) return 0;
    cp = (cp << 6) | (byte(i + k) & 0x3fu);
  }
  const bool overlong = (n == 3 && cp < 0x800) || (n == 4 && cp < 0x10000);
  const bool c1 = cp >= 0x80 && cp < 0xa0;
  const bool surrogate = cp >= 0xd800 && cp < 0xe000;
  if (overlong || c1 || surrogate || cp > 0x10ffff) return 0;
  return n;
}

}  // namespace

std::string printable(std::string_view text, std::size_t max_bytes) {
  std::string out;
  std::size_t i = 0;
  while (i < text.size()) {
    const std::size_t n = printable_run(text, i);
    const std::size_t step = n == 0 ? 1 : n;
    if (i + step > max_bytes) break;
    if (n == 0) {
      out += fmt::format("\\x{:02x}", static_cast<unsigned char>(text[i]));
    } else {
      out.append(text.substr(i, n));
    }
    i += step;
  }
  if (i < text.size()) out += fmt::format("... ({} bytes)", text.size());
  return out;
}

std::string quote(std::string_view text, std::size_t max_bytes) {
  return "'" + printable(text, max_bytes) + "'";
}

}  // namespace mcg
